"""Flags the audit raises on its own numbers, beside the import's warnings.

A null warp (shifted or flipped disparity) that correlates away from 0, no warp correlating as
much as the warp, an attenuation-corrected :math:`\\rho` above 1, and a frame's estimate at
the edge of its bootstrap interval each qualify the verdict (:func:`control_flags`); the page
lists them under :data:`FLAG_LABELS`.
"""

from __future__ import annotations

from .verdict import _f, _find, _ok

NULL_OFF = 0.1
"""A null warp is flagged when its 95% interval excludes 0 and its value is at least this
far from 0."""

EDGE = 0.02
"""A point estimate within this fraction of its interval's width from an end of the interval
(or outside it) is flagged: a few bootstrap tiles decide it."""

FLAG_LABELS = {
    "control": "control off its expected value",
    "corrected_above_1": "corrected rho above 1",
    "edge_of_interval": "estimate at the edge of its interval",
}
"""Kinds of flags the verdict raises on its own numbers (beside the import's warnings)."""


def control_flags(rows: list[dict], correlations: list[dict]) -> list[dict]:
    """Flags on the verdict's own numbers: a shifted or flipped null warp whose interval is
    away from 0 (by at least :data:`NULL_OFF`), no warp correlating as much as the warp, a
    corrected :math:`\\rho` above 1, and a frame's point estimate at the edge of (or outside)
    its bootstrap interval.

    Parameters
    ----------
    rows : list of dict
        :func:`~stereovar.audit.verdict.verdict_rows`.
    correlations : list of dict
        The frames' correlation rows (``scene``, ``region``, ``method``, ``rho``,
        ``boot_low``, ``boot_high``, ``rho_corrected``).

    Returns
    -------
    list of dict
        ``{"kind", "frame", "text"}``, ``kind`` one of :data:`FLAG_LABELS`.

    Examples
    --------
    >>> rows = [{"quantity": "null: disparity shifted", "region": "all", "value": 0.368,
    ...          "low": 0.185, "high": 0.551, "note": ""}]
    >>> control_flags(rows, [])[0]["kind"]
    'control'
    """
    flags = []
    for r in rows:
        if not r["quantity"].startswith("null:") or not _ok(r["value"], r["low"], r["high"]):
            continue
        if r["quantity"].startswith("null: no warp"):
            # smooth fields correlate unwarped when disparities are small: flagged only
            # when the warp adds nothing
            warp = _find(rows, "Pearson rho after", r["region"])
            off = _ok(warp["value"]) and r["value"] >= warp["value"]
        else:
            off = (r["low"] > 0 or r["high"] < 0) and abs(r["value"]) >= NULL_OFF
        if off:
            flags.append({
                "kind": "control",
                "frame": None,
                "text": (
                    f"{r['quantity']} ({r['region']}) is {r['value']:.3f} [{r['low']:.3f}, "
                    f"{r['high']:.3f}], not about 0: the variance fields correlate without the "
                    "right alignment (smooth or intensity-driven structure, or quantisation), "
                    "so part of rho is not the cross-view cue; read rho against it"
                ),
            })
    for r in rows:
        if r["quantity"].startswith("attenuation-corrected") and _ok(r["value"]) and (
            r["value"] > 1
        ):
            flags.append({
                "kind": "corrected_above_1",
                "frame": None,
                "text": (
                    f"the attenuation-corrected rho ({r['region']}) is {r['value']:.3f}, above "
                    "1: the split-half reliabilities are underestimated (few seeds, heavy "
                    "tails); read it as about 1, not as a value"
                ),
            })
    for c in correlations:
        if c.get("method") not in ("warp", "partial"):
            continue
        value, low, high = _f(c.get("rho")), _f(c.get("boot_low")), _f(c.get("boot_high"))
        if not _ok(value, low, high) or high <= low:
            continue
        margin = EDGE * (high - low)
        if value - low < margin or high - value < margin:
            what = "Pearson rho" if c["method"] == "warp" else "intensity-controlled rho"
            flags.append({
                "kind": "edge_of_interval",
                "frame": c.get("scene"),
                "text": (
                    f"frame {c.get('scene')}, {c['region']}: {what} {value:.3f} lies at the "
                    f"edge of its bootstrap interval [{low:.3f}, {high:.3f}]: a few tiles "
                    "decide it; give more frames or a smaller analysis.bootstrap.tile"
                ),
            })
    return flags
