"""The rules the calibration holds to its level, as each fires on one replicate row.

``above_zero``
    the interval lies above 0 (the audit's Monte Carlo rule on ``partial``, the old
    mitigation ``remains``);
``above_null``
    the statistic minus its matched null through the same transform (the mean over the
    ``camera`` null's other replicates, or the encoded null of an 8-bit pipeline) has an
    interval above :data:`MIN_EFFECT`
    (:func:`~stereovar.calibration.nulls.difference_interval`): what "Monte Carlo-specific"
    means here;
``removed``
    that difference's interval lies inside the equivalence margin (:func:`equivalent`);
``shared``
    the audit's shared-streams check (``shared_streams``: the per-seed residuals'
    cross-view correlation at zero disparity) has an interval above
    :data:`~stereovar.statistics.residuals.SHARED_STREAMS`, on frames whose views are
    independent;
``claim <id> holds``
    a level claim of the claims table on :math:`\\rho` against the ``sensor_sim`` camera
    baseline holds on the replicate's scenes (:mod:`stereovar.calibration.claims`, whose rows
    the calibration table job adds; scenes combined, as the table combines them);
``matching``
    the audit's matching-cue rule (``c_sigma_lift``: the variance-matching cost's
    winner-take-all lift over chance, :mod:`stereovar.intervention.lift`): the lift minus its
    matched null's has an interval above 0, and the same replicate's ``partial`` fires
    ``above_null`` (a matching cue is called only where the cue is Monte Carlo-specific, so
    the rule's false positives are at most the verdict rule's).

Every statistic but the audit's light's checks is held to ``above_null`` (:data:`RULE_OF`).
The coverage of an interval is counted here too: how often it holds its estimand, the mean of
the same scene's other replicates.
"""

from __future__ import annotations

import math

import numpy as np

from ..intervention.lift import LIFT_METHOD
from .nulls import _group
from .rates import _f

MIN_EFFECT = 0.05
"""The smallest Monte Carlo-specific :math:`\\rho` a rule calls a cue: the difference from
the matched null must have its 95% interval above it, not merely above 0. Over 57 600
pixels the interval is about 0.01 wide, so any small misfit of the control is significant;
the camera pipelines outside the null's class (:mod:`stereovar.calibration.pipelines`) leave
0.000-0.032 after the intensity control's colour and position terms (0.018 +/- 0.015 for
8-bit sRGB at 1 DN, 0.032 +/- 0.009 and at most 0.048 for a fixed gain map; the default
scenes, 16 replicates each),
and fired the rule above 0 on 6-50% of their replicates. A cue this weak is below what a
camera pipeline leaves, so it is not called Monte Carlo-specific."""

RULE_OF = {"shared_streams": "shared", LIFT_METHOD: "matching"}
"""The rule each check of the audit's light is held to; every other statistic's is
``above_null``."""


def equivalent(low, high, margin) -> bool:
    """Whether an interval lies inside :math:`[-\\delta, \\delta]` (two one-sided tests)."""
    low, high, margin = _f(low), _f(high), _f(margin)
    return bool(math.isfinite(margin) and margin > 0 and -margin < low and high < margin)


def _fires(rule: str, r: dict, margin=math.nan) -> bool | None:
    if rule == "shared":
        from ..statistics.residuals import SHARED_STREAMS

        low = _f(r["boot_low"])
        return None if not math.isfinite(low) else low > SHARED_STREAMS
    if rule == "above_zero":
        low = _f(r["boot_low"])
        return None if not math.isfinite(low) else low > 0
    low, high = _f(r["diff_low"]), _f(r["diff_high"])
    if not (math.isfinite(low) and math.isfinite(high)):
        return None
    if rule == "matching":
        specific = r.get("partial_fires")
        return None if specific is None else bool(low > 0 and specific)
    if rule == "above_null":
        return low > MIN_EFFECT
    if rule == "removed":
        return equivalent(low, high, margin)
    raise ValueError(f"unknown rule {rule!r}")


def _count(rule, group, margin=math.nan) -> tuple[int, int]:
    fired = [_fires(rule, r, margin) for r in group]
    fired = [f for f in fired if f is not None]
    return int(sum(fired)), len(fired)


def _pair_with_partial(rows: list[dict]) -> None:
    """Give each ``c_sigma_lift`` row ``partial_fires``: whether the verdict rule
    (``partial`` ``above_null``) fires on the same scene (or scenes combined), replicate,
    design and transform, which the ``matching`` rule requires."""
    keys = ("scene", "replicate", "kind", "strength_factor", "transform", "region")
    fired = {tuple(r[k] for k in keys): _fires("above_null", r)
             for r in rows if r["method"] == "partial"}
    for r in rows:
        if r["method"] == LIFT_METHOD:
            r["partial_fires"] = fired.get(tuple(r[k] for k in keys))


def _coverage(group, column_value="rho", low="boot_low", high="boot_high") -> tuple[int, int]:
    """Replicates whose interval holds the leave-one-out mean of the same scene's other
    replicates (the estimand: the statistic's expectation under this design and scene)."""
    hits = total = 0
    for scene_group in _group(group, ("scene",)).values():
        k, n = _scene_coverage(scene_group, column_value, low, high)
        hits, total = hits + k, total + n
    return hits, total


def _scene_coverage(group, column_value, low, high) -> tuple[int, int]:
    values = np.array([_f(r[column_value]) for r in group])
    lows = np.array([_f(r[low]) for r in group])
    highs = np.array([_f(r[high]) for r in group])
    ok = np.isfinite(values) & np.isfinite(lows) & np.isfinite(highs)
    values, lows, highs = values[ok], lows[ok], highs[ok]
    n = values.size
    if n < 3:
        return 0, 0
    truth = (values.sum() - values) / (n - 1)
    return int(np.sum((lows <= truth) & (truth <= highs))), int(n)
