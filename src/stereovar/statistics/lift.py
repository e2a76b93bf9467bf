"""The :math:`C_\\sigma` winner-take-all lift over chance across frames, from intervention rows.

Each frame's intervention gives the variance-matching cost's winner-take-all accuracy and its
chance level, with a tile-bootstrap interval over the frame's pixels where it computed one
(:func:`stereovar.intervention.lift.wta_lift`). :func:`lift_rows` turns them into rows shaped
like correlation rows, so that the lift meets its matched null as a correlation does
(:func:`stereovar.statistics.matched_null.matched_difference`); :func:`wta_lift` combines them
over frames. The audit's verdict reads both; the mitigation table reads the lift over its
scenes.
"""

from __future__ import annotations

import math

from .across import combined_interval
from .t_intervals import t_interval
from .values import all_finite as _ok
from .values import as_float as _f


def lift_rows(intervention: list[dict], source: str = "render",
              region: str = "all") -> list[dict]:
    """Per frame, the :math:`C_\\sigma` winner-take-all accuracy minus chance (normal
    condition) with its tile-bootstrap interval where the intervention computed one
    (:func:`stereovar.intervention.lift.wta_lift`), as rows shaped like correlation rows
    (``scene``, ``region``, ``method`` :data:`~stereovar.intervention.lift.LIFT_METHOD`,
    ``rho``, ``boot_low``, ``boot_high``), so that they meet their matched null as a
    correlation does (:func:`stereovar.statistics.matched_null.matched_difference`)."""
    from ..intervention.lift import LIFT_METHOD

    out = []
    for r in intervention:
        if not (r["cost"] == "variance_cost" and r["metric"] == "wta_accuracy"
                and r["condition"] == "normal" and r["region"] == region
                and str(r.get("source") or "render") == source
                and _ok(r["value"], r["chance"])):
            continue
        chance = _f(r["chance"])
        out.append({"scene": r.get("scene"), "region": region, "method": LIFT_METHOD,
                    "rho": _f(r["value"]) - chance,
                    "boot_low": _f(r.get("low")) - chance,
                    "boot_high": _f(r.get("high")) - chance})
    return out


def wta_lift(intervention: list[dict], source: str, region: str = "all") -> tuple:
    """The :math:`C_\\sigma` winner-take-all accuracy minus chance (normal condition), mean
    over frames with its 95% interval: the frames' tile-bootstrap intervals combined
    (:func:`stereovar.statistics.across.combined_interval`); where a frame has none (a
    region other than ``all``), the Student t interval over frames, none for one frame."""
    rows = lift_rows(intervention, source, region)
    if not rows:
        return math.nan, math.nan, math.nan
    if all(_ok(r["boot_low"], r["boot_high"]) for r in rows):
        return combined_interval([r["rho"] for r in rows], [r["boot_low"] for r in rows],
                                 [r["boot_high"] for r in rows])
    # regions and conditions the intervention gives no interval: Student t over frames
    # (none for one frame: a binomial interval over its pixels would be far too narrow)
    return t_interval([r["rho"] for r in rows])
