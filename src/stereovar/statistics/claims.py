"""The claims table: which of the paper's quantitative claims hold on the scenes run.

The claims are data: ``claims.yaml`` beside this module (schema
``stereovar/schemas/claims.schema.yaml``) gives, per claim, its id, text, section of the paper,
the paper's value, its kind and rule settings, the statistic it is tested on and the bearing
control. :func:`load_claims` reads and validates it; :func:`claims_table` computes each claim's
statistic and control (:data:`STATISTICS`) on a run and gives one row per claim with a verdict
of :func:`verdict`, whose rules the file states for the table's caption
(:meth:`Claims.caption`). Every interval is 95% and, for a level, is for the mean over scenes
like those run (:func:`~stereovar.statistics.across.random_effects_interval`: the variance
between scenes is counted; one scene gives no interval; for a mean :math:`\\rho`, on Fisher's
:math:`z`, :func:`~stereovar.statistics.across.random_effects_correlation_interval`). The
rules:

* **level** claims (a value, e.g. :math:`\\rho = 0.754`): *not testable at this scale* when
  ours or its interval is undefined; *does not hold* when the paper's value is outside our
  interval; *not testable at this scale* when the interval contains the null too (no effect,
  :math:`\\rho = 0`: the data cannot tell the claim from no effect); *explained by a
  control* when the control accounts for ours (:func:`explained_by_control`: the interval of
  ours minus the control reaches 0, or the control is at least the claim's ``control_share``
  of ours); *holds* otherwise;
* **level claims with an equivalence margin** :math:`m` (required when the paper's value is
  the null, e.g. real sensors' :math:`\\rho = 0`, which an interval that must exclude the
  null could never confirm): decided by equivalence, :func:`equivalence_verdict` around the
  paper's value;
* **ratio** claims (e.g. glass variance :math:`7\\times` non-glass): the level rule with the
  null 1, on the geometric mean over scenes and the exponentiated Student-t interval of the
  per-scene log ratios (:func:`geometric_t_interval`); a scene with a ratio that is not
  positive has no logarithm, and the claim is *not testable* with that scene named;
* **direction** claims (a sign, e.g. Table 3's normal minus decorrelated): *not testable at
  this scale* when our interval spans 0; *does not hold* when it lies on the other side;
  *explained by a control* when the control accounts for ours, as for a level; *holds*
  otherwise (beyond its control);
* **tolerance** claims (a relative change within the paper's :math:`\\pm t`): equivalence
  with the margin :math:`t` around 0 (:func:`equivalence_verdict`): a statistic without an
  interval cannot show it.

Equivalence is two one-sided tests (TOST) at 5%: *holds* when the 90% interval lies inside
:math:`(c - m,\\ c + m)`; *does not hold* when the 95% interval lies wholly outside
:math:`[c - m,\\ c + m]`; *not testable at this scale* otherwise (too wide to show either).
The 90% interval is the claim's statistic computed again at level 0.90 (Student-t
quantile :math:`t_{0.95,\\,S-1}` in place of :math:`t_{0.975,\\,S-1}`), and the row's note
gives it.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy import stats

from ..errors import ClaimsError
from ..schema import load_yaml
from .across import random_effects_correlation_interval, random_effects_interval

HOLDS = "holds"
FAILS = "does not hold"
EXPLAINED = "explained by a control"
UNTESTABLE = "not testable at this scale"

KINDS = ("level", "ratio", "direction", "tolerance")
"""The kinds of claim, in the order the caption states their rules."""

NULLS = {"level": 0.0, "ratio": 1.0}
"""The no-effect value of a level claim (:math:`\\rho = 0`) and of a ratio claim (1), used by
:func:`verdict` when the claim does not state its own."""

CLAIMS_PATH = Path(__file__).resolve().with_name("claims.yaml")
"""The paper's claims, shipped with the package."""

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "claims.schema.yaml"

CLAIMS_COLUMNS = [
    "id",
    "claim",
    "section",
    "kind",
    "paper",
    "null",
    "ours",
    "ours_low",
    "ours_high",
    "control",
    "control_value",
    "control_low",
    "control_high",
    "verdict",
    "note",
]

_NAN3 = (math.nan,) * 3


def _ok(*values) -> bool:
    return all(v is not None and math.isfinite(float(v)) for v in values)


