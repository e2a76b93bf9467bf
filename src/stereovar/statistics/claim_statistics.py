"""The statistics a claim of the paper can be tested on, each with its interval over scenes.

A claim in ``claims.yaml`` names its statistic and that of its bearing control (``statistic:
{name: ...}``, a key of :data:`STATISTICS` with its settings); each is computed from a run's
rows (:class:`ClaimInputs`) as an :class:`Estimate`: a value with its 95% interval (or at
0.90 for an equivalence test) and a note. A mean :math:`\\rho` over scenes, or a mean
difference of two regions' :math:`\\rho`, has the random-effects interval over scenes like
those run (:func:`~stereovar.statistics.across.random_effects_interval`; for a mean
:math:`\\rho`, on Fisher's :math:`z`); a ratio of regions the geometric mean's
(:func:`~stereovar.statistics.t_intervals.geometric_t_interval`); a Table 3 effect, a seed
change and the attenuation-corrected :math:`\\rho` a Student-t interval over scenes
(:func:`~stereovar.statistics.t_intervals.t_interval`); the spread over the SPP sweep none.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .across import random_effects_correlation_interval, random_effects_interval
from .claim_rules import _NAN3, _ok
from .t_intervals import geometric_t_interval, t_interval


class ClaimInputs(NamedTuple):
    """What a claim's statistic is computed from: every scene's correlation rows at the main
    SPP, Table 2's rows, the seed-subset curve rows and the intervention rows."""

    rows: list
    sweep: list
    curve: list
    intervention: list


class Estimate(NamedTuple):
    """A statistic's value with its interval (95% unless the statistic was asked for another
    level), and why it is undefined or what it left out (empty when nothing)."""

    value: float
    low: float
    high: float
    note: str = ""


def _per_scene(rows, key: str, value=lambda r: r) -> dict:
    """Scene to ``{row[key]: value(row)}``, scenes in first-seen order."""
    out: dict = {}
    for r in rows:
        out.setdefault(r.get("scene"), {})[r[key]] = value(r)
    return out


def _select(rows, region, method):
    return [r for r in rows if r["region"] == region and r["method"] == method]


def _over_scenes(values, level, *, correlation: bool = False) -> Estimate:
    """:func:`~stereovar.statistics.across.random_effects_interval` (``correlation``: of
    correlations, on Fisher's :math:`z`,
    :func:`~stereovar.statistics.across.random_effects_correlation_interval`, so that it stays
    inside :math:`[-1, 1]`), with a note when one scene leaves no between-scene variance to
    estimate."""
    interval = random_effects_correlation_interval if correlation else random_effects_interval
    value, low, high = interval(values, level=level)
    note = ""
    if math.isfinite(value) and not math.isfinite(low):
        note = (
            "one scene: the variance between scenes cannot be estimated, so there is no "
            "interval for the mean over scenes"
        )
    return Estimate(value, low, high, note)


def _rho(inputs: ClaimInputs, *, region, method, level=0.95) -> Estimate:
    """Mean :math:`\\rho` over scenes with the random-effects interval (the variance between
    scenes with the scenes' own errors) on Fisher's :math:`z`."""
    rhos = [r["rho"] for r in _select(inputs.rows, region, method)]
    return _over_scenes(rhos, level, correlation=True)


def _rho_difference(inputs: ClaimInputs, *, region, minus, method, level=0.95) -> Estimate:
    """Mean over scenes of :math:`\\rho_{region} - \\rho_{minus}` with the random-effects
    interval of the per-scene differences (on the normal scale: a difference of two
    correlations lies in :math:`[-2, 2]`)."""
    selected = [r for r in inputs.rows if r["method"] == method and r["region"] in (region, minus)]
    diffs = []
    for pair in _per_scene(selected, "region").values():
        a, b = pair.get(region), pair.get(minus)
        if a and b and _ok(a["rho"], b["rho"]):
            diffs.append(float(a["rho"]) - float(b["rho"]))
    return _over_scenes(diffs, level)


