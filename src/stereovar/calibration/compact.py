"""The compact calibration table (``results/tables/calibration.md``): one row per transform and
statistic, each rate in words (:mod:`stereovar.calibration.sentences`).
"""

from __future__ import annotations

import math

from .rates import _f
from .rules import RULE_OF
from .sentences import false_positive_text, worst_false_positive
from .summary import ANY_NULL, _pick, margin_scope

COMPACT_COLUMNS = [
    "transform",
    "method",
    "false positives above its null, every cue-free design, scenes combined",
    "false positives above its null, per scene",
    "false positives above its null, scenes combined",
    "false positives above 0, per scene",
    "smallest detectable (x the renders)",
    "equivalence margin",
    "coverage of rho (lowest)",
    "coverage of the difference (lowest)",
    "replicates per scene",
]
"""Columns of ``results/tables/calibration.md``: one row per transform and statistic (the
CSV beside it has every check, scope and design). The first rate pools every cue-free
design (the matched nulls and the camera pipelines,
:data:`~stereovar.calibration.summary.ANY_NULL`), the level a verdict is held to; the others
are the worst single design. Each is read by the upper end of its 95% Wilson interval:
``at most 6% (0 of 64; not shown)``, with the replicates that fired and, unless the interval
shows the 5% level, ``not shown`` (it straddles the level) or ``no`` (it lies above); the
rule ``above 0`` is the audit's former Monte Carlo rule; ``shared_streams`` and
``c_sigma_lift`` are read by their own rules (:data:`~stereovar.calibration.rules.RULE_OF`);
coverage is the lowest over the designs, pooled over scenes."""


def _percent(row) -> str:
    """A rate's cell: a rate held to :data:`~stereovar.calibration.rates.LEVEL` by its upper
    bound (:func:`~stereovar.calibration.sentences.false_positive_text`), a coverage by its
    value and interval with its ``meets_target`` word when it is not ``yes``."""
    if not row or not math.isfinite(_f(row["value"])):
        return "n/a"
    if str(row.get("target", "")).startswith("<=") and math.isfinite(_f(row["high"])):
        return false_positive_text(row)
    value, low, high = (100 * _f(row[k]) for k in ("value", "low", "high"))
    text = f"{value:.0f}% [{low:.0f}, {high:.0f}]"
    return text + ("" if row.get("meets_target") in ("yes", "") else f" ({row['meets_target']})")


def _worst(rows, check, rule, pick_max=True, **match):
    chosen = [
        r for r in _pick(rows, check=check, rule=rule, **match) if math.isfinite(_f(r["value"]))
    ]
    if not chosen:
        return None
    return (max if pick_max else min)(chosen, key=lambda r: _f(r["value"]))


def compact_table(table: list[dict]) -> list[dict]:
    """:data:`COMPACT_COLUMNS` rows of the calibration table: per transform and statistic
    the worst false-positive rate of each rule (per scene, and for the verdict rule also with
    the scenes combined), the smallest detectable strength with its margin (scenes
    combined), and the lowest coverage over the designs (per scene): a false-positive rate
    by the upper end of its 95% Wilson interval (the worst over the matched nulls,
    :func:`~stereovar.calibration.sentences.worst_false_positive`), a coverage with its
    interval, each with whether it meets its target
    (:func:`~stereovar.calibration.rates.meets_level`)."""
    out = []
    keys = list(dict.fromkeys((r["transform"], r["method"]) for r in table))
    for transform, method in keys:
        scene = _pick(table, scope="scene", transform=transform, method=method)
        smallest = _pick(table, check="smallest_detectable", transform=transform,
                         method=method, scope=margin_scope(table, transform, method))
        value = _f(smallest[0]["value"]) if smallest else math.nan
        note = smallest[0].get("note", "") if smallest else ""
        n = max(
            (int(_f(r["n"])) for r in scene
             if r["check"] == "false_positive_rate" and r["kind"] != ANY_NULL), default=0
        )
        rule = RULE_OF.get(method, "above_null")
        out.append(
            {
                "transform": transform,
                "method": method,
                "false positives above its null, every cue-free design, scenes combined":
                _percent(worst_false_positive(table, scope="combined", transform=transform,
                                              method=method, rule=rule, pooled=True)),
                "false positives above its null, per scene": _percent(
                    worst_false_positive(table, scope="scene", transform=transform,
                                         method=method, rule=rule)
                ),
                "false positives above its null, scenes combined": _percent(
                    worst_false_positive(table, scope="combined", transform=transform,
                                         method=method, rule=rule)
                ),
                "false positives above 0, per scene": _percent(
                    worst_false_positive(table, scope="scene", transform=transform,
                                         method=method, rule="above_zero")
                )
                if method == "partial"
                else "n/a" if method in RULE_OF
                else "not a Monte Carlo test (a camera correlates too)",
                "smallest detectable (x the renders)": f"{value:.3g}"
                if math.isfinite(value)
                else "none up to the strongest",
                "equivalence margin": note.rsplit(" ", 1)[-1] if math.isfinite(value) and note
                else "n/a",
                "coverage of rho (lowest)": _percent(
                    _worst(scene, "coverage", "rho", pick_max=False)
                ),
                "coverage of the difference (lowest)": _percent(
                    _worst(scene, "coverage", "difference", pick_max=False)
                ),
                "replicates per scene": n,
            }
        )
    return out
