"""A statistic against its matched null: the per-scene difference, combined over scenes.

The matched null is camera-law noise drawn from a scene's own seed means, :math:`N` and
disparity, through the same encoding and transform (:mod:`stereovar.calibration`); a
statistic minus its matched null is the part that only Monte Carlo noise carries. The audit's
verdict, the mitigation table and the generator table read the intensity-controlled
:math:`\\rho` and the :math:`C_\\sigma` lift against it with :func:`matched_difference`.
"""

from __future__ import annotations

import math

import numpy as np

from .across import combined_interval
from .values import as_float as _f


def matched_difference(corr, nulls, *, transform, region, method="partial"):
    """The statistic minus its matched null through the same transform, per scene, combined
    over scenes.

    .. math::

        \\Delta_s = \\rho_s - \\bar\\rho_{0,s}, \\qquad
        \\bar\\Delta = \\frac1S \\sum_s \\Delta_s

    with each scene's interval from its bootstrap interval, the null mean's standard error
    and the fields' own chance standard error
    (:func:`stereovar.calibration.nulls.difference_interval`), combined over scenes
    (:func:`stereovar.statistics.across.combined_interval`).

    Parameters
    ----------
    corr : list of dict
        The row's correlation rows (``scene``, ``region``, ``method``, ``rho``,
        ``boot_low``, ``boot_high``).
    nulls : list of dict
        :data:`stereovar.calibration.summary.NULL_COLUMNS` rows.
    transform : str
        The calibration transform matched to the row (``none`` for renders as rendered).

    Returns
    -------
    null, diff, low, high : float
        The scenes' mean null and the combined difference; NaN when no scene has both.
    """
    from ..calibration.nulls import difference_interval

    table = {
        r["scene"]: r
        for r in nulls
        if (r["transform"], r["region"], r["method"]) == (transform, region, method)
    }
    null_values, diffs, lows, highs = [], [], [], []
    for r in corr:
        if (r["region"], r["method"]) != (region, method) or r["scene"] not in table:
            continue
        null = table[r["scene"]]
        d = difference_interval(
            r["rho"],
            r["boot_low"],
            r["boot_high"],
            null["null_rho"],
            null["null_se"],
            r.get("chance_se", math.nan),
        )
        if not all(math.isfinite(x) for x in d):
            continue
        null_values.append(_f(null["null_rho"]))
        diffs.append(d[0])
        lows.append(d[1])
        highs.append(d[2])
    if not diffs:
        return (math.nan,) * 4
    return (float(np.mean(null_values)), *combined_interval(diffs, lows, highs))
