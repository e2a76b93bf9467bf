"""The probe table: accuracy, end-point error, drops and differences in differences, with
intervals over training seeds and test tiles.

Each training condition :math:`c` of an architecture has :math:`J` networks per fold
(training seeds :math:`j`), each with a **cue-blind twin** trained on the same renders with
the right view's residual drawn again at every step, and the ``sensor_only`` networks as a
second control. A held-out scene is scored by the networks of the fold that did not see it,
so a seed's network set covers every scene. On a test input :math:`t` and region, the
accuracy of seed :math:`j` pools its per-tile sums over the held-out scenes' tiles :math:`k`:

.. math::

    A_{t}^{(j)} = \\frac{\\sum_k h_{t,k}^{(j)}}{\\sum_k n_{t,k}^{(j)}}, \\qquad
    A_{t} = \\frac1J \\sum_j A_{t}^{(j)},

and likewise the end-point error, the share pulled to :math:`d + k` and the share predicted
at :math:`\\hat d = 0`. The drop of an input is :math:`\\Delta_t^{(j)} = A_{\\mathrm{normal}}^{(j)}
- A_t^{(j)}`, and the difference in differences against the twin of the same seed is

.. math::

    \\mathrm{DiD}_t^{(j)} = \\Delta_{t}^{(j)}(\\mathrm{main}) - \\Delta_{t}^{(j)}(\\mathrm{twin}),
    \\qquad \\mathrm{DiD}_t = \\frac1J \\sum_j \\mathrm{DiD}_t^{(j)};

``did_sensor`` takes the ``sensor_only`` network of seed :math:`j` in the twin's place.

**Intervals** (:func:`ratio_contrast`): a t-interval over training seeds with the test tiles'
sampling variance added. Every quantity above is a contrast :math:`C^{(j)} = \\sum_m w_m
A_m^{(j)}` of pooled ratios. Its variance is

.. math::

    \\widehat{\\mathrm{Var}}\\,\\bar C = \\frac{s_j^2}{J} + \\hat V_{\\mathrm{tile}},

with :math:`s_j^2` the variance of :math:`C^{(j)}` over seeds (training spread and each
network's own per-pixel errors) and :math:`\\hat V_{\\mathrm{tile}}` the part of the tile
sampling variance that the seeds share (the same test tiles score every network): from the
linearised tile residuals :math:`z_k^{(j)} = \\sum_m w_m (h_{mk}^{(j)} - A_m^{(j)} n_{mk}^{(j)})
/ N_m^{(j)}`, :math:`V_j = \\tfrac{K}{K-1} \\sum_k (z_k^{(j)})^2` and :math:`V_{\\bar{}} =
\\tfrac{K}{K-1} \\sum_k \\bar z_k^2`,

.. math::

    \\hat V_{\\mathrm{tile}}
        = \\max\\Bigl(0,\\ \\frac{J V_{\\bar{}} - \\overline{V_j}}{J - 1}\\Bigr),

which removes the per-seed part already in :math:`s_j^2`. The interval is :math:`\\bar C \\pm
t_{(1+\\mathrm{level})/2,\\,\\nu} \\sqrt{\\widehat{\\mathrm{Var}}}` with Welch–Satterthwaite
degrees of freedom :math:`\\nu` (:math:`J - 1` for the seed part, taken at its upper-quartile
bound :data:`DF_QUANTILE` for :math:`\\nu` only; :math:`K - 1` for the tile
part). A coverage simulation (``tests/test_probe_intervals.py``: per-seed random effects,
per-tile heterogeneity, binomial hits, 3 and 10 seeds) measures 94–96 % for a 95 % interval.

Importing this module pulls in numpy; :func:`probe_rows` pandas, the intervals scipy.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

import numpy as np

from ..statistics.bootstrap import LEVEL
from .inputs import TEST_INPUTS
from .scoring import SUMS

__all__ = [
    "CONTROL",
    "INTERVAL_METHOD",
    "MAIN",
    "POWER",
    "PRIMARY_ARCHITECTURE",
    "TILE_COLUMNS",
    "TWIN",
    "detectable",
    "planted_factor",
    "probe_rows",
    "ratio_contrast",
    "t_quantile",
]

CONTROL = "sensor_only"
"""The second control condition: clean images plus camera noise, no Monte Carlo structure."""

MAIN, TWIN = "main", "twin"
"""The two variants of a condition's networks: trained on the renders, and the cue-blind twin
(same renders, right residual drawn again at every step)."""

PRIMARY_ARCHITECTURE = "mccnn"
"""The architecture whose verdict the top-level verdict keys and the claims row report."""

DF_QUANTILE = 0.25
"""The seed variance enters the Welch–Satterthwaite degrees of freedom at its upper-quartile
bound, :math:`s_j^2 (J-1)/\\chi^2_{0.25,J-1}`: with 3 seeds the plain estimate lets the
degrees of freedom grow when :math:`s_j^2` is small by chance, and the interval covers 92 %;
with the bound it covers 94–96 % (``tests/test_probe_intervals.py``)."""

POWER = 0.80
"""Power of the smallest detectable DiD (:func:`detectable`)."""

PLANTED = re.compile(r"^planted_x(?P<factor>\d+(?:\.\d*)?(?:e[-+]?\d+)?)$")

TILE_COLUMNS = (
    "tested",
    "architecture",
    "network",
    "variant",
    "train_seed",
    "test_input",
    "region",
    "scene",
    "tile",
    *SUMS,
)
"""Columns of a probe test job's tile table: the condition whose renders were tested, the
network architecture, the training condition of the network, its variant (:data:`MAIN` or
:data:`TWIN`), its training seed, the test input, the region, the scene, the tile and the sums
of :func:`stereovar.probe.scoring.tile_sums` pooled over test frames."""

INTERVAL_METHOD = (
    "95% t-intervals over training seeds (each seed's network paired with its cue-blind twin "
    "and the sensor_only network of the same seed) with the shared test-tile sampling variance "
    "added (linearised over tiles) and Welch-Satterthwaite degrees of freedom (the seed "
    "variance at its upper-quartile bound); coverage 94-96% in simulation with 3 and 10 seeds"
)

_RATIOS = {"accuracy": "hits", "epe": "abs_error", "pulled": "pulled", "zero": "zero"}


def planted_factor(condition: str) -> float:
    """The planted strength factor of a ``planted_x{factor:g}`` condition, NaN for others.

    Examples
    --------
    >>> planted_factor("planted_x2"), planted_factor("planted_x0.5"), planted_factor("none")
    (2.0, 0.5, nan)
    """
    m = PLANTED.match(str(condition))
    return float(m["factor"]) if m else math.nan


def t_quantile(p, df):
    """Student's t quantile, NaN where ``df`` is not finite and positive."""
    from scipy.stats import t

    df = np.asarray(df, dtype=np.float64)
    ok = np.isfinite(df) & (df > 0)
    return np.where(ok, t.ppf(p, np.where(ok, df, 1.0)), np.nan)


