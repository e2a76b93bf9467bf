"""The cross-renderer table: each scene's statistics from every renderer, side by side
(paper Sec. 5, limitations: cross-renderer confirmation).

Every renderer's correlation rows (:func:`stereovar.statistics.rows.correlation_rows`, one
file per scene) give, per scene, region and method, :math:`\\rho` with its block-bootstrap
interval. The table keeps the methods that tell a shortcut from a camera: Pearson's
:math:`\\rho` after the warp, the robust statistics (Spearman, log-variance, trimmed), the
intensity-controlled (partial) :math:`\\rho`, the no-warp control and the sensor baseline;
and adds, per region and method, the mean over scenes with its interval
(:func:`~stereovar.statistics.across.statistics_table`).
"""

from __future__ import annotations

import math

from .across import statistics_table

METHODS = ("warp", "spearman", "log", "trimmed", "partial", "no_warp", "sensor")
"""Methods (correlation-row ``method`` values) shown side by side."""

MEAN = "mean"
"""The ``scene`` label of the mean over scenes."""


def cross_renderer_columns(renderers) -> list[str]:
    """Columns of :func:`cross_renderer_table` for ``renderers`` (in that order)."""
    cols = ["scene", "region", "method"]
    for r in renderers:
        cols += [f"rho_{r}", f"boot_low_{r}", f"boot_high_{r}"]
    if len(renderers) == 2:
        cols.append(f"diff_{renderers[1]}_minus_{renderers[0]}")
    return [*cols, "n_scenes", "spp"]


def _mean_rows(rows: list[dict], spp: int) -> dict:
    """(region, method) to (mean rho, low, high, n scenes) over the scenes of one renderer
    (:func:`~stereovar.statistics.across.statistics_table`)."""
    return {
        (t["region"], t["method"]): (t["mean_rho"], t["boot_low"], t["boot_high"], t["n_scenes"])
        for t in statistics_table(rows, spp=spp)
    }


def cross_renderer_table(rows_by_renderer: dict, *, spp: int) -> list[dict]:
    """Per scene (and their mean), region and method: every renderer's rho and interval.

    Parameters
    ----------
    rows_by_renderer : dict of str to list of dict
        Each renderer's correlation rows (all scenes), with ``scene``, ``spp``, ``region``,
        ``method``, ``rho``, ``boot_low`` and ``boot_high``.
    spp : int, keyword-only
        The sample count compared.

    Returns
    -------
    list of dict
        :func:`cross_renderer_columns` rows: scenes in order, then ``mean``; NaN where a
        renderer has no row. With two renderers, ``diff_<b>_minus_<a>`` is the difference of
        their rho.
    """
    renderers = list(rows_by_renderer)
    nan = math.nan
    per_scene, scenes, regions = {}, [], []
    for r, rows in rows_by_renderer.items():
        for row in rows:
            if int(row["spp"]) != int(spp) or row["method"] not in METHODS:
                continue
            if row["scene"] not in scenes:
                scenes.append(row["scene"])
            if row["region"] not in regions:
                regions.append(row["region"])
            per_scene[(r, row["scene"], row["region"], row["method"])] = (
                float(row["rho"]),
                float(row["boot_low"]),
                float(row["boot_high"]),
                1,
            )
    means = {r: _mean_rows(rows, int(spp)) for r, rows in rows_by_renderer.items()}
    out = []
    for scene in [*sorted(scenes), MEAN]:
        for region in regions:
            for method in METHODS:
                row = {"scene": scene, "region": region, "method": method}
                n = 0
                for r in renderers:
                    if scene == MEAN:
                        rho, low, high, k = means[r].get((region, method), (nan,) * 3 + (0,))
                    else:
                        rho, low, high, k = per_scene.get((r, scene, region, method), (nan,) * 4)
                    row.update({f"rho_{r}": rho, f"boot_low_{r}": low, f"boot_high_{r}": high})
                    n = max(n, int(k) if k == k else 0)
                if len(renderers) == 2:
                    a, b = renderers
                    row[f"diff_{b}_minus_{a}"] = row[f"rho_{b}"] - row[f"rho_{a}"]
                row["n_scenes"] = n
                row["spp"] = int(spp)
                out.append(row)
    return out
