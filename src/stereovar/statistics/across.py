"""Every statistic and control across scenes, with intervals (Table 1's companions).

:func:`statistics_table` summarises the per-scene correlation rows of every registered
statistic; :func:`curve_table` the per-scene seed-subset curves. The interval of a
cross-scene mean combines the scenes' bootstrap intervals (:func:`combined_interval`), so it
is conditional on the scenes that were run; the spread between scenes is the ``std_rho``
column beside it. :func:`random_effects_interval` adds the variance between scenes: the
interval for the mean over scenes like those run, which the claims table uses.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats
from scipy.special import ndtri

from .regions import REGIONS
from .registry import METHODS

Z = float(ndtri(0.975))

STATISTICS_COLUMNS = [
    "region",
    "method",
    "mean_rho",
    "boot_low",
    "boot_high",
    "std_rho",
    "n_scenes",
    "mean_fisher_width",
    "mean_boot_width",
    "mean_top_share",
    "mean_fireflies",
    "mean_reliability_left",
    "mean_reliability_right",
    "mean_rho_corrected",
    "n_corrected_above_1",
    "reason",
]
"""Columns of ``results/{renderer}/{estimator}/tables/statistics.*``."""

CURVE_TABLE_COLUMNS = [
    "region",
    "method",
    "n_prime",
    "mean_rho",
    "std_rho",
    "n_scenes",
    "mean_rho_corrected",
]
"""Columns of ``results/{renderer}/{estimator}/tables/seed_curve.*``."""


def _finite(values) -> np.ndarray:
    v = np.asarray([float(x) for x in values], dtype=np.float64)
    return v[np.isfinite(v)]


def _mean(values) -> float:
    v = _finite(values)
    return float(v.mean()) if v.size else math.nan


def combined_interval(rhos, lows, highs) -> tuple[float, float, float]:
    """The mean of :math:`S` scenes' :math:`\\rho` and its 95% interval from their
    bootstrap intervals, treating scenes as independent.

    .. math::

        \\bar\\rho = \\frac1S \\sum_s \\rho_s, \\qquad
        \\mathrm{se}_s = \\frac{h_s - \\ell_s}{2 z_{0.975}}, \\qquad
        \\bar\\rho \\pm z_{0.975} \\frac{\\sqrt{\\sum_s \\mathrm{se}_s^2}}{S}

    Only scenes with a finite :math:`\\rho` and interval count; NaN when there are none.
    """
    triples = [
        (float(r), float(lo), float(hi))
        for r, lo, hi in zip(rhos, lows, highs, strict=True)
        if all(math.isfinite(float(v)) for v in (r, lo, hi))
    ]
    if not triples:
        return math.nan, math.nan, math.nan
    r, lo, hi = (np.array(c) for c in zip(*triples, strict=True))
    se = (hi - lo) / (2 * Z)
    half = Z * math.sqrt(float((se * se).sum())) / r.size
    mean = float(r.mean())
    return mean, mean - half, mean + half


def random_effects_interval(values, *, level=0.95) -> tuple[float, float, float]:
    """The mean of :math:`S` scenes' values and its interval for the mean over scenes like
    them: the variance between scenes counted with each scene's own error (a random-effects
    interval, the scenes weighted equally).

    Scene :math:`s`'s value is :math:`x_s = m + u_s + e_s`: :math:`m` the mean over scenes,
    :math:`u_s` the scene's departure from it (variance :math:`\\tau^2`, between scenes) and
    :math:`e_s` its estimation error (variance :math:`v_s`, what its bootstrap interval
    measures). Then :math:`\\operatorname{Var}\\bar x = (\\tau^2 + \\bar v)/S`, :math:`\\bar v`
    the mean of the :math:`v_s`, and the sample variance :math:`s_x^2` of the values has
    expectation :math:`\\tau^2 + \\bar v` whatever the :math:`v_s`
    (:math:`\\mathrm{E}(x_s - \\bar x)^2 = (\\tau^2 + v_s)(1 - 2/S) + (\\tau^2 + \\bar v)/S`
    sums over :math:`s` to :math:`(S - 1)(\\tau^2 + \\bar v)`). With the moment estimate
    :math:`\\hat\\tau^2 = s_x^2 - \\bar v`,

    .. math::

        \\bar x \\pm t_{(1+\\gamma)/2,\\,S-1}
        \\sqrt{\\frac{\\hat\\tau^2}{S} + \\frac{\\bar v}{S}}
        = \\bar x \\pm t_{(1+\\gamma)/2,\\,S-1}\\,\\frac{s_x}{\\sqrt S}

    at level :math:`\\gamma`: the Student-t interval of the scene values, which carry both
    variances, so the bootstraps' :math:`\\bar v` cancels. :math:`\\hat\\tau^2` is not
    truncated at 0: :math:`\\max(s_x^2, \\bar v)` is biased up, and over-covers (99.9% for
    :math:`S = 4` scenes without spread between them, against 95.9% untruncated, in
    simulation). :func:`combined_interval` is the same mean with :math:`\\tau^2 = 0`,
    conditional on the scenes run, and misses the mean over scenes whenever they differ by
    more than their errors.

    Only finite values count; NaN when there are none. With one scene the between-scene
    variance cannot be estimated, and the interval is NaN: that scene's own bootstrap
    interval says nothing about other scenes.

    Parameters
    ----------
    values : sequence of float
        Each scene's value.
    level : float, keyword-only
        The interval's level :math:`\\gamma` (0.90 for two one-sided tests at 5%).

    Examples
    --------
    >>> mean, low, high = random_effects_interval([0.6, 0.8])
    >>> round(mean, 3), round(high - mean, 3)  # t_{0.975,1} * 0.1414 / sqrt(2)
    (0.7, 1.271)
    """
    x = _finite(values)
    if x.size == 0:
        return math.nan, math.nan, math.nan
    mean = float(x.mean())
    if x.size < 2:
        return mean, math.nan, math.nan
    half = float(stats.t.ppf(0.5 + level / 2, x.size - 1)) * float(x.std(ddof=1))
    half /= math.sqrt(x.size)
    return mean, mean - half, mean + half


def rows_interval(rows) -> tuple[float, float, float]:
    """:func:`combined_interval` of correlation rows (``rho``, ``boot_low``, ``boot_high``)."""
    nan = math.nan
    return combined_interval(
        [r["rho"] for r in rows],
        [r.get("boot_low", nan) for r in rows],
        [r.get("boot_high", nan) for r in rows],
    )


def statistics_table(rows: list[dict], *, spp: int | None = None) -> list[dict]:
    """One row per region and statistic: cross-scene mean :math:`\\rho` with its interval,
    the spread over scenes and the diagnostics' means.

    .. math::

        \\bar\\rho = \\frac1S \\sum_s \\rho_s, \\quad
        \\mathrm{std} = \\sqrt{\\tfrac{1}{S-1} \\sum_s (\\rho_s - \\bar\\rho)^2}

    with the interval of :func:`combined_interval`, the mean widths of the Fisher-z and
    bootstrap intervals, the mean top-0.1% share, firefly count, reliabilities and
    attenuation-corrected :math:`\\rho` (and how many scenes' corrected :math:`\\rho` exceed 1).

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.statistics.rows.correlation_rows` of every scene (``scene``, ``spp``).
    spp : int, keyword-only, optional
        Use only rows of this sample count.
    """
    rows = [r for r in rows if spp is None or r.get("spp") == spp]
    methods = list(dict.fromkeys([*METHODS.names(), *(r["method"] for r in rows)]))
    out = []
    for region in REGIONS:
        for method in methods:
            group = [r for r in rows if r["region"] == region and r["method"] == method]
            if not group:
                continue
            ok = [r for r in group if math.isfinite(float(r["rho"]))]
            rho = _finite(r["rho"] for r in ok)
            _, low, high = rows_interval(ok)
            reasons = sorted({str(r.get("reason", "")) for r in group} - {""})
            corrected = _finite(r.get("rho_corrected", math.nan) for r in ok)
            out.append(
                {
                    "region": region,
                    "method": method,
                    "mean_rho": float(rho.mean()) if rho.size else math.nan,
                    "boot_low": low,
                    "boot_high": high,
                    "std_rho": float(rho.std(ddof=1)) if rho.size > 1 else math.nan,
                    "n_scenes": int(rho.size),
                    "mean_fisher_width": _mean(
                        float(r["fisher_high"]) - float(r["fisher_low"]) for r in ok
                    ),
                    "mean_boot_width": _mean(
                        float(r.get("boot_high", math.nan)) - float(r.get("boot_low", math.nan))
                        for r in ok
                    ),
                    "mean_top_share": _mean(r.get("top_share", math.nan) for r in ok),
                    "mean_fireflies": _mean(r.get("n_fireflies", math.nan) for r in ok),
                    "mean_reliability_left": _mean(r.get("reliability_left", math.nan) for r in ok),
                    "mean_reliability_right": _mean(
                        r.get("reliability_right", math.nan) for r in ok
                    ),
                    "mean_rho_corrected": float(corrected.mean()) if corrected.size else math.nan,
                    "n_corrected_above_1": int((np.abs(corrected) > 1).sum()),
                    "reason": "" if rho.size else "; ".join(reasons) or "no finite rho",
                }
            )
    return out


def curve_table(curve_rows: list[dict], rows: list[dict] | None = None) -> list[dict]:
    """:math:`\\rho` against :math:`N'` across scenes: the mean over scenes of each scene's
    subset mean, its spread, and the mean attenuation-corrected :math:`\\rho` of the full
    estimate (the curve's asymptote) from ``rows``."""
    rows = rows or []
    out = []
    keys = list(dict.fromkeys((r["region"], r["method"]) for r in curve_rows))
    for region, method in keys:
        corrected = _mean(
            r.get("rho_corrected", math.nan)
            for r in rows
            if r["region"] == region and r["method"] == method
        )
        sizes = sorted(
            {
                int(r["n_prime"])
                for r in curve_rows
                if (r["region"], r["method"]) == (region, method)
            }
        )
        for size in sizes:
            v = _finite(
                r["mean_rho"]
                for r in curve_rows
                if (r["region"], r["method"], int(r["n_prime"])) == (region, method, size)
            )
            out.append(
                {
                    "region": region,
                    "method": method,
                    "n_prime": size,
                    "mean_rho": float(v.mean()) if v.size else math.nan,
                    "std_rho": float(v.std(ddof=1)) if v.size > 1 else math.nan,
                    "n_scenes": int(v.size),
                    "mean_rho_corrected": corrected,
                }
            )
    return out