def difference_interval(ours, control) -> tuple[float, float, float]:
    """Ours minus the control with its interval, the two taken as independent.

    .. math::

        d = \\hat\\theta - \\hat\\theta_c, \\qquad
        \\left[\\, d - \\sqrt{(\\hat\\theta - \\ell)^2 + (h_c - \\hat\\theta_c)^2},\\ \\
        d + \\sqrt{(h - \\hat\\theta)^2 + (\\hat\\theta_c - \\ell_c)^2} \\,\\right]

    (each side's half-widths in quadrature: the interval of a difference of independent
    estimates; for symmetric intervals the half-width is :math:`\\sqrt{w^2 + w_c^2}`). Ours
    and the control are computed on the same scenes, so they are usually positively
    correlated and the difference is then better known than this: the interval errs wide,
    toward "explained by a control".

    Parameters
    ----------
    ours, control : tuple (value, low, high)

    Examples
    --------
    >>> d, low, high = difference_interval((0.088, 0.065, 0.111), (0.003, 0.0026, 0.0034))
    >>> round(d, 3), round(low, 4), round(high, 4)
    (0.085, 0.062, 0.108)
    """
    a, a_low, a_high = (float(v) for v in ours)
    b, b_low, b_high = (float(v) for v in control)
    d = a - b
    return d, d - math.hypot(a - a_low, b_high - b), d + math.hypot(a_high - a, b - b_low)


def explained_by_control(
    ours, control, *, side: float, null: float = 0.0, share: float | None = None
) -> bool:
    """Whether the control accounts for ours: the interval of ours minus the control
    (:func:`difference_interval`) reaches 0 or lies on the control's side, or, with a
    ``share`` :math:`q`, the control's effect is at least :math:`q` of ours,

    .. math::

        \\sigma\\,(\\hat\\theta_c - \\theta_0) \\ge q\\,\\sigma\\,(\\hat\\theta - \\theta_0),

    :math:`\\sigma` the side of the claim (+1 or -1) and :math:`\\theta_0` its null. A control
    on the claim's side but far smaller than ours explains nothing.

    Parameters
    ----------
    ours, control : tuple (value, low, high)
    side : float, keyword-only
        The claim's side: the sign of the paper's value (a direction) or of the paper's
        value minus the null (a level or ratio).
    null : float, keyword-only
        The no-effect value the shares are measured from.
    share : float, keyword-only, optional
        The claim's ``control_share``; None: the interval alone decides.

    Examples
    --------
    >>> explained_by_control((0.088, 0.065, 0.111), (0.003, 0.0026, 0.0034), side=1)
    False
    >>> explained_by_control((0.088, 0.065, 0.111), (0.08, 0.07, 0.09), side=1)
    True
    >>> explained_by_control((0.088, 0.065, 0.111), (0.05, 0.049, 0.051), side=1, share=0.5)
    True
    """
    sign = math.copysign(1.0, side)
    if _ok(*ours, *control):
        _, low, high = difference_interval(ours, control)
        if (low if sign > 0 else -high) <= 0:
            return True
    if share is not None and _ok(ours[0], control[0]):
        theirs, mine = sign * (float(control[0]) - null), sign * (float(ours[0]) - null)
        if theirs >= share * mine:
            return True
    return False


def equivalence_verdict(ours, low, high, *, centre: float, margin: float, interval90=None) -> str:
    """The verdict of equivalence to ``centre`` within ``margin``: two one-sided tests
    (TOST) at 5%.

    .. math::

        \\text{holds} \\iff c - m < \\ell_{90} \\ \\text{and}\\ h_{90} < c + m, \\qquad
        \\text{does not hold} \\iff \\ell_{95} > c + m \\ \\text{or}\\ h_{95} < c - m

    *Holds* rejects both :math:`\\theta \\le c - m` and :math:`\\theta \\ge c + m`, each at
    5% one-sided, which is the 90% interval inside the margin; *does not hold* when the 95%
    interval (the one the table shows) lies wholly outside it; *not testable at this scale*
    otherwise, and when ours or its interval is undefined: a point value without an interval
    cannot show equivalence.

    Parameters
    ----------
    ours, low, high : float
        Our value and its 95% interval.
    centre, margin : float, keyword-only
        The claimed value :math:`c` and the margin :math:`m > 0`.
    interval90 : tuple (low, high), keyword-only, optional
        The 90% interval. None: the 95% interval is used for "holds" too, a conservative
        TOST at 2.5% each side.

    Examples
    --------
    >>> equivalence_verdict(0.0, -0.05, 0.05, centre=0.0, margin=0.002)
    'not testable at this scale'
    >>> equivalence_verdict(0.03, 0.01, 0.05, centre=0.0, margin=0.1)
    'holds'
    >>> equivalence_verdict(0.3, 0.2, 0.4, centre=0.0, margin=0.1)
    'does not hold'
    """
    if not _ok(ours, low, high, centre, margin):
        return UNTESTABLE
    low90, high90 = (low, high) if interval90 is None else interval90
    if _ok(low90, high90) and centre - margin < low90 and high90 < centre + margin:
        return HOLDS
    if low > centre + margin or high < centre - margin:
        return FAILS
    return UNTESTABLE


