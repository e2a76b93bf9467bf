"""The probe table: accuracy, end-point error, drops and differences in differences, with
intervals over test tiles and training seeds.

Each training condition :math:`c` has :math:`J` networks per fold (training seeds
:math:`j`); a held-out scene is scored by the networks of the fold that did not see it, so a
seed's network set covers every scene. On a test input :math:`t` and region, the accuracy of
seed :math:`j` pools its per-tile sums over the held-out scenes' tiles :math:`k`:

.. math::

    A_{c,t}^{(j)} = \\frac{\\sum_k h_{c,t,k}^{(j)}}{\\sum_k n_{c,t,k}^{(j)}}, \\qquad
    A_{c,t} = \\frac1J \\sum_j A_{c,t}^{(j)},

and likewise the end-point error and the share pulled to :math:`d + k`. The drop of an input
is :math:`\\Delta_{c,t} = A_{c,\\mathrm{normal}} - A_{c,t}`, and the difference in
differences against the control network (``sensor_only``) tested on the same inputs is

.. math::

    \\mathrm{DiD}_{c,t} = \\Delta_{c,t} - \\Delta_{\\mathrm{control},t}.

**Intervals** (95 %, percentile) come from a two-level bootstrap: each replicate draws the
test tiles with replacement (square tiles of ``tile`` px of every held-out scene, one draw
shared by every network and input, so comparisons are paired) and, independently per
training condition, :math:`J` training seeds with replacement; the replicate's statistic is
the mean over the drawn seeds of the tile-resampled ratio. The interval therefore holds the
spread of the test pixels and the spread of training.

Importing this module pulls in numpy and pandas.
"""

from __future__ import annotations

import numpy as np

from ..statistics.bootstrap import LEVEL, draw_counts, percentile_interval
from .inputs import TEST_INPUTS
from .scoring import SUMS

__all__ = ["CONTROL", "INTERVAL_METHOD", "TILE_COLUMNS", "probe_rows"]

CONTROL = "sensor_only"
"""The control training condition: clean images plus camera noise, no Monte Carlo structure."""

TILE_COLUMNS = (
    "tested",
    "network",
    "train_seed",
    "test_input",
    "region",
    "scene",
    "tile",
    *SUMS,
)
"""Columns of a probe test job's tile table: the condition whose renders were tested, the
training condition of the network, its training seed, the test input, the region, the scene,
the tile and the sums of :func:`stereovar.probe.scoring.tile_sums` pooled over test frames."""

INTERVAL_METHOD = (
    "95% percentile interval of a two-level bootstrap: test tiles drawn with replacement "
    "(one draw shared by every network and input, paired) and training seeds drawn with "
    "replacement per training condition"
)


def _arrays(part, seeds, inputs, tile_index) -> dict:
    """Sums of one network as arrays (J, I, K)."""
    out = {s: np.zeros((len(seeds), len(inputs), len(tile_index))) for s in SUMS}
    j = part["train_seed"].map({s: i for i, s in enumerate(seeds)}).to_numpy()
    i = part["test_input"].map({t: n for n, t in enumerate(inputs)}).to_numpy()
    k = np.array([tile_index[key] for key in zip(part["scene"], part["tile"], strict=True)])
    for s in SUMS:
        np.add.at(out[s], (j, i, k), part[s].to_numpy(dtype=np.float64))
    return out


def _ratios(sums: dict, counts: np.ndarray | None) -> dict:
    """Accuracy, EPE and pulled share per seed and input: (J, I) for the full sample, or
    (J, I, R) under the tile ``counts`` (R, K)."""
    if counts is None:
        tot = {s: sums[s].sum(axis=2) for s in SUMS}
    else:
        tot = {s: sums[s] @ counts.T for s in SUMS}
    with np.errstate(invalid="ignore", divide="ignore"):
        return {
            "accuracy": tot["hits"] / tot["n"],
            "epe": tot["abs_error"] / tot["n"],
            "pulled": tot["pulled"] / tot["n"],
        }


def _seed_mean(values: np.ndarray, weights: np.ndarray | None) -> np.ndarray:
    """Mean over training seeds: plain for (J, I), or weighted by the drawn seed counts
    ``weights`` (R, J) for (J, I, R) -> (I, R)."""
    if weights is None:
        return values.mean(axis=0)
    return np.einsum("rj,jir->ir", weights, values) / weights.sum(axis=1)[None, :]


def _seed_draws(n_seeds: int, reps: int, rng) -> np.ndarray:
    draws = rng.integers(0, n_seeds, size=(reps, n_seeds))
    return np.stack([np.bincount(row, minlength=n_seeds) for row in draws]).astype(np.float64)


