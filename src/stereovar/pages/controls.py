"""The results page's table by region: the headline numbers and their controls, each with
its 95% interval.

:func:`control_rows` gives the Monte Carlo-specific :math:`\\rho` and its matched null,
:math:`\\rho` after the warp, then each control of :data:`CONTROL_GROUPS`, in every region
of :data:`REGIONS` (intervals by :func:`~stereovar.pages.headline.interval_keys`, stated by
:data:`INTERVAL_NOTE`); beside each number the claims call "explained by a control" it
names that control (:func:`explained_statistics`).
"""

from __future__ import annotations

import math

from .headline import HEADLINE_METHOD, _statistic, interval_keys
from .names import control_name
from .numbers import _f, interval_text

__all__ = ["CONTROL_GROUPS", "REGIONS", "control_rows"]

REGIONS = {"all": "all valid pixels", "non_glass": "non-glass", "glass": "glass"}
"""Regions of the headline table, in order, with their labels."""

CONTROL_GROUPS = (
    (
        "intensity-controlled",
        "ρ of ln σ² with ln μ regressed out of each view; the Monte Carlo-specific ρ is it "
        "minus the same on camera-law noise drawn from this run's frames",
        (("partial", "partial ρ"),),
    ),
    (
        "sensor baseline",
        "the same on a simulated camera's noise: what any stereo pair shows",
        (("sensor_sim", "simulated camera"),),
    ),
    (
        "null warps",
        "wrong alignments, which sit well below ρ when the warp matters",
        (
            ("null_shift", "disparity shifted"),
            ("null_flip", "right field flipped"),
            ("no_warp", "no warp"),
        ),
    ),
)
"""The controls shown beside the headline: (group, what it tells, ((method, label), ...));
every other statistic and control is in the statistics table and figure."""

INTERVAL_NOTE = (
    "95% intervals: of ρ after the warp and its camera and null-warp controls, over scenes "
    "like these (as the claims); of the intensity-controlled and Monte Carlo-specific ρ, on "
    "these scenes' pixels (block bootstrap, as the calibration and the mitigations)."
)
"""How the page's intervals are made, under the headline table."""

EXPLAINED = "explained by a control"
"""The claims' verdict that the page repeats beside the number it concerns."""


def explained_statistics(claims: list[dict], claim_statistics: dict) -> dict:
    """The statistics the claims call "explained by a control", by (region, method): the
    claim's name and its control, so the page says so beside the number.

    Parameters
    ----------
    claims : list of dict
        The claims table's rows (``id``, ``verdict``, ``control``).
    claim_statistics : dict
        Claim id to the (region, method) of the :math:`\\rho` it tests.

    Examples
    --------
    >>> explained_statistics([{"id": "rho_all", "verdict": "explained by a control",
    ...                        "control": "sensor_sim rho"}], {"rho_all": ("all", "warp")})
    {('all', 'warp'): "ρ of a simulated camera's noise"}
    """
    return {
        tuple(claim_statistics[c["id"]]): control_name(c.get("control") or "") or "its control"
        for c in claims
        if c.get("verdict") == EXPLAINED and c.get("id") in claim_statistics
    }


def control_rows(
    statistics: list[dict], matched: dict | None = None, explained: dict | None = None
) -> list[dict]:
    """The headline table by region: the Monte Carlo-specific :math:`\\rho` and its matched
    null (over all valid pixels, where the calibration has them), :math:`\\rho` after the warp,
    then each control of :data:`CONTROL_GROUPS` that ``statistics`` holds, each with its
    interval in every region (:func:`~stereovar.pages.headline.interval_keys`).

    Parameters
    ----------
    statistics : list of dict
        ``summary.json``'s ``statistics``.
    matched : dict, optional
        :func:`~stereovar.pages.headline.matched_headline` over all valid pixels.
    explained : dict, optional
        :func:`explained_statistics`: a cell it names says "explained by a control".

    Returns
    -------
    list of dict
        ``method``, ``group`` (``headline``, ``matched``, ``paper`` or a control group),
        ``label``, ``cells`` (region to text) and ``explained`` (region to the control that
        explains the cell's number).

    Examples
    --------
    >>> stats = [{"region": g, "method": m, "mean_rho": 0.5, "boot_low": 0.4, "boot_high": 0.6}
    ...          for g in ("all", "glass") for m in ("warp", "partial")]
    >>> [(r["method"], r["label"]) for r in control_rows(stats)]
    [('warp', 'ρ after the warp'), ('partial', 'intensity-controlled: partial ρ')]
    >>> control_rows(stats)[1]["cells"]
    {'all': '0.500 [0.400, 0.600]', 'non_glass': 'n/a', 'glass': '0.500 [0.400, 0.600]'}
    """
    explained = explained or {}

    def cells(method):
        return {
            region: interval_text(
                *(_f((_statistic(statistics, region, method) or {}).get(k))
                  for k in ("mean_rho", *interval_keys(method)))
            )
            for region in REGIONS
        }

    def marks(method):
        return {g: explained[(g, method)] for g in REGIONS if (g, method) in explained}

    rows = []
    if matched and math.isfinite(matched["value"]):
        none = {g: "no null" for g in REGIONS if g != "all"}
        rows += [
            {"method": "mc_specific", "group": "headline", "label": "Monte Carlo-specific ρ",
             "cells": {"all": matched["text"], **none}, "explained": {}},
            {"method": "matched_null", "group": "matched",
             "label": "its matched null (camera-law noise)",
             "cells": {"all": f"{matched['null']:.3f}", **none}, "explained": {}},
        ]
    rows.append({"method": HEADLINE_METHOD, "group": "paper", "label": "ρ after the warp",
                 "cells": cells(HEADLINE_METHOD), "explained": marks(HEADLINE_METHOD)})
    present = {r.get("method") for r in statistics}
    for group, _, methods in CONTROL_GROUPS:
        rows += [
            {"method": m, "group": group, "label": f"{group}: {label}", "cells": cells(m),
             "explained": marks(m)}
            for m, label in methods
            if m in present
        ]
    return rows