def _sweep_spread(inputs: ClaimInputs, *, column, level=0.95) -> Estimate:
    """Relative spread of Table 2's ``column`` over the SPP sweep, (max - min) / |mean|; no
    interval (one value per SPP), so no equivalence can be shown with it."""
    rho = np.array([float(r.get(column, math.nan)) for r in inputs.sweep], dtype=np.float64)
    rho = rho[np.isfinite(rho)]
    if rho.size < 2:
        return Estimate(*_NAN3)
    return Estimate(
        float((rho.max() - rho.min()) / abs(rho.mean())),
        math.nan,
        math.nan,
        "a spread over the sweep has no interval",
    )


def _seed_change(inputs: ClaimInputs, *, region, method, level=0.95) -> Estimate:
    """Mean over scenes of the relative change of :math:`\\rho` from the second-largest
    seed subset to all seeds of the seed curve, (full - half) / |full|, with a t interval."""
    selected = [r for r in inputs.curve if (r["region"], r["method"]) == (region, method)]
    changes = []
    for pts in _per_scene(selected, "n_prime", lambda r: float(r["mean_rho"])).values():
        if len(pts) < 2:
            continue
        ordered = sorted(pts, key=int)
        full, half = pts[ordered[-1]], pts[ordered[-2]]
        if _ok(full, half) and full != 0:
            changes.append((full - half) / abs(full))
    return Estimate(*t_interval(changes, level=level))


def _corrected_rho(inputs: ClaimInputs, *, region, method, level=0.95) -> Estimate:
    """Mean over scenes of the attenuation-corrected :math:`\\rho` with a t interval, cut to
    :math:`[-1, 1]`: a corrected value is a ratio that can pass 1, but it estimates a
    correlation, and cutting the interval to where that lies keeps its coverage (as
    :func:`stereovar.audit.verdict.correlation_summary` does). The mean itself is not cut."""
    rows = _select(inputs.rows, region, method)
    values = [float(r.get("rho_corrected", math.nan)) for r in rows]
    value, low, high = t_interval(values, level=level)
    if math.isfinite(low) and math.isfinite(high):
        low, high = min(max(low, -1.0), 1.0), min(max(high, -1.0), 1.0)
    return Estimate(value, low, high)


def _region_ratio(
    inputs: ClaimInputs, *, column, method, numerator, denominator, level=0.95
) -> Estimate:
    """Geometric mean over scenes of ``column`` in region ``numerator`` over region
    ``denominator`` (:func:`~stereovar.statistics.t_intervals.geometric_t_interval`).

    A scene without a finite value in either region (e.g. no glass) is left out and named in
    the note. A scene whose ratio is not positive and finite has no logarithm: the estimate
    is then NaN with those scenes and their values in the note, rather than a geometric mean
    of the other scenes only, which would leave out the scenes that contradict the claim.
    """
    selected = [
        r for r in inputs.rows if r["method"] == method and r["region"] in (numerator, denominator)
    ]
    ratios, refused, missing = [], [], []
    values = _per_scene(selected, "region", lambda r: float(r.get(column, math.nan)))
    for scene, means in values.items():
        a, b = means.get(numerator, math.nan), means.get(denominator, math.nan)
        if not _ok(a, b):
            missing.append(str(scene))
            continue
        ratio = a / b if b != 0 else math.inf
        if a > 0 and b > 0 and math.isfinite(ratio) and ratio > 0:
            ratios.append(ratio)
        else:
            refused.append(f"{scene} ({numerator} {a:g}, {denominator} {b:g})")
    if refused:
        return Estimate(
            *_NAN3,
            f"{column} ratio not positive in {', '.join(refused)}: it has no logarithm, so no "
            "geometric mean",
        )
    note = f"left out, no finite {column}: {', '.join(missing)}" if missing else ""
    if not ratios:
        return Estimate(*_NAN3, note)
    return Estimate(*geometric_t_interval(ratios, level=level), note)


