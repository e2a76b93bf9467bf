"""The generator table: each generator profile's cue, its coupling and its image quality.

One row per generator profile (:mod:`stereovar.generators`) and region, from the profile's
row of the mitigation table (:func:`stereovar.statistics.mitigations.mitigation_table`),
measured against the profile's own matched nulls:

- ``mc_specific``: the intensity-controlled :math:`\\rho` (paper Sec. 2.4) minus the same
  statistic on the matched null through the same path, combined over scenes with its 95%
  interval; ``mc_cue`` its verdict against the calibration's equivalence margin;
- ``residual_rho_zero``: the correlation of the two views' standardised residuals
  :math:`(I^{(n)} - \\bar I)/\\hat\\sigma` pixel by pixel at zero disparity, the coupling a
  shared seed makes (about 0 for independent seeds);
- ``psnr``: one render against the converged reference (the paper row's renders, split in
  half), the mean over scenes with a Student t interval.

What the generator ships (``output``, :data:`stereovar.generators.OUTPUTS`: its renders
through Blender's view transform and an 8-bit PNG, read back as an audit reads it) has the
same Monte Carlo-specific :math:`\\rho` in ``shipped_mc_specific``, against a matched null
drawn through the same chain (camera-law noise, the generator's denoiser where it runs, then
the same PNG), with its own margin and verdict (``shipped_mc_cue``). Where the PNG's codes
fix the variance at :data:`~stereovar.controls.quantisation.FIXED_SHARE` of the pixels or
more (``quantised_share``), the intensity-controlled :math:`\\rho` is undefined and the
verdict reads :data:`NOT_TESTABLE`: the Monte Carlo part of the variance cannot be told from
the rounding of the mean.
"""

from __future__ import annotations

import math

import numpy as np

from .mitigations import _f, _iv

GENERATOR_COLUMNS = [
    "profile",
    "region",
    "generator_spp",
    "spp",
    "spp_scale",
    "adaptive",
    "denoiser",
    "seed_rule",
    "n_scenes",
    "n_seeds",
    "partial",
    "partial_low",
    "partial_high",
    "null_partial",
    "mc_specific",
    "mc_specific_low",
    "mc_specific_high",
    "margin",
    "mc_cue",
    "residual_rho_zero",
    "residual_rho_zero_low",
    "residual_rho_zero_high",
    "probe",
    "psnr",
    "psnr_low",
    "psnr_high",
    "matched_null",
    "output",
    "shipped_partial",
    "shipped_null_partial",
    "shipped_mc_specific",
    "shipped_mc_specific_low",
    "shipped_mc_specific_high",
    "shipped_margin",
    "shipped_margin_strength",
    "shipped_mc_cue",
    "quantised_share",
]
"""Columns of ``results/tables/generators.csv``."""

NOT_TESTABLE = "not testable"
"""The verdict on a shipped output whose integer codes fix the variance at most pixels."""

OUTPUT_TEXT = {
    "png8_filmic": "8-bit PNG, Filmic",
    "png16_filmic": "16-bit PNG, Filmic",
    "png8_agx": "8-bit PNG, AgX",
}
"""How the tables name each output (:mod:`stereovar.transforms.output`)."""

COMPACT_COLUMNS = [
    "profile",
    "SPP",
    "adaptive",
    "denoiser",
    "seed rule",
    "Monte Carlo-specific rho",
    "matched null",
    "verdict",
    "as shipped",
    "Monte Carlo-specific rho as shipped",
    "verdict as shipped",
    "coupling at d = 0",
    "probe",
    "PSNR",
]
"""Columns of ``results/tables/generators.md`` (and ``.tex``, ``.html``)."""

PROBE_NOT_RUN = "not run"
"""The probe column of a profile the probe was not run on."""


def generator_rows(profile, rows: list[dict], *, generator_spp: int, matched: str) -> list[dict]:
    """A profile's rows of :data:`GENERATOR_COLUMNS` from its mitigation-table rows.

    Parameters
    ----------
    profile : stereovar.generators.GeneratorProfile
        The profile as rendered (at the budget).
    rows : list of dict
        Its :data:`~stereovar.statistics.mitigations.MITIGATION_COLUMNS` rows, one per region.
    generator_spp : int
        The samples per pixel the generator itself renders with.
    matched : str
        The calibration transform of its matched null (``none``, or ``denoise`` for a
        profile whose Cycles denoiser runs).
    """
    out = []
    for r in rows:
        row = {
            "profile": profile.name,
            "region": r["region"],
            "generator_spp": int(generator_spp),
            "spp": int(profile.spp),
            "spp_scale": float(profile.scale),
            "adaptive": profile.adaptive,
            "denoiser": profile.denoiser,
            "seed_rule": profile.seed_rule,
            "probe": PROBE_NOT_RUN,
            "matched_null": (
                "camera-law noise at the raw renders' level through OIDN"
                if matched == "denoise"
                else "camera-law noise at the profile's own level"
            ),
        }
        for column in GENERATOR_COLUMNS:
            if column not in row:
                row[column] = r.get(column, math.nan)
        out.append(row)
    return out


