"""The calibration in words: what the results and verdict pages say of it.

:func:`headline` reads the verdict rule's false-positive rates by the upper end of their 95%
Wilson interval, with the smallest planted strength detected;
:func:`coverage_sentence` gives the measured coverage of each 95% interval a page shows;
:func:`false_positive_text` says one rate as a table cell does.
"""

from __future__ import annotations

import math

from ..intervention.lift import LIFT_METHOD
from .rates import LEVEL, NOT_SHOWN, _f, _meets_coverage, meets_level, replicates_to_show
from .summary import ANY_NULL, _pick

COVERAGE_SHOWN = (
    ("warp", "rho", "Pearson rho after the warp"),
    ("partial", "rho", "intensity-controlled rho"),
    ("partial", "difference", "Monte Carlo-specific rho"),
    ("spearman", "rho", "Spearman rho"),
)
"""The 95% intervals the results page shows, as (statistic, what, label) of the coverage
checks."""

VERDICT_COVERAGE_SHOWN = (
    *COVERAGE_SHOWN,
    (LIFT_METHOD, "difference", "C_sigma lift beyond its matched null"),
)
"""The 95% intervals an audit's verdict page shows: the results page's and the matching-cue
rule's."""


def worst_false_positive(
    table: list[dict], *, scope: str = "scene", transform: str = "none",
    method: str = "partial", rule: str = "above_null", pooled: bool = False,
) -> dict | None:
    """The false-positive row of ``rule`` over the cue-free designs whose Wilson upper bound
    is highest (what "at most" can claim), or ``None``; with ``pooled`` the row of every
    cue-free design together (:data:`~stereovar.calibration.summary.ANY_NULL`)."""
    rows = _pick(table, check="false_positive_rate", rule=rule, scope=scope,
                 transform=transform, method=method)
    rows = [r for r in rows if (r["kind"] == ANY_NULL) == pooled]
    rows = [r for r in rows if math.isfinite(_f(r["value"])) and math.isfinite(_f(r["high"]))]
    return max(rows, key=lambda r: (_f(r["high"]), _f(r["value"]))) if rows else None


def _at_most(row) -> str:
    """A rate's Wilson upper bound in percent, rounded up: ``at most 6%``."""
    return f"at most {math.ceil(round(100 * _f(row['high']), 6)):.0f}%"


def _fired(row) -> str:
    """A rate as replicates: ``0 of 64``."""
    n = int(_f(row["n"]))
    return f"{round(_f(row['value']) * n)} of {n}"


def false_positive_text(row) -> str:
    """A rate held to :data:`~stereovar.calibration.rates.LEVEL` as what it shows: the upper
    end of its 95% Wilson interval, the replicates that fired and, unless it is ``yes``, its
    :func:`~stereovar.calibration.rates.meets_level` word.

    Examples
    --------
    >>> from stereovar.calibration.rates import rate
    >>> value, low, high = rate(0, 64)
    >>> false_positive_text({"value": value, "low": low, "high": high, "n": 64})
    'at most 6% (0 of 64; not shown)'
    """
    meets = row.get("meets_target") or meets_level(row["low"], row["high"])
    return f"{_at_most(row)} ({_fired(row)}" + ("" if meets == "yes" else f"; {meets}") + ")"


