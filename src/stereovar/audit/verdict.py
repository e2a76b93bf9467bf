"""The audit's verdict: does the data carry a Monte Carlo-specific cross-view variance cue?

:func:`verdict_rows` gathers, over an audit's frames, the rows a data team needs (each with
its 95% interval): Pearson's :math:`\\rho` of Eq. 3 and its attenuation-corrected value, the
robust statistics, the intensity-controlled :math:`\\rho`, the camera baselines, the null
warps, and the residual-shuffle intervention's :math:`C_\\sigma` winner-take-all lift over
chance beside the same lift on the matched null (camera-law frames through the data's own
encoding). :func:`verdict` applies :data:`RULES` to them.

A real camera's noise variance is a function of intensity (:math:`a\\mu + b`), so it
correlates across views wherever intensity does; the part of the variance that intensity does
not explain (the ``partial`` statistic) is what only Monte Carlo noise carries. The verdict
rests on its interval, and on whether a variance-matching cost finds the true disparity more
often than on its matched null.

:mod:`stereovar.audit.seeding` checks whether the two views share their random streams,
:mod:`stereovar.audit.flags` flags the verdict's own numbers, and
:mod:`stereovar.audit.decision` turns all three into the page's opening.
"""

from __future__ import annotations

import math

import numpy as np

from ..calibration.rules import MIN_EFFECT
from ..statistics.across import combined_interval, rows_interval
from ..statistics.lift import lift_rows, wta_lift
from ..statistics.matched_null import matched_difference
from ..statistics.reliability import corrected_interval
from ..statistics.values import all_finite as _ok
from ..statistics.values import as_float as _f

STRENGTHS = ((0.5, "strong"), (0.3, "moderate"), (0.1, "weak"), (-math.inf, "negligible"))
"""Words for the intensity-controlled :math:`\\rho` (Cohen's conventions for a correlation)."""

RULES = (
    "The cue is Monte Carlo-specific when the intensity-controlled rho (partial: Pearson of "
    "ln sigma^2 after removing each view's conditional mean of ln sigma^2 given ln mu, its "
    "chromaticity and its position on the sensor) minus the same statistic on its matched "
    "null (camera-law noise drawn from the frames' own seed means, N and disparity, through "
    "the frames' own encoding, stereovar.calibration) has a 95% interval above 0.05, the most "
    "camera pipelines without a Monte Carlo cue leave; its strength is the word for that "
    "difference (>= 0.5 strong, >= 0.3 moderate, >= 0.1 weak, else negligible). The "
    "calibration measures how often this rule fires on matched nulls and on camera pipelines "
    "outside the null's class, and from which planted strength it detects a cue. A "
    "Monte Carlo-specific cue works as a matching cue beyond a camera when, besides, the "
    "C_sigma winner-take-all accuracy's lift over chance minus the same lift on its matched "
    "null has a 95% interval above 0 (the calibration measures this rule too). "
    "Intervals: rho, frames' spatial block-bootstrap intervals combined, each at least as "
    "wide as two independent fields with the frames' spatial structure would give by "
    "chance; C_sigma lift, the same tile bootstrap over its per-pixel hits, combined over "
    "frames."
)

RULE_ITEMS = (
    "**Monte Carlo-specific cue:** the intensity-controlled :math:`\\rho` minus its matched "
    "null has a 95% interval above 0.05, more than camera pipelines leave. The matched null "
    "is camera-law noise drawn from these frames' seed means, :math:`N` and disparity, "
    "through their own encoding.",
    "**Intensity-controlled** :math:`\\rho`: Pearson's :math:`\\rho` of "
    ":math:`\\ln\\sigma^2` after removing what each view's brightness "
    "(:math:`\\ln\\mu`), colour and position on the sensor explain.",
    "**Strength:** the word for that difference: at least 0.5 strong, 0.3 moderate, 0.1 weak, "
    "else negligible.",
    "**A matching cue beyond a camera:** a Monte Carlo-specific cue whose "
    ":math:`C_\\sigma` winner-take-all lift over chance, minus the same lift on its matched "
    "null, has a 95% interval above 0.",
    "**Intervals:** the frames' spatial block-bootstrap intervals combined, for "
    ":math:`\\rho` and for the :math:`C_\\sigma` lift alike.",
    "**Calibration:** how often this rule fires on matched nulls, and from which planted "
    "strength it detects a cue, is measured on these frames.",
)
""":data:`RULES` as the page lists them: one short item each, reStructuredText inline
markup with ``:math:`` roles."""