def detectable(se, df, *, level: float = LEVEL, power: float = POWER):
    """The smallest effect a two-sided test at ``level`` detects with probability ``power``:

    .. math::

        \\mathrm{MDE} = \\bigl(t_{(1+\\mathrm{level})/2,\\,\\nu}
            + t_{\\mathrm{power},\\,\\nu}\\bigr)\\,\\mathrm{SE}.

    Examples
    --------
    >>> round(float(detectable(1.0, 1e9)), 3)  # the normal limit, 1.960 + 0.842
    2.802
    """
    return (t_quantile((1 + level) / 2, df) + t_quantile(power, df)) * np.asarray(se)


def ratio_contrast(num, den, weights, *, level: float = LEVEL) -> dict:
    """A contrast of pooled ratios over training seeds, with its t-interval.

    Parameters
    ----------
    num, den : array_like, shape (..., J, M, K)
        Per-tile numerator (hits, summed error, ...) and pixel counts of seed :math:`j`, term
        :math:`m` (a network and test input) and tile :math:`k`; leading axes batch.
    weights : array_like, shape (M,)
        :math:`w_m`.
    level : float, keyword-only

    Returns
    -------
    dict
        ``value``, ``low``, ``high``, ``se``, ``df`` (arrays of the leading shape): the mean
        over seeds of :math:`C^{(j)} = \\sum_m w_m A_m^{(j)}` and its interval (module text).
        One seed: the tile variance alone, :math:`K - 1` degrees of freedom (no training
        spread). Zero variance: the interval is the point.

    Examples
    --------
    Two seeds, one term, two tiles: the seed accuracies 0.5 and 0.7; the tiles agree within
    each seed, so only the seeds' spread counts, :math:`t_{0.975,1}\\,0.1 = 1.271`:

    >>> num = np.array([[[5.0, 5.0]], [[7.0, 7.0]]])
    >>> r = ratio_contrast(num, np.full_like(num, 10.0), [1.0])
    >>> round(float(r["value"]), 3), round(float(r["se"]), 3), round(float(r["high"]), 3)
    (0.6, 0.1, 1.871)
    """
    num = np.asarray(num, dtype=np.float64)
    den = np.asarray(den, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    n_seeds, n_tiles = num.shape[-3], num.shape[-1]
    with np.errstate(invalid="ignore", divide="ignore"):
        total = den.sum(axis=-1)
        ratio = num.sum(axis=-1) / total
        per_seed = (ratio * w).sum(axis=-1)
        z = (w[:, None] * (num - ratio[..., None] * den) / total[..., None]).sum(axis=-2)
        scale = n_tiles / (n_tiles - 1) if n_tiles > 1 else math.nan
        v_seeds = scale * (z * z).sum(axis=-1)
        z_mean = z.mean(axis=-2)
        v_mean = scale * (z_mean * z_mean).sum(axis=-1)
        value = per_seed.mean(axis=-1)
        if n_seeds > 1:
            a = per_seed.var(axis=-1, ddof=1) / n_seeds
            b = np.maximum((n_seeds * v_mean - v_seeds.mean(axis=-1)) / (n_seeds - 1), 0.0)
            a_df = a * _seed_df_factor(n_seeds)
            df = (a_df + b) ** 2 / (a_df * a_df / (n_seeds - 1) + b * b / (n_tiles - 1))
        else:
            a, b = 0.0, v_mean
            df = np.full(np.shape(v_mean), n_tiles - 1.0)
        var = a + b
        se = np.sqrt(var)
        half = t_quantile((1 + level) / 2, df) * se
        half = np.where(var == 0, 0.0, half)
    return {"value": value, "low": value - half, "high": value + half, "se": se, "df": df}


def _seed_df_factor(n_seeds: int) -> float:
    """:math:`(J - 1) / \\chi^2_{0.25,\\,J-1}`: the seed variance's upper-quartile bound over its
    estimate, used for the degrees of freedom only (:func:`ratio_contrast`)."""
    from scipy.stats import chi2

    return (n_seeds - 1) / float(chi2.ppf(DF_QUANTILE, n_seeds - 1))


def _arrays(part, seeds, inputs, tile_index) -> dict:
    """Sums of one network set as arrays (J, I, K)."""
    out = {s: np.zeros((len(seeds), len(inputs), len(tile_index))) for s in SUMS}
    j = part["train_seed"].map({s: i for i, s in enumerate(seeds)}).to_numpy()
    i = part["test_input"].map({t: n for n, t in enumerate(inputs)}).to_numpy()
    k = np.array([tile_index[key] for key in zip(part["scene"], part["tile"], strict=True)])
    for s in SUMS:
        np.add.at(out[s], (j, i, k), part[s].to_numpy(dtype=np.float64))
    return out


def _contrast(arms: dict, terms: list, quantity: str, level: float) -> dict:
    """:func:`ratio_contrast` of ``terms`` [(arm, input index, weight)], seeds paired by
    training seed (those every arm of the terms has)."""
    names = list(dict.fromkeys(a for a, _, _ in terms))
    if any(arms.get(a) is None for a in names):
        return {"value": math.nan, "low": math.nan, "high": math.nan, "se": math.nan,
                "df": math.nan}
    common = sorted(set.intersection(*(set(arms[a][0]) for a in names)))
    if not common:
        return {"value": math.nan, "low": math.nan, "high": math.nan, "se": math.nan,
                "df": math.nan}
    num, den = [], []
    for arm, i, _ in terms:
        seeds, sums = arms[arm]
        js = [seeds.index(s) for s in common]
        num.append(sums[_RATIOS[quantity]][js, i])
        den.append(sums["n"][js, i])
    r = ratio_contrast(
        np.stack(num, axis=1), np.stack(den, axis=1), [w for _, _, w in terms], level=level
    )
    return {k: float(v) for k, v in r.items()}


def _put(row: dict, name: str, r: dict, *, spread: bool = False) -> None:
    row[name] = r["value"]
    row[f"{name}_low"] = r["low"]
    row[f"{name}_high"] = r["high"]
    if spread:
        row[f"{name}_se"] = r["se"]
        row[f"{name}_df"] = r["df"]


def _strength(condition: str, strengths) -> float:
    if strengths is None:
        return math.nan
    if isinstance(strengths, Mapping):
        value = strengths.get(condition)
        factor = planted_factor(condition)
        if value is None and math.isfinite(factor):
            value = strengths.get(f"{factor:g}")
        return math.nan if value is None else float(value)
    return planted_factor(condition) * float(strengths)


def _condition_order(names) -> list:
    """Conditions in order of appearance, the planted series last by factor."""
    names = list(dict.fromkeys(names))
    plain = [c for c in names if math.isnan(planted_factor(c))]
    return plain + sorted((c for c in names if c not in plain), key=planted_factor)


def probe_rows(tiles, *, strengths=None, level: float = LEVEL) -> list[dict]:
    """The probe table's rows from the tile sums of every test job.

    Parameters
    ----------
    tiles : pandas.DataFrame
        Columns :data:`TILE_COLUMNS`. For each (architecture, tested condition, fold): the
        condition's networks (variant ``main``), their twins (``twin``, absent for
        ``sensor_only``) and the ``sensor_only`` main networks, scored on the tested
        condition's renders.
    strengths : mapping or float, optional, keyword-only
        The planted cue's strength, SD of :math:`\\ln\\sigma^2`: per condition name or per
        factor (``f"{factor:g}"``), or the renders' strength that ``planted_x{factor}``
        multiplies.
    level : float, keyword-only

    Returns
    -------
    list of dict
        One per (architecture, tested, test input, region): ``architecture``, ``tested``,
        ``test_input``, ``region``, ``strength_factor``, ``strength`` (NaN unless planted),
        ``accuracy``, ``epe``, ``drop`` (from ``normal``), ``did`` (against the twin, with
        ``did_se``, ``did_df`` and ``did_mde``, the smallest DiD detectable at 80 % power),
        ``did_sensor`` (against the ``sensor_only`` network, with ``_se``, ``_df``),
        ``pulled`` and ``pulled_vs_twin`` (the conflict input), ``zero`` (share of
        predictions at 0), ``twin_accuracy``, ``sensor_accuracy`` (each with ``_low`` and
        ``_high``), ``n_pixels`` (scored pixels per seed), ``n_tiles``, ``train_seeds``,
        ``twin_seeds``, ``sensor_seeds``. NaN where an arm is missing.

    Raises
    ------
    ValueError
        Missing columns, no ``normal`` input, a tested condition without its main networks.
    """
    missing = [c for c in TILE_COLUMNS if c not in tiles.columns]
    if missing:
        raise ValueError(f"probe tile table lacks columns {missing}")
    inputs = [t for t in TEST_INPUTS if t in set(tiles["test_input"])]
    if "normal" not in inputs:
        raise ValueError("the probe tile table has no 'normal' test input to take drops from")
    ni = inputs.index("normal")
    rows: list[dict] = []
    for architecture in dict.fromkeys(tiles["architecture"]):
        by_arch = tiles[tiles["architecture"] == architecture]
        for tested in _condition_order(by_arch["tested"]):
            by_tested = by_arch[by_arch["tested"] == tested]
            for region in dict.fromkeys(by_tested["region"]):
                part = by_tested[by_tested["region"] == region]
                rows += _rows_of(part, architecture, tested, region, inputs, ni, strengths,
                                 level)
    return rows


def _rows_of(part, architecture, tested, region, inputs, ni, strengths, level) -> list[dict]:
    keys = list(dict.fromkeys(zip(part["scene"], part["tile"], strict=True)))
    tile_index = {key: i for i, key in enumerate(keys)}
    selectors = {
        "main": (tested, MAIN),
        "twin": (tested, TWIN),
        "sensor": (CONTROL, MAIN),
    }
    arms: dict = {}
    for arm, (network, variant) in selectors.items():
        sub = part[(part["network"] == network) & (part["variant"] == variant)]
        if sub.empty:
            arms[arm] = None
            continue
        seeds = sorted(set(sub["train_seed"]))
        arms[arm] = (seeds, _arrays(sub, seeds, inputs, tile_index))
    if arms["main"] is None:
        raise ValueError(
            f"probe tiles of {architecture!r}, {tested!r}, region {region!r}, have no main "
            f"network trained on {tested!r}"
        )
    # the control has a twin only where probe.mitigations judges it; its own networks are
    # the sensor arm either way (did_sensor is not defined for it)
    factor = planted_factor(tested)
    n_pixels = arms["main"][1]["n"][0].sum(axis=1)
    rows = []
    for i, test_input in enumerate(inputs):
        row = {
            "architecture": architecture,
            "tested": tested,
            "test_input": test_input,
            "region": region,
            "strength_factor": factor,
            "strength": _strength(tested, strengths),
        }
        _put(row, "accuracy", _contrast(arms, [("main", i, 1.0)], "accuracy", level))
        _put(row, "epe", _contrast(arms, [("main", i, 1.0)], "epe", level))
        drop = [("main", ni, 1.0), ("main", i, -1.0)]
        _put(row, "drop", _contrast(arms, drop, "accuracy", level))
        did = _contrast(arms, drop + [("twin", ni, -1.0), ("twin", i, 1.0)], "accuracy", level)
        _put(row, "did", did, spread=True)
        row["did_mde"] = float(detectable(did["se"], did["df"], level=level))
        sensor = (
            {k: math.nan for k in did}
            if tested == CONTROL
            else _contrast(
                arms, drop + [("sensor", ni, -1.0), ("sensor", i, 1.0)], "accuracy", level
            )
        )
        _put(row, "did_sensor", sensor, spread=True)
        nan = {k: math.nan for k in did}
        if test_input == "conflict":
            _put(row, "pulled", _contrast(arms, [("main", i, 1.0)], "pulled", level))
            vs_twin = [("main", i, 1.0), ("twin", i, -1.0)]
            _put(row, "pulled_vs_twin", _contrast(arms, vs_twin, "pulled", level))
        else:
            _put(row, "pulled", nan)
            _put(row, "pulled_vs_twin", nan)
        has_zero = "zero" in SUMS
        _put(row, "zero",
             _contrast(arms, [("main", i, 1.0)], "zero", level) if has_zero else nan)
        _put(row, "twin_accuracy", _contrast(arms, [("twin", i, 1.0)], "accuracy", level))
        _put(row, "sensor_accuracy", _contrast(arms, [("sensor", i, 1.0)], "accuracy", level))
        row.update(
            n_pixels=int(n_pixels[i]),
            n_tiles=len(keys),
            train_seeds=len(arms["main"][0]),
            twin_seeds=len(arms["twin"][0]) if arms["twin"] else 0,
            sensor_seeds=len(arms["sensor"][0]) if arms["sensor"] else 0,
        )
        rows.append(row)
    return rows
