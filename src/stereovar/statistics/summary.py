"""Cross-scene and SPP-sweep summaries (paper Sec. 3.2 and 3.3, Tables 1 and 2).

The row lists feed :func:`stereovar.io.tables.write_tables`. Rows whose ``rho`` is NaN (an
undefined correlation, see :func:`stereovar.statistics.correlation.pearson_over_mask`) are
skipped, never counted as a scene.
"""

from __future__ import annotations

import math

import numpy as np

from .across import rows_interval
from .regions import REGIONS, as_field
from .registry import PRIMARY_METHOD, secondary_methods


def cross_scene_columns() -> list[str]:
    """Columns of Table 1 (:func:`cross_scene_table`): the primary statistic's summary, then
    the mean of every other registered statistic (``mean_rho_no_warp``, ...)."""
    return [
        "region",
        "mean_rho",
        "boot_low",
        "boot_high",
        "std_rho",
        "min_rho",
        "max_rho",
        "n_scenes",
        *(f"mean_rho_{m}" for m in secondary_methods()),
        "reason",
    ]


CROSS_SCENE_COLUMNS = cross_scene_columns()
"""Columns of Table 1 with the statistics registered at import."""

SPP_SWEEP_COLUMNS = [
    "spp",
    "mean_var_left_glass",
    "mean_var_left_non_glass",
    "rho_all",
    "rho_glass",
    "rho_non_glass",
]
"""Columns of Table 2 as produced by :func:`spp_sweep_table`."""


def _finite(value) -> bool:
    return value is not None and math.isfinite(float(value))


def cross_scene_table(rows: list[dict], *, spp: int | None = None) -> list[dict]:
    """Table 1: statistics of the warped correlation over scenes, per region (paper Sec. 3.2).

    For the :math:`S` scenes with a finite warped :math:`\\rho_s` in a region,

    .. math::

        \\bar\\rho = \\frac1S \\sum_{s=1}^{S} \\rho_s, \\qquad
        \\mathrm{std} = \\sqrt{\\frac{1}{S - 1} \\sum_{s=1}^{S} (\\rho_s - \\bar\\rho)^2},

    the sample standard deviation (``ddof=1``; NaN when :math:`S = 1`), with the range
    :math:`[\\min_s \\rho_s, \\max_s \\rho_s]` and the 95% interval of the mean from the
    scenes' block-bootstrap intervals (``boot_low``, ``boot_high``;
    :func:`~stereovar.statistics.across.combined_interval`). ``mean_rho_no_warp`` averages
    the no-warp rows (Eq. 3 without Eq. 2) over the scenes where that value is finite.

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.statistics.rows.correlation_rows` of every scene, each with ``scene`` and
        ``spp`` added.
    spp : int, keyword-only, optional
        Use only rows of this sample count; required when ``rows`` mix several.

    Returns
    -------
    list of dict
        One row per region (``all``, ``non_glass``, ``glass``) with :data:`CROSS_SCENE_COLUMNS`
        (and ``spp``); ``reason`` is ``""`` or, when no scene has a finite warped rho, says so
        with the scenes' own reasons, and the statistics are NaN.
    """
    rows = [r for r in rows if spp is None or r.get("spp") == spp]
    spps = sorted({r.get("spp") for r in rows}, key=str)
    if len(spps) > 1:
        raise ValueError(f"rows mix several spp values {spps}; pass spp=")
    seen = set()
    for r in rows:
        key = (r.get("scene"), r["region"], r["method"])
        if key in seen:
            raise ValueError(f"duplicate correlation row for scene, region, method {key}")
        seen.add(key)
    nan = float("nan")
    out = []
    for region in REGIONS:
        primary = [r for r in rows if r["region"] == region and r["method"] == PRIMARY_METHOD]
        rho = np.array([float(r["rho"]) for r in primary if _finite(r["rho"])], dtype=np.float64)
        _, low, high = rows_interval(primary)
        row = {
            "region": region,
            "mean_rho": float(rho.mean()) if rho.size else nan,
            "boot_low": low,
            "boot_high": high,
            "std_rho": float(rho.std(ddof=1)) if rho.size > 1 else nan,
            "min_rho": float(rho.min()) if rho.size else nan,
            "max_rho": float(rho.max()) if rho.size else nan,
            "n_scenes": int(rho.size),
        }
        for method in secondary_methods():
            others = [
                float(r["rho"])
                for r in rows
                if r["region"] == region and r["method"] == method and _finite(r["rho"])
            ]
            row[f"mean_rho_{method}"] = float(np.mean(others)) if others else nan
        row["reason"] = ""
        if spps:
            row["spp"] = spps[0]
        if not rho.size:
            reasons = sorted({r.get("reason", "") for r in primary} - {""})
            row["reason"] = f"no scene has a finite rho in region {region}" + (
                f" ({'; '.join(reasons)})" if reasons else ""
            )
        out.append(row)
    return out