VERDICT_COLUMNS = ["quantity", "region", "value", "low", "high", "note"]

ROWS = (
    ("warp", "Pearson rho after the warp", "the raw correlation; a camera gives one too"),
    ("corrected", "attenuation-corrected rho", "rho / sqrt(split-half reliabilities)"),
    ("spearman", "Spearman rho", "robust to fireflies"),
    ("log", "log-Pearson rho", "robust to fireflies"),
    ("trimmed", "Pearson rho without the top 0.1%", "robust to fireflies"),
    ("partial", "intensity-controlled rho", "intensity removed; read against its matched null"),
    ("relative", "rho of sigma^2 / mu^2", "not a Monte Carlo test: fails the calibration"),
    ("sensor_sim", "camera baseline: simulated sensor, same N", "what a camera shows"),
    ("sensor", "camera baseline: analytic a*mu + b", "what a camera shows"),
    ("no_warp", "null: no warp", "alignment control"),
    ("null_shift", "null: disparity shifted", "alignment control"),
    ("null_flip", "null: right field flipped", "alignment control"),
)
"""Correlation rows of the verdict: method (``corrected``: the warp row corrected), label,
note."""


def correlation_summary(rows: list[dict], method: str, region: str) -> tuple:
    """Mean over frames of one statistic with its combined bootstrap interval, placed on
    Fisher's :math:`z` (:func:`stereovar.statistics.across.combined_correlation_interval`);
    ``corrected``: the attenuation-corrected Pearson :math:`\\rho` with its corrected intervals
    (:func:`stereovar.statistics.reliability.corrected_interval`, uncut) combined on the
    normal scale (:func:`stereovar.statistics.across.combined_interval`) and then cut to
    :math:`[-1, 1]`: a corrected value is a ratio that can exceed 1, so it has no Fisher
    :math:`z`, but it estimates a correlation, and cutting the interval to where that lies
    keeps its coverage. The mean itself is not cut (a value above 1 is flagged where the
    corrected values are reported)."""
    name = "warp" if method == "corrected" else method
    chosen = [
        {k: _f(v) if k not in ("region", "method", "scene", "reason") else v for k, v in r.items()}
        for r in rows
        if r["region"] == region and r["method"] == name
    ]
    if method != "corrected":
        return rows_interval(chosen)
    intervals = [corrected_interval(r, bounded=False) for r in chosen]
    mean, low, high = combined_interval(
        [r.get("rho_corrected", math.nan) for r in chosen],
        [lo for lo, _ in intervals],
        [hi for _, hi in intervals],
    )
    return mean, min(max(low, -1.0), 1.0), min(max(high, -1.0), 1.0)


def _interval(value, low, high) -> str:
    """``value [low, high]`` to 3 decimals (``n/a``; ``(no interval)``)."""
    if not _ok(value):
        return "n/a"
    if not _ok(low, high):
        return f"{value:.3f} (no interval)"
    return f"{value:.3f} [{low:.3f}, {high:.3f}]"


def _row(quantity: str, region: str, value, low, high, note: str) -> dict:
    """One :data:`VERDICT_COLUMNS` row."""
    return {
        "quantity": quantity, "region": region, "value": value, "low": low, "high": high,
        "note": note,
    }


def _reason(rows, region) -> str:
    reasons = {str(r.get("reason") or "") for r in rows if r["region"] == region} - {""}
    return "; ".join(sorted(reasons))


SPECIFIC = "Monte Carlo-specific rho"
"""The label of the verdict's row: the intensity-controlled rho minus its matched null."""