def headline(table: list[dict], *, transform: str = "none", method: str = "partial",
             shown=None) -> str:
    """The calibration in a few plain words, for the results and verdict pages: the upper
    end of the 95% Wilson interval of the verdict rule's false-positive rate over every
    cue-free design together (matched nulls and camera pipelines,
    :data:`~stereovar.calibration.summary.ANY_NULL`) with the scenes combined, the scope the
    verdicts use, and per scene; the worst single design; the smallest planted strength it
    detects with 80% power (scenes combined); and, where an upper bound is above the 5% level,
    that the replicates run cannot show it and how many would
    (:func:`~stereovar.calibration.rates.replicates_to_show`).

    Examples
    --------
    >>> row = {"check": "false_positive_rate", "rule": "above_null", "transform": "none",
    ...        "method": "partial"}
    >>> table = [
    ...     {**row, "kind": "camera", "scope": "scene", "value": 0.0, "low": 0.0,
    ...      "high": 0.0566, "n": 64},
    ...     {**row, "kind": "camera", "scope": "combined", "value": 0.0, "low": 0.0,
    ...      "high": 0.1936, "n": 16},
    ...     {**row, "kind": ANY_NULL, "scope": "combined", "value": 0.0, "low": 0.0,
    ...      "high": 0.0169, "n": 224},
    ...     {**row, "kind": ANY_NULL, "scope": "scene", "value": 0.0, "low": 0.0,
    ...      "high": 0.0085, "n": 448},
    ...     {"check": "smallest_detectable", "rule": "above_null", "scope": "combined",
    ...      "transform": "none", "method": "partial", "kind": "planted", "value": 0.3,
    ...      "note": "equivalence margin (mean rho minus null there) 0.0200"},
    ... ]
    >>> print(headline(table))  # doctest: +NORMALIZE_WHITESPACE
    On data like yours, this instrument calls a Monte Carlo-specific cue where there is none
    in at most 2% of cue-free frames with the scenes combined (95% confidence; 0 of 224
    replicates of the matched nulls and camera pipelines together; per scene at most 1%, 0
    of 448), and detects one from 0.3x the strength the renders show (80% power;
    intensity-controlled rho 0.0200 above its null). Each design alone: at most 20% (worst,
    camera, 0 of 16 with the scenes combined; 73 replicates with no false positive would
    show 5%).
    """
    pooled = {scope: worst_false_positive(table, scope=scope, transform=transform,
                                          method=method, pooled=True)
              for scope in ("combined", "scene")}
    single = {scope: worst_false_positive(table, scope=scope, transform=transform,
                                          method=method)
              for scope in ("combined", "scene")}
    if single["scene"] is None:
        return "No calibration replicates: the instrument's false-positive rate is not known."
    lead = pooled["combined"] or single["combined"] or single["scene"]
    where = "with the scenes combined" if lead["scope"] == "combined" else "per scene"
    what = ("the matched nulls and camera pipelines together" if lead["kind"] == ANY_NULL
            else f"worst design, {lead['kind']}")
    text = (
        "On data like yours, this instrument calls a Monte Carlo-specific cue where there is "
        f"none in {_at_most(lead)} of cue-free frames {where} (95% confidence; "
        f"{_fired(lead)} replicates of {what}"
    )
    second = pooled["scene"] if lead["kind"] == ANY_NULL else None
    if second is not None:
        text += f"; per scene {_at_most(second)}, {_fired(second)}"
    text += "), and "
    smallest = _pick(table, check="smallest_detectable", scope="combined",
                     transform=transform, method=method)
    value = _f(smallest[0]["value"]) if smallest else math.nan
    if not math.isfinite(value):
        text += "detects no planted cue with 80% power up to the strongest planted."
    else:
        margin = smallest[0].get("note", "").rsplit(" ", 1)[-1]
        text += (
            f"detects one from {value:.2g}x the strength the renders show (80% power; "
            f"intensity-controlled rho {margin} above its null)."
        )
    state = meets_level(lead["low"], lead["high"])
    if state == "no":
        low = math.floor(round(100 * _f(lead["low"]), 6))
        text += f" The rate is above the {100 * LEVEL:g}% level (at least {low:.0f}%)."
    elif state == NOT_SHOWN:
        text += (
            f" {int(_f(lead['n']))} replicates cannot show the {100 * LEVEL:g}% level: "
            f"{replicates_to_show()} with no false positive would."
        )
    worst = single["combined"] or single["scene"]
    if lead["kind"] == ANY_NULL and worst is not None:
        scope = "with the scenes combined" if worst["scope"] == "combined" else "per scene"
        text += (
            f" Each design alone: {_at_most(worst)} (worst, {worst['kind']}, {_fired(worst)} "
            f"{scope}"
        )
        if meets_level(worst["low"], worst["high"]) == NOT_SHOWN:
            text += f"; {replicates_to_show()} replicates with no false positive would show 5%"
        text += ")."
    coverage = coverage_sentence(table, transform=transform, shown=shown)
    return text + (f" {coverage}" if coverage else "")


def coverage_sentence(table: list[dict], *, transform: str = "none", shown=None) -> str:
    """The measured coverage of each 95% interval a page shows (``shown``:
    :data:`COVERAGE_SHOWN`, or :data:`VERDICT_COVERAGE_SHOWN` for a verdict page),
    per scene over the camera null and the planted cue at each strength (designs with one
    estimand and every replicate; the pipeline nulls' few replicates set their false-positive
    rates, not a coverage), as the range of the point estimates; an interval whose range
    leaves 93-97% is so labelled rather than taken at its word.

    Examples
    --------
    Coverage is labelled by its 95% Wilson interval: here the second misses 93-97%.

    >>> row = {"check": "coverage", "scope": "scene", "transform": "none",
    ...        "method": "warp", "rule": "rho"}
    >>> table = [{**row, "kind": "camera", "value": 0.95, "low": 0.87, "high": 0.98},
    ...          {**row, "kind": "planted", "value": 0.66, "low": 0.53, "high": 0.76}]
    >>> print(coverage_sentence(table))  # doctest: +NORMALIZE_WHITESPACE
    Measured coverage of the 95% intervals shown (target 93-97%): Pearson rho after the
    warp 66-95% (too narrow at some designs).
    """
    parts = []
    for method, what, label in shown or COVERAGE_SHOWN:
        rows = [r for r in _pick(table, check="coverage", scope="scene", transform=transform,
                                 method=method, rule=what)
                if r["kind"] in ("camera", "planted") and math.isfinite(_f(r["value"]))]
        if not rows:
            continue
        values = [_f(r["value"]) for r in rows]
        low, high = 100 * min(values), 100 * max(values)
        text = f"{label} {low:.0f}-{high:.0f}%" if round(low) != round(high) else (
            f"{label} {low:.0f}%")
        states = {_meets_coverage((_f(r["value"]), _f(r["low"]), _f(r["high"]))) for r in rows}
        notes = []
        if "short" in states:
            notes.append("too narrow at some designs")
        if "over" in states:
            notes.append("wider than 95% at some designs")
        parts.append(text + (f" ({'; '.join(notes)})" if notes else ""))
    if not parts:
        return ""
    return ("Measured coverage of the 95% intervals shown (target 93-97%): "
            + ", ".join(parts) + ".")