def probe_rows(
    tiles,
    *,
    control: str = CONTROL,
    reps: int = 1000,
    seed: int = 0,
    level: float = LEVEL,
) -> list[dict]:
    """The probe table's rows from the tile sums of every test job.

    Parameters
    ----------
    tiles : pandas.DataFrame
        Columns :data:`TILE_COLUMNS`.
    control : str, keyword-only
        The control training condition; its networks must be tested on every condition's
        inputs.
    reps, seed : int, keyword-only
        Bootstrap replicates and seed.
    level : float, keyword-only

    Returns
    -------
    list of dict
        One per (training condition, test input, region), conditions in their order of
        appearance: ``training``, ``test_input``, ``region``, ``accuracy`` [``_low``,
        ``_high``], ``epe`` [...], ``drop`` [...] (from ``normal``), ``did`` [...] against the
        control (NaN for the control), ``pulled`` [...] and ``pulled_vs_control`` [...] (the
        conflict input only), ``control_accuracy``, ``n_pixels`` (scored pixels per seed),
        ``n_tiles``, ``train_seeds``, ``control_seeds``.
    """
    missing = [c for c in TILE_COLUMNS if c not in tiles.columns]
    if missing:
        raise ValueError(f"probe tile table lacks columns {missing}")
    rows: list[dict] = []
    conditions = list(dict.fromkeys(tiles["tested"]))
    inputs = [t for t in TEST_INPUTS if t in set(tiles["test_input"])]
    if "normal" not in inputs:
        raise ValueError("the probe tile table has no 'normal' test input to take drops from")
    ni = inputs.index("normal")
    for c_index, tested in enumerate(conditions):
        for region in dict.fromkeys(tiles.loc[tiles["tested"] == tested, "region"]):
            part = tiles[(tiles["tested"] == tested) & (tiles["region"] == region)]
            keys = list(dict.fromkeys(zip(part["scene"], part["tile"], strict=True)))
            tile_index = {key: i for i, key in enumerate(keys)}
            nets = {}
            for network in (tested, control):
                sub = part[part["network"] == network]
                if sub.empty:
                    raise ValueError(
                        f"probe tiles of {tested!r}, region {region!r}, have no network "
                        f"trained on {network!r}; test the control on every condition's inputs"
                    )
                seeds = sorted(set(sub["train_seed"]))
                nets[network] = (seeds, _arrays(sub, seeds, inputs, tile_index))
            rng = np.random.default_rng([int(seed), c_index, len(rows)])
            counts = draw_counts(len(keys), int(reps), rng.integers(2**32))
            point, reps_of = {}, {}
            for network, (seeds, sums) in nets.items():
                weights = _seed_draws(len(seeds), int(reps), rng)
                point[network] = {k: _seed_mean(v, None) for k, v in _ratios(sums, None).items()}
                reps_of[network] = {
                    k: _seed_mean(v, weights) for k, v in _ratios(sums, counts).items()
                }
            own, ctl = tested, control
            n_pixels = nets[own][1]["n"][0].sum(axis=1)
            for i, test_input in enumerate(inputs):
                def stat(quantity, network=own, i=i, point=point, reps_of=reps_of):
                    return point[network][quantity][i], reps_of[network][quantity][i]

                acc, acc_r = stat("accuracy")
                epe, epe_r = stat("epe")
                drop = point[own]["accuracy"][ni] - acc
                drop_r = reps_of[own]["accuracy"][ni] - acc_r
                row = {
                    "training": own,
                    "test_input": test_input,
                    "region": region,
                    **_with_interval("accuracy", acc, acc_r, level),
                    **_with_interval("epe", epe, epe_r, level),
                    **_with_interval("drop", drop, drop_r, level),
                }
                c_acc, c_acc_r = stat("accuracy", ctl)
                if own == ctl:
                    row.update(_with_interval("did", np.nan, None, level))
                else:
                    c_drop = point[ctl]["accuracy"][ni] - c_acc
                    c_drop_r = reps_of[ctl]["accuracy"][ni] - c_acc_r
                    row.update(_with_interval("did", drop - c_drop, drop_r - c_drop_r, level))
                if test_input == "conflict":
                    pulled, pulled_r = stat("pulled")
                    c_pulled, c_pulled_r = stat("pulled", ctl)
                    row.update(_with_interval("pulled", pulled, pulled_r, level))
                    if own == ctl:
                        row.update(_with_interval("pulled_vs_control", np.nan, None, level))
                    else:
                        row.update(
                            _with_interval(
                                "pulled_vs_control",
                                pulled - c_pulled,
                                pulled_r - c_pulled_r,
                                level,
                            )
                        )
                else:
                    row.update(_with_interval("pulled", np.nan, None, level))
                    row.update(_with_interval("pulled_vs_control", np.nan, None, level))
                row.update(
                    control_accuracy=float(c_acc),
                    n_pixels=int(n_pixels[i]),
                    n_tiles=len(keys),
                    train_seeds=len(nets[own][0]),
                    control_seeds=len(nets[ctl][0]),
                )
                rows.append(row)
    return rows


def _with_interval(name: str, value, replicates, level: float) -> dict:
    low, high = (np.nan, np.nan) if replicates is None else percentile_interval(replicates, level)
    return {name: float(value), f"{name}_low": low, f"{name}_high": high}