def mean_variance_by_region(sigma_left, masks: dict) -> dict:
    """Mean left-view variance within each region (the :math:`\\bar\\sigma_L^2` of Table 2).

    .. math::

        \\bar\\sigma_L^2\\big|_r = \\frac{1}{|\\Omega_r|} \\sum_{(x, y) \\in \\Omega_r}
            \\sigma_L^2(x, y)

    (paper Sec. 3.3), in float64 over the finite values of each mask; NaN for an empty one.

    Parameters
    ----------
    sigma_left : array_like or xarray.DataArray, shape (H, W)
        :math:`\\sigma_L^2` (Eq. 1).
    masks : dict
        Region name to bool mask, e.g. :func:`stereovar.statistics.regions.region_masks` of
        :math:`\\Omega`.

    Returns
    -------
    dict
        Region name to mean variance.
    """
    sigma = as_field(sigma_left).astype(np.float64)
    out = {}
    for region, mask in masks.items():
        values = sigma[as_field(mask).astype(bool) & np.isfinite(sigma)]
        out[region] = float(values.mean()) if values.size else float("nan")
    return out


def sweep_entry(spp: int, rows: list[dict], mean_variance: dict) -> dict:
    """One entry of :func:`spp_sweep_table` from a scene's correlation rows at ``spp``.

    Parameters
    ----------
    spp : int
    rows : list of dict
        :func:`stereovar.statistics.rows.correlation_rows` at this ``spp``; the warp rows are used.
    mean_variance : dict
        :func:`mean_variance_by_region` at this ``spp``.

    Returns
    -------
    dict
        ``spp``, ``mean_var_left_{region}`` and ``rho_{region}`` for each region present.
    """
    entry = {"spp": int(spp)}
    for region, value in mean_variance.items():
        entry[f"mean_var_left_{region}"] = float(value)
    for r in rows:
        if r["method"] == PRIMARY_METHOD:
            entry[f"rho_{r['region']}"] = float(r["rho"])
    return entry


def _log_log_fit(spp: np.ndarray, value: np.ndarray) -> dict:
    x, y = np.log(spp), np.log(value)
    dx, dy = x - x.mean(), y - y.mean()
    slope = float(dx @ dy / (dx @ dx))
    intercept = float(y.mean() - slope * x.mean())
    ss_res = float(((y - intercept - slope * x) ** 2).sum())
    ss_tot = float(dy @ dy)
    r2 = 1.0 if ss_tot == 0 else 1.0 - ss_res / ss_tot
    return {"slope": slope, "intercept": intercept, "r2": r2, "n_points": int(x.size), "reason": ""}