def verdict(
    kind: str,
    paper: float,
    ours,
    low,
    high,
    control=_NAN3,
    *,
    control_explains: bool = True,
    null_value: float | None = None,
    equivalence_margin: float | None = None,
    equivalence_interval=None,
    control_share: float | None = None,
) -> str:
    """The verdict of one claim (the rules of the module docstring).

    A tolerance claim, and a level claim with an ``equivalence_margin``, is decided by
    :func:`equivalence_verdict` (its control is shown for context only); a level, ratio or
    direction claim that would hold is *explained by a control* when
    :func:`explained_by_control`.

    Parameters
    ----------
    kind : {"level", "ratio", "direction", "tolerance"}
    paper : float
        The paper's value: a level, a ratio, the signed effect of a direction claim (only its
        sign counts) or the tolerance of a tolerance claim.
    ours, low, high : float
        Our value and its 95% interval (a ratio's on the ratio scale).
    control : tuple (value, low, high)
        The bearing control with its 95% interval.
    control_explains : bool, keyword-only
        Whether the control can explain the claim away (False when it is shown for context).
    null_value : float, keyword-only, optional
        The no-effect value a level or ratio interval must exclude (default :data:`NULLS`).
    equivalence_margin : float, keyword-only, optional
        A level claim's margin: the claim is then equivalence to the paper's value within it.
        A tolerance claim's margin is its tolerance, ``paper``.
    equivalence_interval : tuple (low, high), keyword-only, optional
        The 90% interval for the equivalence test (default: the 95% one, a conservative TOST
        at 2.5%).
    control_share : float, keyword-only, optional
        The share of ours a control must reach to explain it whatever the intervals.

    Examples
    --------
    The default run's Table 3 residual SAD gt_margin on non-glass, against its sensor
    control, 30 times smaller:

    >>> verdict("direction", 59, 0.088, 0.065, 0.111, (0.003, 0.0026, 0.0034))
    'holds'
    """
    if kind not in KINDS:
        raise ValueError(f"unknown claim kind {kind!r}")
    if kind == "tolerance":
        return equivalence_verdict(
            ours, low, high, centre=0.0, margin=paper, interval90=equivalence_interval
        )
    if equivalence_margin is not None:
        if kind != "level":
            raise ValueError(f"a {kind} claim has no equivalence margin")
        return equivalence_verdict(
            ours,
            low,
            high,
            centre=paper,
            margin=equivalence_margin,
            interval90=equivalence_interval,
        )
    if not _ok(ours, low, high):
        return UNTESTABLE
    if kind in NULLS:
        null = NULLS[kind] if null_value is None else float(null_value)
        if not low <= paper <= high:
            return FAILS
        if low <= null <= high:
            return UNTESTABLE
        side = paper - null
    else:
        null, side = 0.0, paper
        if low <= 0 <= high:
            return UNTESTABLE
        if (low > 0) != (side > 0):
            return FAILS
    ours3 = (ours, low, high)
    if control_explains and explained_by_control(
        ours3, tuple(control), side=side, null=null, share=control_share
    ):
        return EXPLAINED
    return HOLDS