def verdict_rows(
    correlations: list[dict], intervention: list[dict], nulls: list[dict] | None = None
) -> list[dict]:
    """:data:`VERDICT_COLUMNS` rows: every statistic of :data:`ROWS` per region with a
    finite value (``all`` always), with ``nulls`` (the calibration's matched nulls) the
    Monte Carlo-specific difference after the intensity-controlled row
    (:func:`stereovar.statistics.matched_null.matched_difference`), then the intervention's
    lifts (:func:`stereovar.statistics.lift.wta_lift`)."""
    out = []
    for region in ("all", "non_glass", "glass"):
        for method, label, note in ROWS:
            value, low, high = correlation_summary(correlations, method, region)
            if region != "all" and not _ok(value):
                continue
            why = "" if _ok(value) else _reason(correlations, region)
            out.append(_row(label, region, value, low, high, why or note))
            if method == "partial" and nulls is not None:
                null, *diff = matched_difference(
                    correlations, nulls, transform="none", region=region
                )
                out.append(
                    {
                        **_row(
                            SPECIFIC,
                            region,
                            *diff,
                            f"intensity-controlled rho minus its matched null ({null:.3f})"
                            if _ok(null)
                            else "no matched null for these frames",
                        ),
                        "null": null,
                    }
                )
    for source, label in (("render", "renders"), ("sensor", "simulated camera frames")):
        value, low, high = wta_lift(intervention, source)
        quantity = f"C_sigma WTA accuracy minus chance, {label}"
        out.append(_row(quantity, "all", value, low, high,
                        "share of pixels above chance (0.10 = 10 pp)"))
        if source == "render" and nulls is not None:
            from ..intervention.lift import LIFT_METHOD

            null, *diff = matched_difference(lift_rows(intervention), nulls, transform="none",
                                             region="all", method=LIFT_METHOD)
            out.append({**_row(
                MATCHING, "all", *diff,
                f"renders' lift minus its matched null's ({100 * null:+.1f} pp)" if _ok(null)
                else "no matched null for these frames"), "null": null})
    return out


MATCHING = "C_sigma WTA lift beyond its matched null"
"""The label of the matching-cue rule's row: the renders' :math:`C_\\sigma` lift minus the
same lift on the matched null's frames."""


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
        ``mc_specific`` (True, False or None: not testable), ``matched_null`` (whether the
        rule read the intensity-controlled rho against its matched null; without one the
        rule reads the intensity-controlled rho itself), ``strength``, ``matching_cue``
        (True, False or None) and ``text``, one plain-language paragraph.
    """
    partial = _find(rows, "intensity-controlled")
    specific = _find(rows, SPECIFIC)
    against = ""
    if _ok(specific["value"], specific["low"], specific["high"]):
        partial, against = specific, " beyond its matched null (camera-law noise on these frames)"
    lift = _find(rows, "C_sigma WTA accuracy minus chance, renders")
    beyond = _find(rows, MATCHING)
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
    elif partial["low"] > MIN_EFFECT:
        mc, word = True, strength(partial["value"])
        kind = "Monte Carlo-specific" if against else "intensity-controlled"
        first = (
            f"The data carries a {word} {kind} cross-view variance cue: after "
            f"removing what intensity explains, the two views' variance fields still correlate"
            f"{against} (rho {iv(partial)}). A real camera's noise would leave about 0 here."
            + ("" if against else " No matched null was given, so whether it is Monte "
               "Carlo-specific is not tested.")
        )
    else:
        mc, word = False, "none detected"
        first = (
            "No Monte Carlo-specific cross-view variance cue was detected: once intensity, "
            f"colour and sensor position are controlled the correlation{against} is "
            f"{iv(partial)}, an interval that does not clear {MIN_EFFECT:g}, the most that "
            "camera pipelines without a Monte Carlo cue leave."
        )
    second = (
        f" The raw Pearson rho after the warp is {iv(pearson)}; a simulated camera with the "
        f"same number of frames gives {iv(sim)}, so the raw rho alone does not separate "
        "Monte Carlo noise from sensor noise."
    )
    if _ok(beyond["value"], beyond["low"], beyond.get("null")):
        matching = bool(mc is True and beyond["low"] > 0)
        third = (
            f" A variance-matching cost (C_sigma) picks the true disparity {iv(lift, True)} "
            f"more often than chance, {iv(beyond, True)} beyond its matched null "
            f"({100 * beyond['null']:+.1f} pp): "
            + (
                "a stereo network trained on this data can use the Monte Carlo variance as a "
                "matching cue that real images do not have."
                if matching
                else "no matching cue beyond what the same camera's noise offers"
                + ("." if beyond["low"] <= 0 else
                   ", as the cue is not Monte Carlo-specific.")
            )
        )
    elif _ok(lift["value"]):
        matching = None
        third = (
            f" A variance-matching cost (C_sigma) picks the true disparity {iv(lift, True)} "
            "more often than chance; without a matched null it is not read as a matching cue."
        )
    else:
        matching, third = None, " The intervention's lift is undefined on these frames."
    return {
        "mc_specific": mc,
        "matched_null": bool(against),
        "strength": word,
        "matching_cue": matching,
        "text": first + second + third,
    }


def summary_lines(name: str, found: str, rows: list[dict], result: dict) -> list[str]:
    """The verdict's summary lines (``stereovar audit`` prints them)."""

    def fmt(label):
        r = _find(rows, label)
        return _interval(r["value"], r["low"], r["high"])

    lift = _find(rows, "C_sigma WTA accuracy minus chance, renders")
    beyond = _find(rows, MATCHING)
    specific = _find(rows, SPECIFIC)
    first = (
        f"audit {name} ({found}): Monte Carlo-specific cue: {result['strength']}; "
        f"Monte Carlo-specific rho {fmt(SPECIFIC)} (intensity-controlled rho "
        f"{fmt('intensity-controlled')} minus its matched null {specific['null']:.3f})"
        if _ok(specific["value"], specific.get("null"))
        else f"audit {name} ({found}): intensity-controlled cue: {result['strength']}; "
        f"intensity-controlled rho {fmt('intensity-controlled')} (no matched null)"
    )
    return [
        first,
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
        + " (beyond its matched null "
        + (
            f"{100 * beyond['value']:+.1f} pp [{100 * beyond['low']:+.1f}, "
            f"{100 * beyond['high']:+.1f}])"
            if _ok(beyond["value"], beyond["low"], beyond["high"])
            else "n/a)"
        ),
    ]


