"""The results page's headline numbers: :math:`\\rho` after the warp and the Monte
Carlo-specific :math:`\\rho`, each with its 95% interval.

:func:`headline` is :math:`\\rho` after the warp (Eq. 3), the paper's statistic;
:func:`matched_headline` the intensity-controlled :math:`\\rho` minus its matched null
through the same path, with its verdict. Which interval the page shows each statistic with
(:func:`interval_keys`) is decided here for the whole page: one quantity, one interval.
"""

from __future__ import annotations

import math

from .numbers import _f, interval_text

__all__ = ["headline", "interval_keys", "matched_headline"]

HEADLINE_METHOD = "warp"
"""The paper's statistic: Pearson's :math:`\\rho` after the warp (Eq. 3)."""

MATCHED_METHOD = "partial"
"""The statistic whose difference from its matched null is the Monte Carlo-specific part:
the intensity-controlled :math:`\\rho` (camera noise follows intensity, which both views
share)."""

SCENE_METHODS = frozenset({"warp", "sensor_sim", "sensor", "null_shift", "null_flip",
                           "no_warp"})
"""Statistics the page reads against the paper and the camera, as the claims do: each shown
with the interval for the mean over scenes like these (``scenes_low``, ``scenes_high``, a
random-effects interval), the same interval as in the claims table. The others (the
intensity-controlled :math:`\\rho`, read against its matched null as the calibration and the
mitigations read it) keep the scenes' block-bootstrap intervals combined. One quantity, one
interval: no number on the page is shown with both."""

Z = 1.959963984540054
"""The standard normal's 0.975 quantile (95% intervals)."""


def interval_keys(method: str) -> tuple[str, str]:
    """The statistics-table columns of ``method``'s interval on the page
    (:data:`SCENE_METHODS`).

    Examples
    --------
    >>> interval_keys("warp"), interval_keys("partial")
    (('scenes_low', 'scenes_high'), ('boot_low', 'boot_high'))
    """
    return ("scenes_low", "scenes_high") if method in SCENE_METHODS else ("boot_low", "boot_high")


def _statistic(statistics: list[dict], region: str, method: str) -> dict | None:
    """The row of ``statistics`` for ``region`` and ``method``; None when it has none."""
    return next(
        (r for r in statistics if r.get("region") == region and r.get("method") == method), None
    )


def headline(statistics: list[dict]) -> dict:
    """:math:`\\rho` after the warp over all valid pixels (Eq. 3) from ``summary.json``'s
    ``statistics``: the mean over scenes with its interval for scenes like these
    (:func:`interval_keys`; the claims table's).

    Returns
    -------
    dict
        ``rho``, ``low``, ``high`` (NaN when missing), ``n_scenes`` and ``text``
        (:func:`~stereovar.pages.numbers.interval_text`).

    Examples
    --------
    >>> h = headline([{"region": "all", "method": "warp", "mean_rho": 0.7, "boot_low": 0.65,
    ...                "boot_high": 0.75, "scenes_low": 0.6, "scenes_high": 0.8, "n_scenes": 3}])
    >>> h["text"], h["n_scenes"]
    ('0.700 [0.600, 0.800]', 3)
    """
    row = _statistic(statistics, "all", HEADLINE_METHOD) or {}
    rho, low, high = (_f(row.get(k)) for k in ("mean_rho", *interval_keys(HEADLINE_METHOD)))
    return {
        "rho": rho,
        "low": low,
        "high": high,
        "n_scenes": row.get("n_scenes"),
        "text": interval_text(rho, low, high),
    }


