"""The calibration table: false-positive rates, power and interval coverage of every rule.

From every scene's replicate rows (:mod:`stereovar.calibration.replicates`), per transform and
statistic:

``false_positive_rate``
    how often a rule fires on a matched null, against its level of 5%;
``power``
    how often it fires on the planted cue at each strength;
``smallest_detectable``
    the smallest planted strength (a multiple of what the renders show) detected with 80%
    power, interpolated on the grid; its mean Monte Carlo-specific :math:`\\rho` is the
    equivalence margin of the ``removed`` verdict;
``coverage``
    how often a 95% interval contains the value it estimates, against 95 +/- 2%.

Rates carry their 95% Wilson interval and the number of replicates, and meet their target
only when the whole interval does (:mod:`stereovar.calibration.rates`). The rules
(``above_zero``, ``above_null``, ``removed``, ``shared``, ``matching`` and the claims
table's ``claim <id> holds``) are :mod:`stereovar.calibration.rules`'s, each read on the
statistic's difference from its matched null (:mod:`stereovar.calibration.nulls`).

Cue-free designs are the matched nulls (``camera``, ``misaligned``) and the camera pipelines
(:mod:`stereovar.calibration.pipelines`, with the 8-bit ones' encoded nulls); each rule's
false-positive rate is given per design and over all of them (:data:`ANY_NULL`).

``scope`` is ``scene`` (one scene's rows) or ``combined`` (the scenes' rows of one replicate
combined as the tables combine them:
:func:`stereovar.statistics.across.combined_correlation_interval` for the statistic and
:func:`stereovar.statistics.across.combined_interval` for its difference).

The table in words is :mod:`stereovar.calibration.sentences`'s and, one row per transform
and statistic, :mod:`stereovar.calibration.compact`'s.
"""

from __future__ import annotations

import math

import numpy as np

from ..intervention.lift import LIFT_METHOD
from .nulls import _group, combined_rows, matched_nulls, with_differences
from .rates import LEVEL, _f, _meets_coverage, _meets_rate, detectable, rate
from .rules import RULE_OF, _count, _coverage, _pair_with_partial

ANY_NULL = "any cue-free design"
"""The ``kind`` of the false-positive rows that pool every cue-free design of a scope."""

MARGIN_REPLICATES = 8
"""Fewest replicates of the scenes combined whose power curve sets a transform's equivalence
margin; with fewer (the denoisers' few replicates), the scenes' pooled curve sets it."""

CALIBRATION_TABLE_COLUMNS = [
    "check",
    "rule",
    "scope",
    "transform",
    "method",
    "kind",
    "strength_factor",
    "value",
    "low",
    "high",
    "n",
    "target",
    "meets_target",
    "note",
]
"""Columns of ``results/tables/calibration.*``."""

NULL_COLUMNS = [  # margin: the equivalence margin of the row's transform and statistic
    "scene",
    "transform",
    "region",
    "method",
    "null_rho",
    "null_se",
    "n",
    "chance_sd",
    "margin",
    "margin_strength",
]
"""Columns of ``results/tables/calibration_nulls.csv``: each scene's matched null per
transform and statistic, the equivalence margin and the planted strength (a multiple of the
renders' own) that sets it: a result inside the margin certifies that no cue as strong as
that survives."""

SUMMARY_METHODS = ("warp", "partial", "log", "spearman", "relative", "null_shift",
                   "shared_streams", LIFT_METHOD)
"""The statistics the table reports (every calibrated one stays in the replicate rows)."""