HALF_FLOAT_NULL = "float: the renders' half-float storage is not reproduced by the null"
"""How :func:`null_encoding` words a null drawn in float for half-float renders."""


def null_encoding(stores: list[dict], records=()) -> str:
    """One sentence: the encoding the matched null was drawn through, as each frame's
    variance store says its renders were stored (``bit_depth``, ``transfer``,
    ``file_format``: :data:`~stereovar.io.contracts.RENDER_PROVENANCE`, the attrs from which
    :func:`stereovar.jobs.calibration.scene_frames` sets the null's encoding), and whether
    the import found half-float renders (``records``, each frame's import record: ``half``).
    Empty without stores.

    Examples
    --------
    >>> null_encoding([{"scene": "f0", "bit_depth": 8, "transfer": "srgb",
    ...                 "file_format": "PNG"}])
    'The matched null was drawn in 8-bit sRGB, as the PNG files were.'
    >>> null_encoding([{"scene": "f0", "bit_depth": 0, "file_format": "EXR"}],
    ...               [{"frame": "f0", "found": {"half": {"left": 0.2}}}]) == (
    ...     f"The matched null was drawn in {HALF_FLOAT_NULL}.")
    True
    """
    half = {r.get("frame") for r in records if (r.get("found") or {}).get("half")}
    groups: dict = {}
    for attrs in stores:
        frame, depth = str(attrs.get("scene", "")), attrs.get("bit_depth")
        files = f"the {attrs.get('file_format') or 'render'} files were"
        if depth is None:
            words = ("float: the import recorded no encoding (import the frames again to draw "
                     "it through theirs)")
        elif int(depth):
            curve = "sRGB" if attrs.get("transfer") == "srgb" else "linear"
            words = f"{int(depth)}-bit {curve}, as {files}"
        else:
            words = HALF_FLOAT_NULL if frame in half else f"float, as {files}"
        groups.setdefault(words, []).append(frame)
    if len(groups) < 2:
        return "".join(f"The matched null was drawn in {w}." for w in groups)
    return "The matched null was drawn in each frame's own encoding: " + "; ".join(
        f"{w} ({', '.join(frames)})" for w, frames in groups.items()) + "."


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
