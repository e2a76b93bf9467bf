"""The audit's verdict: does the data carry a Monte Carlo-specific cross-view variance cue?

:func:`verdict_rows` gathers, over an audit's frames, the rows a data team needs (each with
its 95% interval): Pearson's :math:`\\rho` of Eq. 3 and its attenuation-corrected value, the
robust statistics, the intensity-controlled :math:`\\rho`, the camera baselines, the null
warps, and the residual-shuffle intervention's :math:`C_\\sigma` winner-take-all lift over
chance beside the same lift on simulated camera frames. :func:`verdict` applies
:data:`RULES` to them.

A real camera's noise variance is a function of intensity (:math:`a\\mu + b`), so it
correlates across views wherever intensity does; the part of the variance that intensity does
not explain (the ``partial`` statistic) is what only Monte Carlo noise carries. The verdict
rests on its interval, and on whether a variance-matching cost finds the true disparity more
often than on camera frames.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..statistics.across import combined_interval, rows_interval
from ..statistics.claims import t_interval
from ..statistics.reliability import corrected_interval

STRENGTHS = ((0.5, "strong"), (0.3, "moderate"), (0.1, "weak"), (-math.inf, "negligible"))
"""Words for the intensity-controlled :math:`\\rho` (Cohen's conventions for a correlation)."""

RULES = (
    "The cue is Monte Carlo-specific when the intensity-controlled rho (partial: Pearson of "
    "ln sigma^2 after removing a cubic in ln mu per view, which a camera's a*mu + b noise "
    "leaves at 0) has a 95% interval above 0; its strength is the word for that rho "
    "(>= 0.5 strong, >= 0.3 moderate, >= 0.1 weak, else negligible). It works as a matching "
    "cue beyond a camera when the C_sigma winner-take-all accuracy's lift over chance has an "
    "interval above 0 and above the same lift on simulated camera frames. Intervals: rho, "
    "frames' spatial block-bootstrap intervals combined; intervention, Student t over frames "
    "(one frame: Wilson interval treating pixels as independent, too narrow)."
)

VERDICT_COLUMNS = ["quantity", "region", "value", "low", "high", "note"]

ROWS = (
    ("warp", "Pearson rho after the warp (Eq. 3)", ""),
    ("corrected", "attenuation-corrected rho", "rho / sqrt(split-half reliabilities)"),
    ("spearman", "Spearman rho", "robust to fireflies"),
    ("log", "log-Pearson rho", "robust to fireflies"),
    ("trimmed", "Pearson rho without the top 0.1%", "robust to fireflies"),
    ("partial", "intensity-controlled rho", "the Monte Carlo-specific part"),
    ("relative", "rho of sigma^2 / mu^2", "intensity control"),
    ("sensor_sim", "camera baseline: simulated sensor, same N", "what a camera shows"),
    ("sensor", "camera baseline: analytic a*mu + b", "what a camera shows"),
    ("no_warp", "null: no warp", "alignment control"),
    ("null_shift", "null: disparity shifted", "alignment control"),
    ("null_flip", "null: right field flipped", "alignment control"),
)
"""Correlation rows of the verdict: method (``corrected``: the warp row corrected), label,
note."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _ok(*values) -> bool:
    return all(math.isfinite(_f(v)) for v in values)


def correlation_summary(rows: list[dict], method: str, region: str) -> tuple:
    """Mean over frames of one statistic with its combined bootstrap interval
    (:func:`stereovar.statistics.across.combined_interval`); ``corrected``: the
    attenuation-corrected Pearson :math:`\\rho` with its corrected intervals combined."""
    name = "warp" if method == "corrected" else method
    chosen = [
        {k: _f(v) if k not in ("region", "method", "scene", "reason") else v for k, v in r.items()}
        for r in rows
        if r["region"] == region and r["method"] == name
    ]
    if method != "corrected":
        return rows_interval(chosen)
    intervals = [corrected_interval(r) for r in chosen]
    return combined_interval(
        [r.get("rho_corrected", math.nan) for r in chosen],
        [lo for lo, _ in intervals],
        [hi for _, hi in intervals],
    )


def _reason(rows, region) -> str:
    reasons = {str(r.get("reason") or "") for r in rows if r["region"] == region} - {""}
    return "; ".join(sorted(reasons))


def wta_lift(intervention: list[dict], source: str, region: str = "all") -> tuple:
    """The :math:`C_\\sigma` winner-take-all accuracy minus chance (normal condition), mean
    over frames with its 95% interval: Student t over frames, or for one frame a Wilson
    interval over its scoreable pixels (pixels taken as independent)."""
    chosen = [
        r
        for r in intervention
        if r["cost"] == "variance_cost"
        and r["metric"] == "wta_accuracy"
        and r["condition"] == "normal"
        and r["region"] == region
        and str(r.get("source") or "render") == source
        and _ok(r["value"], r["chance"])
    ]
    lifts = [_f(r["value"]) - _f(r["chance"]) for r in chosen]
    if len(lifts) != 1:
        return t_interval(lifts)
    n = int(_f(chosen[0]["n_pixels"]))
    if n < 1:
        return lifts[0], math.nan, math.nan
    k = int(round(_f(chosen[0]["value"]) * n))
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    chance = _f(chosen[0]["chance"])
    return lifts[0], ci.low - chance, ci.high - chance


def verdict_rows(correlations: list[dict], intervention: list[dict]) -> list[dict]:
    """:data:`VERDICT_COLUMNS` rows: every statistic of :data:`ROWS` per region with a
    finite value (``all`` always), then the intervention's lifts."""
    out = []
    for region in ("all", "non_glass", "glass"):
        for method, label, note in ROWS:
            value, low, high = correlation_summary(correlations, method, region)
            if region != "all" and not _ok(value):
                continue
            why = "" if _ok(value) else _reason(correlations, region)
            out.append(
                {
                    "quantity": label,
                    "region": region,
                    "value": value,
                    "low": low,
                    "high": high,
                    "note": why or note,
                }
            )
    for source, label in (("render", "renders"), ("sensor", "simulated camera frames")):
        value, low, high = wta_lift(intervention, source)
        out.append(
            {
                "quantity": f"C_sigma WTA accuracy minus chance, {label}",
                "region": "all",
                "value": value,
                "low": low,
                "high": high,
                "note": "intervention (Sec. 3.4)",
            }
        )
    return out


def _find(rows, label_start: str, region: str = "all") -> dict:
    for r in rows:
        if r["quantity"].startswith(label_start) and r["region"] == region:
            return r
    return {"value": math.nan, "low": math.nan, "high": math.nan}


def strength(rho: float) -> str:
    """The word of :data:`STRENGTHS` for a correlation."""
    return next(word for bound, word in STRENGTHS if rho >= bound)


def verdict(rows: list[dict]) -> dict:
    """Apply :data:`RULES` to :func:`verdict_rows`.

    Returns
    -------
    dict
        ``mc_specific`` (True, False or None: not testable), ``strength``,
        ``matching_cue`` (True, False or None) and ``text``, one plain-language paragraph.
    """
    partial = _find(rows, "intensity-controlled")
    lift = _find(rows, "C_sigma WTA accuracy minus chance, renders")
    camera = _find(rows, "C_sigma WTA accuracy minus chance, simulated")
    pearson = _find(rows, "Pearson rho after")
    sim = _find(rows, "camera baseline: simulated")

    def iv(r, pct=False):
        k = 100.0 if pct else 1.0
        unit = " pp" if pct else ""
        if not _ok(r["value"]):
            return "n/a"
        if not _ok(r["low"], r["high"]):
            return f"{k * r['value']:+.1f}{unit} (no interval)" if pct else f"{r['value']:.3f}"
        if pct:
            return f"{k * r['value']:+.1f}{unit} [{k * r['low']:+.1f}, {k * r['high']:+.1f}]"
        return f"{r['value']:.3f} [{r['low']:.3f}, {r['high']:.3f}]"

    if not _ok(partial["value"], partial["low"], partial["high"]):
        mc, word = None, "not testable"
        first = (
            "The intensity-controlled correlation is undefined on these frames "
            f"({partial.get('note') or 'too few valid pixels'}), so whether the variance "
            "structure goes beyond a camera's cannot be told."
        )
    elif partial["low"] > 0:
        mc, word = True, strength(partial["value"])
        first = (
            f"The data carries a {word} Monte Carlo-specific cross-view variance cue: after "
            f"removing what intensity explains, the two views' variance fields still correlate "
            f"(rho {iv(partial)}). A real camera's noise would leave about 0 here."
        )
    else:
        mc, word = False, "none detected"
        first = (
            "No Monte Carlo-specific cross-view variance cue was detected: once intensity is "
            f"controlled the correlation is {iv(partial)}, an interval that reaches 0, as a "
            "real camera's would."
        )
    second = (
        f" The raw Pearson rho after the warp is {iv(pearson)}; a simulated camera with the "
        f"same number of frames gives {iv(sim)}, so the raw rho alone does not separate "
        "Monte Carlo noise from sensor noise."
    )
    if _ok(lift["value"], lift["low"]):
        above_camera = _ok(camera["high"]) and lift["low"] > camera["high"]
        matching = bool(lift["low"] > 0 and above_camera)
        third = (
            f" A variance-matching cost (C_sigma) picks the true disparity {iv(lift, True)} "
            f"more often than chance, against {iv(camera, True)} on camera frames: "
            + (
                "a stereo network trained on this data can use the variance as a matching cue "
                "that real images do not have."
                if matching
                else "not a matching cue beyond what a camera's noise offers."
            )
        )
    else:
        matching, third = None, " The intervention's lift is undefined on these frames."
    return {
        "mc_specific": mc,
        "strength": word,
        "matching_cue": matching,
        "text": first + second + third,
    }


def summary_lines(name: str, found: str, rows: list[dict], result: dict) -> list[str]:
    """The verdict's summary lines (``stereovar audit`` prints them)."""

    def fmt(label):
        r = _find(rows, label)
        if not _ok(r["value"]):
            return "n/a"
        if not _ok(r["low"], r["high"]):
            return f"{r['value']:.3f} (no interval)"
        return f"{r['value']:.3f} [{r['low']:.3f}, {r['high']:.3f}]"

    lift = _find(rows, "C_sigma WTA accuracy minus chance, renders")
    camera = _find(rows, "C_sigma WTA accuracy minus chance, simulated")
    return [
        f"audit {name} ({found}): Monte Carlo-specific cue: {result['strength']}; "
        f"intensity-controlled rho {fmt('intensity-controlled')}",
        f"  Pearson rho {fmt('Pearson rho after')}, corrected {fmt('attenuation-corrected')}, "
        f"Spearman {fmt('Spearman')}",
        f"  camera baseline (simulated sensor) {fmt('camera baseline: simulated')}; null warps: "
        f"shift {fmt('null: disparity')}, flip {fmt('null: right field')}",
        "  C_sigma WTA lift over chance "
        + (
            f"{100 * lift['value']:+.1f} pp [{100 * lift['low']:+.1f}, {100 * lift['high']:+.1f}]"
            if _ok(lift["value"], lift["low"], lift["high"])
            else "n/a"
        )
        + " (camera frames "
        + (
            f"{100 * camera['value']:+.1f} pp)"
            if _ok(camera["value"])
            else "n/a)"
        ),
    ]


def as_table(rows: list[dict]) -> list[dict]:
    """Verdict rows with rounded numbers for the page."""
    out = []
    for r in rows:
        out.append(
            {
                **r,
                **{
                    k: (float(np.round(r[k], 4)) if _ok(r[k]) else math.nan)
                    for k in ("value", "low", "high")
                },
            }
        )
    return out
