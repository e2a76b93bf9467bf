"""Every statistic and control across scenes, with intervals (Table 1's companions).

:func:`statistics_table` summarises the per-scene correlation rows of every registered
statistic; :func:`curve_table` the per-scene seed-subset curves. The interval of a
cross-scene mean combines the scenes' bootstrap intervals (:func:`combined_interval`), so it
is conditional on the scenes that were run; the spread between scenes is the ``std_rho``
column beside it. :func:`random_effects_interval` adds the variance between scenes: the
interval for the mean over scenes like those run, which the claims table uses. Intervals of
correlations are placed on Fisher's :math:`z` so that they stay inside :math:`[-1, 1]`
(:func:`combined_correlation_interval`, :func:`random_effects_correlation_interval`); the
normal ones remain for other quantities, e.g. differences of two correlations.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtri, stdtrit

from .regions import REGIONS
from .registry import METHODS

Z = float(ndtri(0.975))

STATISTICS_COLUMNS = [
    "region",
    "method",
    "mean_rho",
    "boot_low",
    "boot_high",
    "scenes_low",
    "scenes_high",
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
    "chance_se",
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

    Only scenes with a finite :math:`\\rho` and interval count; NaN when there are none. This
    normal interval suits differences of correlations (in :math:`[-2, 2]`); for correlations,
    whose interval it can take past :math:`\\pm 1`, use :func:`combined_correlation_interval`.
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
    interval says nothing about other scenes. For correlations, whose interval this can take
    past :math:`\\pm 1`, use :func:`random_effects_correlation_interval`.

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
    half = float(stdtrit(x.size - 1, 0.5 + level / 2)) * float(x.std(ddof=1))
    half /= math.sqrt(x.size)
    return mean, mean - half, mean + half


_EDGE = 1e-12
"""A correlation of exactly :math:`\\pm 1` is taken as :math:`\\pm(1 - 10^{-12})`, so that
its Fisher :math:`z` is finite (:math:`\\pm 14.2`)."""


def _fisher_z(values) -> np.ndarray:
    """:math:`\\operatorname{atanh}` of correlations; a value beyond :math:`\\pm 1` by more
    than rounding is not a correlation and is refused."""
    v = np.asarray(values, dtype=np.float64)
    if np.any(np.abs(v) > 1 + 1e-9):
        raise ValueError(
            f"a correlation interval needs values in [-1, 1], got {v[np.abs(v) > 1 + 1e-9]}; "
            "use the normal-scale interval for other quantities"
        )
    return np.arctanh(np.clip(v, -1 + _EDGE, 1 - _EDGE))


def combined_correlation_interval(rhos, lows, highs) -> tuple[float, float, float]:
    """The mean of :math:`S` scenes' correlations and its 95% interval from their bootstrap
    intervals, placed on Fisher's :math:`z` so that it stays inside :math:`[-1, 1]`.

    The point estimate and its error are :func:`combined_interval`'s: the mean
    :math:`\\bar\\rho` of the scenes' :math:`\\rho_s` and the length :math:`w` of its normal
    interval. The interval keeps that length on the scale of :math:`\\rho` but is symmetric
    on :math:`z = \\operatorname{atanh}\\rho` about :math:`\\operatorname{atanh}\\bar\\rho` (the
    scale on which a correlation's estimate is near normal), which places it inside
    :math:`(-1, 1)`:

    .. math::

        \\mathrm{se}_s = \\frac{h_s - \\ell_s}{2 z_{0.975}}, \\qquad
        w = 2 z_{0.975} \\frac{\\sqrt{\\sum_s \\mathrm{se}_s^2}}{S}, \\qquad
        \\bigl[\\tanh(\\operatorname{atanh}\\bar\\rho - a),\\
            \\tanh(\\operatorname{atanh}\\bar\\rho + a)\\bigr]

    .. math::

        \\tanh(\\operatorname{atanh}\\bar\\rho + a) - \\tanh(\\operatorname{atanh}\\bar\\rho - a)
            = w
        \\iff
        a = \\frac12\\Bigl[\\operatorname{atanh}\\frac w2 + \\operatorname{asinh}
            \\frac{w\\,(1 + \\bar\\rho^2)}{(1 - \\bar\\rho^2)\\sqrt{4 - w^2}}\\Bigr]

    (:math:`\\tanh(x + a) - \\tanh(x - a) = 2\\sinh 2a / (\\cosh 2x + \\cosh 2a)`), and
    :math:`[-1, 1]` when :math:`w \\ge 2`. For small :math:`w`,
    :math:`a \\approx (w/2) / (1 - \\bar\\rho^2)`: the delta method's half-width on
    :math:`z`, so far from :math:`\\pm 1` this is :func:`combined_interval`'s interval to first
    order; near :math:`\\pm 1` it slides away from the bound. It contains :math:`\\bar\\rho`,
    and its estimand is, like :func:`combined_interval`'s, the mean :math:`\\rho` of the scenes
    run. Two shortcuts fail near :math:`\\pm 1`: the delta method's half-width on :math:`z`
    grows without bound as :math:`\\bar\\rho \\to \\pm 1` (scenes at 0.99 in
    :math:`[0.9, 1]` and 0.999 in :math:`[0.99, 1]` would get a lower bound of 0.58; here
    0.95); and each scene's interval mapped to :math:`z` has an unbounded :math:`z` at a bound
    near 1, so its error read there collapses (:math:`[0.99, 1 - 10^{-8}]` would count as
    :math:`\\mathrm{se}_\\rho = 3.5 \\times 10^{-5}` against its width's
    :math:`2.6 \\times 10^{-3}`). In simulation (4 scenes of 200 bivariate-normal pixels at
    :math:`\\rho = 0.9`, each with its Fisher interval) it covers :math:`\\rho` in 95% of runs
    (97% at :math:`\\rho = 0.99` with 30 pixels, as the normal interval: the widths of
    intervals symmetric on :math:`z` overstate their error there).

    Only scenes with a finite :math:`\\rho` and interval count; NaN when there are none. For
    quantities that are not correlations (e.g. differences of two, in :math:`[-2, 2]`) use
    :func:`combined_interval`.

    Parameters
    ----------
    rhos, lows, highs : sequence of float
        Each scene's correlation and the bounds of its 95% interval.

    Returns
    -------
    mean, low, high : float

    Raises
    ------
    ValueError
        When a scene's :math:`\\rho` lies outside :math:`[-1, 1]` (beyond rounding): it is not a
        correlation.

    Examples
    --------
    Two scenes near 1, where the normal-scale interval passes 1:

    >>> rhos, lows, highs = [0.95, 0.98], [0.85, 0.95], [1.0, 1.0]
    >>> [round(v, 3) for v in combined_interval(rhos, lows, highs)]
    [0.965, 0.925, 1.005]
    >>> mean, low, high = combined_correlation_interval(rhos, lows, highs)
    >>> round(mean, 3), round(low, 3), round(high, 3)
    (0.965, 0.908, 0.987)
    >>> round(high - low, 4)  # the normal interval's length
    0.0791
    """
    mean, low, high = combined_interval(rhos, lows, highs)
    if not math.isfinite(mean):
        return mean, low, high
    _fisher_z(np.array([float(r) for r in rhos if math.isfinite(float(r))]))  # correlations only
    width = high - low  # the normal interval's length: the same standard error
    if width >= 2:
        return mean, -1.0, 1.0
    if width == 0:  # no error: exactly the mean, not tanh(atanh(mean))
        return mean, mean, mean
    centre = float(_fisher_z(mean))
    a = 0.5 * (
        math.atanh(width / 2)
        + math.asinh(width * math.cosh(2 * centre) / math.sqrt(4 - width * width))
    )
    # the mean inside even where tanh(atanh(mean)) misses it in the last bit
    return mean, min(math.tanh(centre - a), mean), max(math.tanh(centre + a), mean)


def random_effects_correlation_interval(values, *, level=0.95) -> tuple[float, float, float]:
    """The mean of :math:`S` scenes' correlations and its interval for the mean over scenes
    like them (:func:`random_effects_interval`), built on Fisher's :math:`z` so that it stays
    inside :math:`[-1, 1]`.

    The point estimate is the mean :math:`\\bar\\rho` of the scenes' :math:`\\rho_s`, as for
    :func:`random_effects_interval`; the interval is the Student-t interval of the scenes'
    :math:`z_s = \\operatorname{atanh}\\rho_s`, centred on :math:`\\operatorname{atanh}\\bar\\rho`
    and mapped back:

    .. math::

        \\tanh\\Bigl(\\operatorname{atanh}\\bar\\rho \\pm t_{(1+\\gamma)/2,\\,S-1}
            \\frac{s_z}{\\sqrt S}\\Bigr), \\qquad
        s_z^2 = \\frac{1}{S-1}\\sum_s (z_s - \\bar z)^2

    The spread of the :math:`z_s` carries the variance between scenes and each scene's own
    error, as :math:`s_x` does in :func:`random_effects_interval`, on the scale where a
    correlation's estimate is near normal. The centre is :math:`\\operatorname{atanh}\\bar\\rho`
    rather than :math:`\\bar z`: :math:`\\tanh\\bar z` estimates another quantity than the mean
    :math:`\\rho` over scenes (it is pulled towards the scenes nearest :math:`\\pm 1`), and an
    interval about it misses that mean more often the more scenes there are (in simulation,
    scene correlations uniform on [0.1, 0.99]: 80% coverage at :math:`S = 30`, against 99%
    centred on :math:`\\bar\\rho`; at :math:`S = 4`, 94.6%, against 92.8% for the
    normal-scale interval, whose upper bound passed 1 in 39% of runs; scenes crowded just
    below 1 with a long lower tail are covered less as they grow in number: 82% at
    :math:`S = 30`). Values of exactly :math:`\\pm 1` are moved inside by :math:`10^{-12}`.

    Only finite values count; NaN when there are none; the interval is NaN with one scene.

    Parameters
    ----------
    values : sequence of float
        Each scene's correlation, in :math:`[-1, 1]`.
    level : float, keyword-only
        The interval's level :math:`\\gamma` (0.90 for two one-sided tests at 5%).

    Raises
    ------
    ValueError
        When a finite value lies outside :math:`[-1, 1]` (beyond rounding).

    Examples
    --------
    Scenes that disagree: the normal-scale interval passes 1, this one does not.

    >>> values = [0.95, 0.85, 0.20, 0.14]
    >>> round(random_effects_interval(values)[2], 3)
    1.21
    >>> mean, low, high = random_effects_correlation_interval(values)
    >>> round(mean, 3), round(low, 3), round(high, 3)
    (0.535, -0.616, 0.957)
    """
    x = _finite(values)
    if x.size == 0:
        return math.nan, math.nan, math.nan
    z = _fisher_z(x)
    mean = float(x.mean())
    if x.size < 2:
        return mean, math.nan, math.nan
    half = float(stdtrit(x.size - 1, 0.5 + level / 2)) * float(z.std(ddof=1))
    half /= math.sqrt(x.size)
    if half == 0:  # scenes that agree: exactly their value, not tanh(atanh(mean))
        return mean, mean, mean
    centre = float(_fisher_z(mean))
    return mean, min(math.tanh(centre - half), mean), max(math.tanh(centre + half), mean)


def rows_interval(rows) -> tuple[float, float, float]:
    """:func:`combined_correlation_interval` of correlation rows (``rho``, ``boot_low``,
    ``boot_high``): the mean :math:`\\rho` with an interval on Fisher's :math:`z`."""
    nan = math.nan
    return combined_correlation_interval(
        [r["rho"] for r in rows],
        [r.get("boot_low", nan) for r in rows],
        [r.get("boot_high", nan) for r in rows],
    )


def _chance_se(rows) -> float:
    """The standard error of the mean over scenes when each scene's is the larger of its
    bootstrap's and its chance standard error (``chance_se``, the statistics that report it;
    :func:`stereovar.calibration.nulls.difference_interval`'s term):
    :math:`\\sqrt{\\sum_s \\max(\\mathrm{se}_{b,s}, \\mathrm{se}_{c,s})^2}/S`; NaN when no
    scene reports a chance term."""
    if not rows or not any(math.isfinite(float(r.get("chance_se", math.nan))) for r in rows):
        return math.nan
    total = 0.0
    for r in rows:
        own = (float(r.get("boot_high", math.nan)) - float(r.get("boot_low", math.nan))) / (2 * Z)
        chance = float(r.get("chance_se", math.nan))
        values = [v for v in (own, chance) if math.isfinite(v)]
        if not values:
            return math.nan
        total += max(values) ** 2
    return math.sqrt(total) / len(rows)


def statistics_table(rows: list[dict], *, spp: int | None = None) -> list[dict]:
    """One row per region and statistic: cross-scene mean :math:`\\rho` with its interval,
    the spread over scenes and the diagnostics' means.

    .. math::

        \\bar\\rho = \\frac1S \\sum_s \\rho_s, \\quad
        \\mathrm{std} = \\sqrt{\\tfrac{1}{S-1} \\sum_s (\\rho_s - \\bar\\rho)^2}

    with the interval of :func:`combined_correlation_interval` (``boot_low``, ``boot_high``:
    conditional on the scenes run) and that of :func:`random_effects_correlation_interval`
    (``scenes_low``, ``scenes_high``: for the mean over scenes like those run, the one the
    claims read; none for one scene), the mean widths of the Fisher-z and
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
            _, scenes_low, scenes_high = random_effects_correlation_interval(rho)
            reasons = sorted({str(r.get("reason", "")) for r in group} - {""})
            corrected = _finite(r.get("rho_corrected", math.nan) for r in ok)
            out.append(
                {
                    "region": region,
                    "method": method,
                    "mean_rho": float(rho.mean()) if rho.size else math.nan,
                    "boot_low": low,
                    "boot_high": high,
                    "scenes_low": scenes_low,
                    "scenes_high": scenes_high,
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
                    "chance_se": _chance_se(ok),
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