def _intervention_effect(
    inputs: ClaimInputs, *, cost, metric, region, source, level=0.95
) -> Estimate:
    """Mean over scenes of normal minus decorrelated for one Table 3 cell, with a t
    interval (rows of ``source``: ``render`` or ``sensor``; no ``source`` is ``render``)."""
    selected = [
        r
        for r in inputs.intervention
        if (r["cost"], r["metric"], r["region"]) == (cost, metric, region)
        and str(r.get("source") or "render") == source
    ]
    diffs = [
        float(c["normal"]) - float(c["decorrelated"])
        for c in _per_scene(selected, "condition", lambda r: r["value"]).values()
        if "normal" in c and "decorrelated" in c and _ok(c["normal"], c["decorrelated"])
    ]
    return Estimate(*t_interval(diffs, level=level))


def _regions():
    from .regions import REGIONS

    return REGIONS


def _methods():
    from .registry import METHODS

    return METHODS.names()


def _sweep_columns():
    return tuple(f"rho_{r}" for r in _regions())


def _row_columns():
    from .correlation import RESULT_KEYS

    return tuple(k for k in RESULT_KEYS if k != "reason")


def _costs():
    from ..intervention.metrics import COSTS

    return tuple(COSTS)


def _metrics():
    from ..intervention.metrics import COSTS

    return tuple(dict.fromkeys(m for ms in COSTS.values() for m in ms))


def _intervention_regions():
    from ..intervention.metrics import REGIONS

    return REGIONS


def _two_regions(settings, first="region", second="minus") -> str | None:
    if settings[first] == settings[second]:
        return f"{first} and {second} are both {settings[first]!r}; give two different regions"
    return None


def _metric_of_cost(settings) -> str | None:
    from ..intervention.metrics import COSTS

    metrics = COSTS[settings["cost"]]
    if settings["metric"] not in metrics:
        return (
            f"metric {settings['metric']!r} is not reported for cost {settings['cost']!r}; "
            f"use one of {', '.join(metrics)}"
        )
    return None


@dataclass(frozen=True)
class Statistic:
    """A statistic a claim can be tested on.

    Attributes
    ----------
    compute : callable
        ``compute(inputs, level=0.95, **settings) -> Estimate``: the value with its interval
        at ``level`` (0.90 for an equivalence test).
    settings : dict
        Each setting's name to a function giving its allowed values.
    check : callable, optional
        ``check(settings) -> message or None``: a rule across settings.
    """

    compute: Callable[..., Estimate]
    settings: dict = field(default_factory=dict)
    check: Callable[[dict], str | None] | None = None


STATISTICS = {
    "rho": Statistic(_rho, {"region": _regions, "method": _methods}),
    "rho_difference": Statistic(
        _rho_difference,
        {"region": _regions, "minus": _regions, "method": _methods},
        _two_regions,
    ),
    "sweep_spread": Statistic(_sweep_spread, {"column": _sweep_columns}),
    "seed_change": Statistic(_seed_change, {"region": _regions, "method": _methods}),
    "corrected_rho": Statistic(_corrected_rho, {"region": _regions, "method": _methods}),
    "region_ratio": Statistic(
        _region_ratio,
        {
            "column": _row_columns,
            "method": _methods,
            "numerator": _regions,
            "denominator": _regions,
        },
        lambda s: _two_regions(s, "numerator", "denominator"),
    ),
    "intervention_effect": Statistic(
        _intervention_effect,
        {
            "cost": _costs,
            "metric": _metrics,
            "region": _intervention_regions,
            "source": lambda: ("render", "sensor"),
        },
        _metric_of_cost,
    ),
}
"""What a claim in ``claims.yaml`` can be tested on (its ``statistic: {name: ...}``)."""


def estimate(statistic: dict, inputs: ClaimInputs, level: float = 0.95) -> Estimate:
    """A claim's statistic (a ``statistic`` of ``claims.yaml``: its ``name`` in
    :data:`STATISTICS` and its settings) computed on ``inputs``, its interval at ``level``."""
    settings = {k: v for k, v in statistic.items() if k != "name"}
    return STATISTICS[statistic["name"]].compute(inputs, level=level, **settings)