def t_interval(values, *, level: float = 0.95) -> tuple[float, float, float]:
    """Mean of the finite values and its Student-t interval at ``level`` (95%; NaN below 2
    values)."""
    v = np.asarray([float(x) for x in values], dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, math.nan
    mean = float(v.mean())
    if v.size < 2:
        return mean, math.nan, math.nan
    half = float(stats.t.ppf(0.5 + level / 2, v.size - 1) * v.std(ddof=1) / math.sqrt(v.size))
    return mean, mean - half, mean + half


def geometric_t_interval(ratios, *, level: float = 0.95) -> tuple[float, float, float]:
    """Geometric mean of positive ratios and its interval (95%) from their logarithms.

    .. math::

        \\bar\\ell = \\frac1S \\sum_s \\log r_s, \\qquad
        \\exp\\bar\\ell, \\quad
        \\exp\\!\\left(\\bar\\ell \\pm t_{0.975,\\,S-1}\\,\\frac{s_\\ell}{\\sqrt S}\\right)

    (:func:`t_interval` of the logs, exponentiated): never below 0, and symmetric in a ratio
    and its inverse. Equal ratios give that ratio with a zero-width interval, exactly (no
    log and exp round trip to move it by an ulp). NaN when there are none; a NaN interval
    below 2 ratios.

    Parameters
    ----------
    ratios : sequence of float
        Per-scene ratios, each finite and > 0.
    level : float, keyword-only
        The interval's level (the quantile :math:`t_{(1+\\gamma)/2,\\,S-1}`).

    Raises
    ------
    ValueError
        If a ratio is not finite or not positive (it has no logarithm).
    """
    r = np.asarray([float(x) for x in ratios], dtype=np.float64)
    bad = r[~(np.isfinite(r) & (r > 0))]
    if bad.size:
        raise ValueError(f"ratio {bad[0]!r} has no logarithm; every ratio must be finite and > 0")
    if r.size >= 2 and np.all(r == r[0]):
        return float(r[0]), float(r[0]), float(r[0])
    mean, low, high = t_interval(np.log(r), level=level)
    return math.exp(mean), math.exp(low), math.exp(high)


# ------------------------------------------------------------------------------ statistics


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
    ``denominator`` (:func:`geometric_t_interval`).

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


def _estimate(statistic: dict, inputs: ClaimInputs, level: float = 0.95) -> Estimate:
    settings = {k: v for k, v in statistic.items() if k != "name"}
    return STATISTICS[statistic["name"]].compute(inputs, level=level, **settings)


# ------------------------------------------------------------------------------ the file


@dataclass(frozen=True)
class Claims:
    """A validated claims file.

    Attributes
    ----------
    claims : tuple of dict
        One per claim, in the table's order (the keys of ``claims.schema.yaml``).
    rules : dict
        Each kind's verdict rule, in words.
    intervals : str
        How the intervals are made, in words.
    path : str
        The file read.
    sha256 : str
        The SHA-256 of the bytes the claims were read from.
    """

    claims: tuple
    rules: dict
    intervals: str
    path: str
    sha256: str

    def caption(self) -> str:
        """The rules of each kind of claim and how the intervals are made, from the file's
        ``rules`` and ``intervals``, as the claims table's caption states them."""
        return " ".join(
            ["Verdicts, by kind of claim:", *(self.rules[k] for k in KINDS), self.intervals]
        )


@lru_cache(maxsize=1)
def _validator():
    import jsonschema
    import yaml

    schema = yaml.safe_load(SCHEMA_PATH.read_text(encoding="utf-8"))
    return jsonschema.validators.validator_for(schema)(schema)


def _key(path, data) -> str:
    """A dotted key, claims named by index and id: ``claims[7] (glass_ratio).paper``."""
    parts, node = [], data
    for p in path:
        if isinstance(p, int):
            name = node[p].get("id") if isinstance(node[p], dict) else None
            index = f"[{p}]" + (f" ({name})" if isinstance(name, str) else "")
            if parts:
                parts[-1] += index
            else:
                parts.append(index)
        else:
            parts.append(str(p))
        node = node[p]
    return ".".join(parts) if parts else "(top level)"


def _one_line(text: str, limit: int = 200) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _check_claim(index: int, claim: dict, seen: dict) -> tuple[list, str] | None:
    """The first rule across keys ``claim`` breaks: ``(key path, problem)``, or None."""
    kind, paper, rule = claim["kind"], claim["paper"], claim["rule"]
    where = ["claims", index]
    if claim["id"] in seen:
        return where + ["id"], f"{claim['id']!r} is also the id of claims[{seen[claim['id']]}]"
    seen[claim["id"]] = index
    if not math.isfinite(paper):
        return where + ["paper"], f"{paper!r} is not a finite number"
    if kind in NULLS:
        if "null_value" not in rule:
            return where + ["rule"], (
                f"a {kind} claim needs null_value, the no-effect value its interval must "
                f"exclude ({NULLS[kind]:g} for a {kind})"
            )
        if not math.isfinite(rule["null_value"]):
            return where + ["rule", "null_value"], f"{rule['null_value']!r} is not finite"
    elif "null_value" in rule:
        return where + ["rule", "null_value"], (
            f"a {kind} claim has no null_value (its rule is fixed); remove it"
        )
    if kind == "ratio" and not (paper > 0 and rule["null_value"] > 0):
        return where + ["paper"], "a ratio claim's paper value and null_value must be > 0"
    if kind == "direction" and paper == 0:
        return where + ["paper"], "a direction claim's paper value must be non-zero (its sign)"
    if kind == "tolerance" and paper <= 0:
        return where + ["paper"], "a tolerance claim's paper value (the tolerance) must be > 0"
    margin = rule.get("equivalence_margin")
    if margin is not None:
        if kind != "level":
            return where + ["rule", "equivalence_margin"], (
                f"a {kind} claim has no equivalence_margin"
                + (" (its margin is its tolerance, paper)" if kind == "tolerance" else "")
                + "; remove it"
            )
        if not (math.isfinite(margin) and margin > 0):
            return where + ["rule", "equivalence_margin"], f"{margin!r} must be finite and > 0"
        if claim["control"] is not None and rule.get("control_explains", True):
            return where + ["rule"], (
                "an equivalence claim's control is shown for context; set control_explains: false"
            )
    elif kind == "ratio" and paper == rule["null_value"]:
        return where + ["paper"], (
            f"the paper's value {paper:g} is the null, which a ratio claim's interval must "
            "exclude, so it could never hold; equivalence margins are for level claims"
        )
    elif kind == "level" and paper == rule["null_value"]:
        return where + ["rule"], (
            f"the paper's value {paper:g} is the null, which an interval that must exclude "
            "the null can never confirm; give equivalence_margin, the largest departure "
            "from it that still counts as the claim"
        )
    share = rule.get("control_share")
    if share is not None:
        if not rule.get("control_explains", True) or claim["control"] is None:
            return where + ["rule", "control_share"], (
                "control_share needs a control that can explain the claim "
                "(control_explains: true); remove it"
            )
        if kind == "tolerance":
            return where + ["rule", "control_share"], (
                "a tolerance claim's control is shown for context; remove it"
            )
    parts = [("statistic", claim["statistic"])]
    if claim["control"] is not None:
        parts.append(("control", claim["control"]["statistic"]))
        if claim["control"]["statistic"] == claim["statistic"]:
            return where + ["control", "statistic"], "the control is the claim's own statistic"
    for part, statistic in parts:
        at = where + ([part] if part == "statistic" else [part, "statistic"])
        name = statistic["name"]
        if name not in STATISTICS:
            return at + ["name"], (
                f"unknown statistic {name!r}; use one of {', '.join(STATISTICS)}"
            )
        spec = STATISTICS[name]
        settings = {k: v for k, v in statistic.items() if k != "name"}
        for key in spec.settings:
            if key not in settings:
                return at, f"statistic {name!r} needs the setting {key!r}"
        for key, value in settings.items():
            if key not in spec.settings:
                return at + [key], (
                    f"statistic {name!r} has no setting {key!r}; its settings: "
                    f"{', '.join(spec.settings)}"
                )
            allowed = spec.settings[key]()
            if value not in allowed:
                return at + [key], f"{value!r} is not allowed; use one of {', '.join(allowed)}"
        problem = spec.check(settings) if spec.check else None
        if problem:
            return at, problem
    return None


def load_claims(path=None) -> Claims:
    """Read and validate a claims file.

    Parameters
    ----------
    path : str or path-like, optional
        The file (default :data:`CLAIMS_PATH`, the paper's claims).

    Raises
    ------
    ClaimsError
        One line naming the file, the key and the problem, when the file is missing, not
        YAML, or breaks ``claims.schema.yaml`` or a rule across keys (unique ids, a level or
        ratio claim's null_value, an equivalence_margin where the paper's value is the null
        and only on level claims, control_share only where a control can explain the claim,
        a known statistic with its settings).
    """
    path = Path(CLAIMS_PATH if path is None else path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise ClaimsError(
            f"claims file '{path}' cannot be read: {err.strerror}; restore it "
            "(git checkout the package's statistics/claims.yaml) or pass an existing file"
        ) from None
    data = load_yaml(path, "claims file", error=ClaimsError)
    if raw != path.read_bytes():
        raise ClaimsError(f"claims file '{path}' changed while it was read; run again")

    def fail(key_path, problem):
        raise ClaimsError(f"{path}: {_key(key_path, data)}: {_one_line(problem)}; fix that key")

    import jsonschema

    error = jsonschema.exceptions.best_match(_validator().iter_errors(data))
    if error is not None:
        fail(list(error.absolute_path), error.message)
    seen: dict = {}
    for index, claim in enumerate(data["claims"]):
        problem = _check_claim(index, claim, seen)
        if problem:
            fail(*problem)
    return Claims(
        claims=tuple(data["claims"]),
        rules=dict(data["rules"]),
        intervals=data["intervals"],
        path=str(path),
        sha256=hashlib.sha256(raw).hexdigest(),
    )


def claims_digest(path=None) -> str:
    """SHA-256 of a claims file's bytes (default :data:`CLAIMS_PATH`), without validating
    it: the claims job's rerun trigger."""
    return hashlib.sha256(Path(CLAIMS_PATH if path is None else path).read_bytes()).hexdigest()


# ------------------------------------------------------------------------------ the table


def _tost_note(claim: dict, tost: Estimate) -> str:
    """The equivalence test's 90% interval and margin, for the row's note."""
    paper = float(claim["paper"])
    if claim["kind"] == "tolerance":
        centre, margin = 0.0, paper
    else:
        centre, margin = paper, float(claim["rule"]["equivalence_margin"])
    if not _ok(tost.low, tost.high):
        return f"equivalence within {centre:g} +- {margin:g} needs an interval"
    return (
        f"equivalence (two one-sided tests at 5%): 90% interval [{tost.low:.3g}, "
        f"{tost.high:.3g}] against {centre:g} +- {margin:g}"
    )


def _claim_row(claim: dict, inputs: ClaimInputs, *, moments: bool) -> dict:
    ours = _estimate(claim["statistic"], inputs)
    control = claim["control"]
    theirs = _estimate(control["statistic"], inputs) if control else Estimate(*_NAN3)
    label = ""
    if control:
        label = control.get("label_moments", control["label"]) if moments else control["label"]
    rule = claim["rule"]
    notes = [ours.note, f"control: {theirs.note}" if theirs.note else ""]
    tost = None
    if claim["kind"] == "tolerance" or "equivalence_margin" in rule:
        tost = _estimate(claim["statistic"], inputs, level=0.90)
        notes.append(_tost_note(claim, tost))
    return {
        "id": claim["id"],
        "claim": claim["text"],
        "section": claim["section"],
        "kind": claim["kind"],
        "paper": claim["paper"],
        "null": rule.get("null_value", math.nan),
        "ours": ours.value,
        "ours_low": ours.low,
        "ours_high": ours.high,
        "control": label,
        "control_value": theirs.value,
        "control_low": theirs.low,
        "control_high": theirs.high,
        "verdict": verdict(
            claim["kind"],
            claim["paper"],
            ours.value,
            ours.low,
            ours.high,
            theirs[:3],
            control_explains=rule.get("control_explains", True),
            null_value=rule.get("null_value"),
            equivalence_margin=rule.get("equivalence_margin"),
            equivalence_interval=None if tost is None else (tost.low, tost.high),
            control_share=rule.get("control_share"),
        ),
        "note": "; ".join(n for n in notes if n),
    }


def claims_table(
    rows: list[dict],
    *,
    sweep: list[dict] | None = None,
    curve: list[dict] | None = None,
    intervention: list[dict] | None = None,
    claims: Claims | None = None,
) -> list[dict]:
    """The claims of the paper against this run (columns :data:`CLAIMS_COLUMNS`), one row
    per claim of ``claims`` in its order.

    Parameters
    ----------
    rows : list of dict
        Every scene's correlation rows at the main SPP.
    sweep : list of dict, optional
        Table 2 rows (``spp``, ``rho_all``).
    curve : list of dict, optional
        Every scene's seed-subset curve rows (:func:`stereovar.statistics.rows.seed_curve_rows`).
    intervention : list of dict, optional
        Every scene's intervention rows (``cost``, ``metric``, ``region``, ``condition``,
        ``value`` and optionally ``source``: ``render`` or ``sensor``).
    claims : Claims, keyword-only, optional
        The claims (default :func:`load_claims` of the paper's).
    """
    claims = load_claims() if claims is None else claims
    inputs = ClaimInputs(list(rows), list(sweep or []), list(curve or []), list(intervention or []))
    from ..estimators import reads_moments

    moments = any(reads_moments(r.get("estimator")) for r in rows)
    return [_claim_row(c, inputs, moments=moments) for c in claims.claims]
