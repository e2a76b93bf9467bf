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
"""

from __future__ import annotations

import math

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
]
"""Columns of ``results/tables/generators.csv``."""

COMPACT_COLUMNS = [
    "profile",
    "SPP",
    "adaptive",
    "denoiser",
    "seed rule",
    "Monte Carlo-specific rho",
    "matched null",
    "verdict",
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
                "coupling at d = 0": _iv(r, "residual_rho_zero"),
                "probe": r["probe"],
                "PSNR": _iv(r, "psnr", " dB", 1),
            }
        )
    return out