def calibration_table(rows: list[dict], *, methods=SUMMARY_METHODS, region="all") -> tuple:
    """The calibration table and the matched nulls.

    Parameters
    ----------
    rows : list of dict
        Every scene's replicate rows (:data:`~stereovar.calibration.replicates.
        CALIBRATION_COLUMNS`).
    methods : sequence of str
        The statistics reported.
    region : str
        The region reported.

    Returns
    -------
    table : list of dict
        :data:`CALIBRATION_TABLE_COLUMNS`.
    nulls : list of dict
        :data:`NULL_COLUMNS`.
    """
    rows = [r for r in rows if r["region"] == region and r["method"] in methods]
    for r in rows:
        for k in ("rho", "boot_low", "boot_high", "strength_factor"):
            r[k] = _f(r[k])
        r["replicate"] = int(r["replicate"])
    null_means = matched_nulls(rows)
    per_scene = with_differences(rows, null_means)
    scopes = {"scene": per_scene, "combined": combined_rows(per_scene)}
    for scoped in scopes.values():
        _pair_with_partial(scoped)
    table: list[dict] = []
    margins: dict = {}

    def add(check, rule, scope, transform, method, kind, factor, triple, n, target, meets, note=""):
        table.append(
            {
                "check": check,
                "rule": rule,
                "scope": scope,
                "transform": transform,
                "method": method,
                "kind": kind,
                "strength_factor": factor,
                "value": triple[0],
                "low": triple[1],
                "high": triple[2],
                "n": n,
                "target": target,
                "meets_target": meets,
                "note": note,
            }
        )

    for scope, scoped in scopes.items():
        groups = _group(scoped, ("transform", "method"))
        for (transform, method), group in groups.items():
            by_design = _group(group, ("kind", "strength_factor"))
            # the rules on the nulls: at most 5% false positives, per cue-free design and
            # over all of them (the level a verdict is held to on data of unknown kind)
            cue_free = [k for (k, f) in by_design if k not in ("planted", "renders")]
            pooled = [r for k in cue_free for r in by_design[(k, 0.0)]]
            rules = (RULE_OF[method],) if method in RULE_OF else ("above_zero", "above_null")
            detects = "matching" if method == LIFT_METHOD else "above_null"
            for kind, chosen in [*((k, by_design[(k, 0.0)]) for k in cue_free),
                                 *([(ANY_NULL, pooled)] if len(cue_free) > 1 else [])]:
                for rule in rules:
                    k, n = _count(rule, chosen)
                    if not n:
                        continue
                    r = rate(k, n)
                    note = ""
                    if rule == "above_zero" and method != "partial":
                        note = "a camera's a*mu + b correlates too: not a Monte Carlo test"
                    add("false_positive_rate", rule, scope, transform, method, kind, 0.0, r, n,
                        f"<= {LEVEL:g}", _meets_rate(r), note)
            # power on the planted cue, by strength
            planted = sorted(f for (k, f) in by_design if k == "planted")
            curve = []
            for factor in planted:
                chosen = by_design[("planted", factor)]
                k, n = _count(detects, chosen)
                if not n:
                    continue
                r = rate(k, n)
                curve.append((factor, r[0]))
                add("power", detects, scope, transform, method, "planted", factor, r, n,
                    "", "")
            smallest = detectable(curve)
            margin = math.nan
            if math.isfinite(smallest) and detects == "above_null":
                # the mean Monte Carlo-specific rho at the detectable strength: interpolated
                margin = _interpolated_diff(by_design, smallest)
            replicates = max((len(v) for k, v in by_design.items() if k[0] == "planted"),
                             default=0)
            margins[(scope, transform, method)] = (margin, replicates, smallest)
            if planted:
                add("smallest_detectable", detects, scope, transform, method, "planted",
                    smallest, (smallest, math.nan, math.nan),
                    sum(len(v) for v in by_design.values()), "", "",
                    f"equivalence margin (mean rho minus null there) {margin:.4f}"
                    if math.isfinite(margin) else "" if math.isfinite(smallest)
                    else "no planted strength reaches 80% power")
            # removed: how often the equivalence rule calls a cue removed
            for kind, factor in [("camera", 0.0), *(("planted", f) for f in planted)]:
                chosen = by_design.get((kind, factor), [])
                k, n = _count("removed", chosen, margin)
                if not n or not math.isfinite(margin):
                    continue
                r = rate(k, n)
                wrong = kind == "planted" and factor >= smallest
                add("removed_rate", "removed", scope, transform, method, kind, factor, r, n,
                    f"<= {LEVEL:g}" if wrong else "", _meets_rate(r) if wrong else "",
                    "calls a detectable cue removed" if wrong else "")
            # coverage of the 95% intervals, of the statistic and of its difference, where
            # every replicate of a scene has one estimand (not the misaligned null, whose
            # random offset changes what it estimates)
            for (kind, factor), chosen in sorted(by_design.items()):
                if kind == "misaligned":
                    continue
                for what, cols in (("rho", ("rho", "boot_low", "boot_high")),
                                   ("difference", ("diff", "diff_low", "diff_high"))):
                    k, n = _coverage(chosen, *cols)
                    if not n:
                        continue
                    r = rate(k, n)
                    add("coverage", what, scope, transform, method, kind, factor, r, n,
                        "0.95 +/- 0.02", _meets_coverage(r))
    def margin_of(transform, method):
        """The combined scope's margin when at least :data:`MARGIN_REPLICATES` replicates
        set it, else the pooled scenes' (:func:`margin_scope`)."""
        scope = margin_scope(table, transform, method)
        margin, _, strength = margins.get((scope, transform, method), (math.nan, 0, math.nan))
        return margin, strength if math.isfinite(margin) else math.nan

    nulls = []
    for (scene, transform, region_, method, kind), null in null_means.items():
        if kind != "camera":  # an encoded null of a pipeline, not of the run's frames
            continue
        nulls.append(
            {
                "scene": scene,
                "transform": transform,
                "region": region_,
                "method": method,
                "null_rho": null["mean"],
                "null_se": null["se"],
                "n": null["n"],
                "chance_sd": null["chance_sd"],
                **dict(zip(("margin", "margin_strength"), margin_of(transform, method),
                           strict=True)),
            }
        )
    return table, nulls


def _interpolated_diff(by_design, strength) -> float:
    points = []
    for (kind, factor), group in by_design.items():
        if kind != "planted":
            continue
        d = np.array([_f(r["diff"]) for r in group])
        d = d[np.isfinite(d)]
        if d.size:
            points.append((factor, float(d.mean())))
    if not points:
        return math.nan
    points.sort()
    xs, ys = zip(*points, strict=True)
    return float(np.interp(strength, xs, ys))


def _pick(table, **match) -> list[dict]:
    return [r for r in table if all(r.get(k) == v for k, v in match.items())]


def margin_scope(table: list[dict], transform: str, method: str) -> str:
    """The scope whose power curve sets a transform's equivalence margin, as
    :func:`calibration_table` chooses it for the verdicts: ``combined`` when at least
    :data:`MARGIN_REPLICATES` replicates of the scenes combined reach each planted strength,
    else ``scene`` (the scenes' replicates pooled), so that every page quotes the margin the
    verdict uses."""
    power = _pick(table, check="power", scope="combined", transform=transform, method=method)
    n = max((int(_f(r["n"])) for r in power), default=0)
    return "combined" if n >= MARGIN_REPLICATES else "scene"