def spp_sweep_table(entries: list[dict]) -> tuple[list[dict], dict]:
    """Table 2 rows and the log-log fit of mean variance against SPP (paper Sec. 3.3).

    For each region with at least two sample counts where the mean variance is finite and
    positive, the least-squares line

    .. math::

        \\ln \\bar\\sigma_L^2\\big|_r = a + b \\ln \\mathrm{SPP}

    is fitted (``intercept`` :math:`a` in natural-log units, ``slope`` :math:`b`, expected
    :math:`\\approx -1` since :math:`\\sigma^2 \\propto 1/\\mathrm{SPP}`), with
    :math:`r^2 = 1 - \\sum (y - a - bx)^2 / \\sum (y - \\bar y)^2`.

    Parameters
    ----------
    entries : list of dict
        One per sample count (see :func:`sweep_entry`): ``spp``, ``mean_var_left_glass``,
        ``mean_var_left_non_glass`` (and optionally ``mean_var_left_all``), ``rho_all``,
        ``rho_glass``, ``rho_non_glass``.

    Returns
    -------
    rows : list of dict
        Copies of ``entries`` sorted by ``spp`` (columns :data:`SPP_SWEEP_COLUMNS`).
    fit : dict
        Region (``all``, ``non_glass``, ``glass``) to ``slope``, ``intercept``, ``r2``,
        ``n_points`` and ``reason`` (``""``, or why the fit is undefined; then NaN).
    """
    rows = sorted((dict(e) for e in entries), key=lambda e: e["spp"])
    spps = [int(r["spp"]) for r in rows]
    if any(s <= 0 for s in spps) or len(set(spps)) != len(spps):
        raise ValueError(f"spp values must be positive and distinct, got {spps}")
    nan = float("nan")
    fit = {}
    for region in REGIONS:
        key = f"mean_var_left_{region}"
        points = [
            (r["spp"], float(r[key]))
            for r in rows
            if key in r and _finite(r[key]) and float(r[key]) > 0
        ]
        if len(points) < 2:
            fit[region] = {
                "slope": nan,
                "intercept": nan,
                "r2": nan,
                "n_points": len(points),
                "reason": f"fewer than 2 SPP values with a positive {key}",
            }
            continue
        spp, value = (np.array(c, dtype=np.float64) for c in zip(*points, strict=True))
        fit[region] = _log_log_fit(spp, value)
    return rows, fit


def intervention_table(rows: list[dict]) -> list[dict]:
    """Table 3 from per-scene intervention rows (paper Sec. 3.4).

    For each (source, cost, metric, region), ``source`` being ``render`` or ``sensor`` (the
    same metrics on simulated sensor frames; rows without one are renders): the mean and
    sample standard deviation (ddof 1) across scenes of the normal and the decorrelated
    values, their mean chance levels, the number of scenes with a finite value, and the
    relative change

    .. math:: \\Delta = \\frac{\\bar v_{\\text{normal}} - \\bar v_{\\text{decorr}}}
        {|\\bar v_{\\text{decorr}}|}.

    NaN values (with a reason) are left out; a row without any finite value is NaN.
    """
    keys = []
    groups: dict = {}
    for r in rows:
        key = (str(r.get("source") or "render"), r["cost"], r["metric"], r["region"])
        if key not in groups:
            keys.append(key)
            groups[key] = {"normal": [], "decorrelated": []}
        groups[key][r["condition"]].append(r)
    out = []
    for source, cost, metric, region in keys:
        row = {"source": source, "cost": cost, "metric": metric, "region": region}
        means = {}
        for condition in ("normal", "decorrelated"):
            items = [
                g for g in groups[(source, cost, metric, region)][condition] if _finite(g["value"])
            ]
            values = np.array([float(g["value"]) for g in items])
            chances = [float(g["chance"]) for g in items if _finite(g.get("chance"))]
            means[condition] = float(values.mean()) if values.size else math.nan
            row[f"{condition}_mean"] = means[condition]
            row[f"{condition}_std"] = float(values.std(ddof=1)) if values.size > 1 else math.nan
            row[f"{condition}_chance"] = float(np.mean(chances)) if chances else math.nan
            row[f"{condition}_n_scenes"] = int(values.size)
        denominator = abs(means["decorrelated"])
        row["relative_change"] = (
            (means["normal"] - means["decorrelated"]) / denominator
            if denominator > 0 and _finite(means["normal"])
            else math.nan
        )
        out.append(row)
    return out
