"""The results page's compact mitigation table (:func:`mitigation_rows`,
:data:`MITIGATION_COLUMNS`): per mitigation the Monte Carlo-specific :math:`\\rho` beside its
matched null, the verdict and the image-quality cost; the full table is
``results/tables/mitigations.csv``.
"""

from __future__ import annotations

import math

from .claims_table import VERDICT_CLASSES
from .names import readable
from .numbers import _f, interval_text

__all__ = ["mitigation_rows"]

MITIGATION_COLUMNS = {
    "mitigation": "mitigation",
    "samples": "samples per image",
    "mc_specific": "Monte Carlo-specific ρ of its renders [95%]",
    "null": "matched null",
    "ships": "Monte Carlo-specific ρ of what it ships [95%] (the verdict reads it)",
    "verdict": "verdict",
    "psnr": "PSNR, dB [95%]",
    "budget": "raw render at equal budget, dB",
}
"""The compact mitigation table's columns and headers (:func:`mitigation_rows`)."""


def _iv(row: dict, column: str, digits: int = 3) -> str:
    value, low, high = (_f(row.get(k)) for k in (column, f"{column}_low", f"{column}_high"))
    return interval_text(value, low, high, fmt=f".{digits}f")


def mitigation_rows(rows: list[dict], region: str = "all") -> list[dict]:
    """The compact mitigation table (:data:`MITIGATION_COLUMNS`) over ``region``: per
    mitigation its samples per image, the Monte Carlo-specific :math:`\\rho` with its 95%
    interval beside its matched null, what a seed-mean transform ships, the verdict, and the
    PSNR cost beside a raw render at the same samples per image
    (:func:`stereovar.statistics.mitigations.equal_budget_psnr`). The full table is
    ``results/tables/mitigations.csv``.

    Examples
    --------
    >>> rows = [{"mitigation": "none", "region": "all", "render_spp": 32, "spp": 32,
    ...          "kind": "baseline", "mc_specific": 0.5, "mc_specific_low": 0.4,
    ...          "mc_specific_high": 0.6, "null_partial": 0.001, "mc_cue": "remains",
    ...          "psnr": 19.5, "psnr_low": 16.1, "psnr_high": 22.9}]
    >>> r = mitigation_rows(rows)[0]
    >>> r["mc_specific"], r["null"], r["verdict"], r["psnr"], r["budget"]
    ('0.500 [0.400, 0.600]', '0.001', 'remains', '19.5 [16.1, 22.9]', '')
    """
    from ..statistics.mitigations import equal_budget_psnr

    chosen = [r for r in rows if r.get("region") == region]
    out = []
    for r in chosen:
        budget, how = equal_budget_psnr(chosen, r)
        same = r.get("mitigation") == "none" or r.get("kind") == "spp"
        null = _f(r.get("null_partial"))
        samples = _f(r.get("render_spp"))
        out.append({
            "mitigation": readable(str(r.get("mitigation", ""))),
            "samples": f"{samples:.0f}" if math.isfinite(samples) else "",
            "mc_specific": _iv(r, "mc_specific"),
            "null": f"{null:.3f}" if math.isfinite(null) else "n/a",
            "ships": _iv(r, "shipped_mc_specific")
            if math.isfinite(_f(r.get("shipped_mc_specific"))) else "as measured",
            "verdict": str(r.get("mc_cue", "")),
            "verdict_class": VERDICT_CLASSES.get(str(r.get("mc_cue", "")), ""),
            "psnr": _iv(r, "psnr", 1),
            "budget": f"{budget:.1f} ({how})" if math.isfinite(budget) and not same else "",
        })
    return out