def shipped_columns(replicates: list[dict], nulls: list[dict], chain: str | None) -> dict:
    """A profile's shipped columns and ``quantised_share`` (all pixels) from its
    calibration rows: the ``renders`` rows through ``chain``
    (:func:`stereovar.calibration.renders.renders_output_rows`) against the nulls through
    the same chain (:func:`~stereovar.statistics.matched_null.matched_difference`).

    Examples
    --------
    A shipped output that keeps no testable variance:

    >>> rows = [{"scene": "s", "kind": "renders", "transform": "png8_agx", "region": "all",
    ...          "method": m, "rho": r, "boot_low": float("nan"), "boot_high": float("nan")}
    ...         for m, r in (("partial", float("nan")), ("quantised_share", 0.95))]
    >>> out = shipped_columns(rows, [], "png8_agx")
    >>> out["output"], out["shipped_mc_cue"], out["quantised_share"]
    ('8-bit PNG, AgX', 'not testable', 0.95)
    """
    from ..calibration.renders import QUANTISED_SHARE
    from ..controls.quantisation import FIXED_SHARE
    from ..transforms import CHAIN
    from .matched_null import matched_difference
    from .mitigations import equivalence_margin, mc_cue_state

    nan = math.nan
    out = {c: nan for c in GENERATOR_COLUMNS if c.startswith("shipped_")}
    out.update(output="float (EXR)", shipped_mc_cue="n/a", quantised_share=nan)
    if not chain:
        return out
    ship = chain.split(CHAIN)[-1]
    mine = [r for r in replicates if r["kind"] == "renders" and r["transform"] == chain
            and r["region"] == "all"]
    partial = [_f(r["rho"]) for r in mine if r["method"] == "partial"]
    shares = [_f(r["rho"]) for r in mine if r["method"] == QUANTISED_SHARE]
    null, *diff = matched_difference(mine, nulls, transform=chain, region="all")
    margin = equivalence_margin(nulls, chain)
    finite = [x for x in partial if math.isfinite(x)]
    out.update(
        output=OUTPUT_TEXT.get(ship, ship),
        shipped_partial=float(np.mean(finite)) if finite else nan,
        shipped_null_partial=null,
        shipped_mc_specific=diff[0],
        shipped_mc_specific_low=diff[1],
        shipped_mc_specific_high=diff[2],
        shipped_margin=margin,
        shipped_margin_strength=equivalence_margin(nulls, chain, column="margin_strength"),
        shipped_mc_cue=mc_cue_state(diff[1], diff[2], margin),
        quantised_share=float(np.mean(shares)) if shares else nan,
    )
    if partial and not finite and shares and max(shares) >= FIXED_SHARE:
        out["shipped_mc_cue"] = NOT_TESTABLE
    return out


def _spp_text(row: dict) -> str:
    spp, own = int(_f(row["spp"])), int(_f(row["generator_spp"]))
    if spp == own:
        return f"{spp}"
    return f"{spp} of {own} (x1/{own / spp:g})"


def compact_table(rows: list[dict], region: str = "all") -> list[dict]:
    """The generator table in :data:`COMPACT_COLUMNS` over ``region``: every number beside
    its 95% interval, the Monte Carlo-specific part beside its matched null.

    Examples
    --------
    >>> row = {"profile": "kubric", "region": "all", "spp": 64, "generator_spp": 128,
    ...        "adaptive": "off", "denoiser": "render", "seed_rule": "unset",
    ...        "mc_specific": 0.1, "mc_specific_low": 0.05, "mc_specific_high": 0.15,
    ...        "null_partial": 0.8, "mc_cue": "remains", "residual_rho_zero": 0.6,
    ...        "residual_rho_zero_low": 0.5, "residual_rho_zero_high": 0.7,
    ...        "probe": "not run", "psnr": 30.0, "psnr_low": 29.0, "psnr_high": 31.0}
    >>> out = compact_table([row])[0]
    >>> out["SPP"], out["Monte Carlo-specific rho"]
    ('64 of 128 (x1/2)', '0.100 [0.050, 0.150]')
    """
    out = []
    for r in rows:
        if r["region"] != region:
            continue
        null = _f(r.get("null_partial"))
        out.append(
            {
                "profile": r["profile"],
                "SPP": _spp_text(r),
                "adaptive": r["adaptive"],
                "denoiser": r["denoiser"],
                "seed rule": r["seed_rule"],
                "Monte Carlo-specific rho": _iv(r, "mc_specific"),
                "matched null": f"{null:.3f}" if math.isfinite(null) else "n/a",
                "verdict": r["mc_cue"],
                "as shipped": r.get("output", "float (EXR)"),
                "Monte Carlo-specific rho as shipped": _shipped_text(r),
                "verdict as shipped": r.get("shipped_mc_cue", "n/a"),
                "coupling at d = 0": _iv(r, "residual_rho_zero"),
                "probe": r["probe"],
                "PSNR": _iv(r, "psnr", " dB", 1),
            }
        )
    return out


def _shipped_text(row: dict) -> str:
    """The shipped difference beside its null, or why there is none."""
    if row.get("shipped_mc_cue") == NOT_TESTABLE:
        share = _f(row.get("quantised_share"))
        return f"undefined: the codes fix the variance at {100 * share:.0f}% of pixels"
    if not math.isfinite(_f(row.get("shipped_mc_specific"))):
        return "n/a"
    return f"{_iv(row, 'shipped_mc_specific')} (null {_f(row['shipped_null_partial']):.3f})"