def matched_headline(
    statistics: list[dict],
    nulls: list[dict],
    *,
    region: str = "all",
    method: str = MATCHED_METHOD,
    transform: str = "none",
    scenes=None,
) -> dict:
    """The Monte Carlo-specific :math:`\\rho`: the statistic ``method`` over ``region``
    (``summary.json``'s mean over scenes) minus its matched null through the same path (the
    calibration's ``calibration_nulls.csv``, ``transform`` ``none``: the renders as
    rendered), with its 95% interval.

    .. math::

        \\Delta = \\bar\\rho - \\frac1S\\sum_s \\bar\\rho_{0,s}, \\qquad
        \\Delta \\pm z_{0.975}\\sqrt{\\Bigl(\\frac{h - \\ell}{2 z_{0.975}}\\Bigr)^2
            + \\frac{1}{S^2}\\sum_s \\bigl(\\mathrm{se}_{0,s}^2 + s_{\\text{chance},s}^2\\bigr)}

    with :math:`[\\ell, h]` the statistic's interval from the scenes' block bootstraps
    combined (:func:`stereovar.statistics.across.combined_correlation_interval`: placed on
    Fisher's :math:`z` but as long as :func:`stereovar.statistics.across.combined_interval`'s,
    so :math:`(h - \\ell)/(2 z_{0.975})` is still the mean's standard error; the difference
    keeps the normal interval, being no correlation). This is
    :func:`stereovar.statistics.matched_null.matched_difference` (each scene's difference
    with :func:`stereovar.calibration.nulls.difference_interval`, combined over scenes)
    written with the scenes' mean: the same number and interval as the mitigation table's
    ``none`` row. The verdict is :func:`stereovar.statistics.mitigations.mc_cue_state`'s
    against the calibration's equivalence margin.

    Parameters
    ----------
    statistics : list of dict
        ``summary.json``'s ``statistics`` (``region``, ``method``, ``mean_rho``,
        ``boot_low``, ``boot_high``, ``n_scenes``).
    nulls : list of dict
        :data:`stereovar.calibration.summary.NULL_COLUMNS` rows.
    scenes : iterable of str, optional
        The run's scenes: only their nulls count.

    Returns
    -------
    dict
        ``value``, ``low``, ``high``, ``null`` (the scenes' mean null), ``margin``,
        ``statistic`` (the statistic's own value, low, high), ``n_scenes``, ``verdict`` and
        ``text``; ``value`` NaN and ``verdict`` ``n/a`` when the run has no such null.

    Examples
    --------
    >>> stats = [{"region": "all", "method": "partial", "mean_rho": 0.5, "boot_low": 0.4,
    ...           "boot_high": 0.6, "n_scenes": 1}]
    >>> nulls = [{"scene": "a", "transform": "none", "region": "all", "method": "partial",
    ...           "null_rho": 0.1, "null_se": 0.0, "chance_sd": 0.0, "margin": 0.05}]
    >>> h = matched_headline(stats, nulls)
    >>> h["text"], h["null"], h["verdict"]
    ('0.400 [0.300, 0.500]', 0.1, 'remains')
    """
    from ..statistics.mitigations import mc_cue_state

    row = _statistic(statistics, region, method) or {}
    value, low, high = (_f(row.get(k)) for k in ("mean_rho", "boot_low", "boot_high"))
    wanted = set(scenes) if scenes else None
    chosen = [
        r for r in nulls
        if (r.get("transform"), r.get("region"), r.get("method")) == (transform, region, method)
        and (wanted is None or r.get("scene") in wanted)
        and math.isfinite(_f(r.get("null_rho")))
    ]
    margins = [_f(r.get("margin")) for r in chosen if math.isfinite(_f(r.get("margin")))]
    out = {
        "value": math.nan, "low": math.nan, "high": math.nan, "null": math.nan,
        "margin": margins[0] if margins else math.nan,
        "statistic": (value, low, high), "n_scenes": row.get("n_scenes"),
        "verdict": "n/a", "text": "n/a",
    }
    if not chosen or not math.isfinite(value):
        return out
    s = len(chosen)
    null = sum(_f(r["null_rho"]) for r in chosen) / s

    def sq(key):
        return sum(_f(r.get(key)) ** 2 for r in chosen if math.isfinite(_f(r.get(key))))

    diff = value - null
    out |= {"value": diff, "null": null, "text": interval_text(diff, math.nan, math.nan)}
    if math.isfinite(low) and math.isfinite(high):
        own = (high - low) / (2 * Z)
        chance = _f(row.get("chance_se"))
        own = max(own, chance) if math.isfinite(chance) else own
        se = math.sqrt(own**2 + sq("null_se") / s**2)
        out |= {"low": diff - Z * se, "high": diff + Z * se}
        out["text"] = interval_text(diff, out["low"], out["high"])
        out["verdict"] = mc_cue_state(out["low"], out["high"], out["margin"])
    return out
