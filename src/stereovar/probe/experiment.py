"""The probe experiment: scene folds, training frames and the counterfactual test of one
held-out scene.

Scenes are split into ``folds`` folds in config order (scene :math:`i` in fold
:math:`i \\bmod F`); the networks of fold :math:`f` train on every other fold's scenes, so each
scene is tested only by networks that never saw it. A training frame is one seed's render of
each view (the same seed index in both views, as a data set pairs them); a test frame is one
of the first ``test_frames`` seed indices of a held-out scene, turned into every counterfactual
input (:mod:`stereovar.probe.inputs`) and scored by every network on the left view's valid
set :math:`\\Omega` (paper Sec. 2.2) split into regions.

Importing this module pulls in numpy and PyTorch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..seeding import derive_seed
from ..statistics.bootstrap import tile_labels
from ..statistics.regions import region_masks, valid_set
from ..transforms.sensor import DEFAULT_GAIN, DEFAULT_READ_NOISE, camera_noise
from .inputs import LEFT_KEPT, TEST_INPUTS, counterfactual_pair, network_input
from .network import border, dense_features, wta_from_features
from .scoring import SUMS, tile_sums
from .training import TrainingFrame

__all__ = [
    "TestSettings",
    "fold_scenes",
    "scored_disparity",
    "test_scene",
    "training_frames",
]


@dataclass(frozen=True)
class TestSettings:
    """``probe`` test options: seed indices tested per scene, disparities scored
    (:math:`0..D`), the residual block and seed of :math:`\\Pi`, the conflict shift :math:`k`,
    the bootstrap tile, the camera of the ``camera`` input and the seed of its draws."""

    test_frames: int = 2
    max_disparity: int = 20
    block: int = 16
    shuffle_seed: int = 0
    conflict_shift: int = 3
    tile: int = 16
    gain: float = DEFAULT_GAIN
    read_noise: float = DEFAULT_READ_NOISE
    seed: int = 0
    inputs: tuple = TEST_INPUTS


def fold_scenes(scenes, folds: int) -> list[tuple[list[str], list[str]]]:
    """``(training scenes, held-out scenes)`` of each fold.

    Raises
    ------
    ValueError
        Fewer than 2 folds, or more folds than scenes.

    Examples
    --------
    >>> fold_scenes(["a", "b", "c"], 2)
    [(['b'], ['a', 'c']), (['a', 'c'], ['b'])]
    """
    scenes = list(scenes)
    folds = int(folds)
    if folds < 2 or folds > len(scenes):
        raise ValueError(
            f"probe.folds is {folds} with {len(scenes)} scenes; cross-validation needs "
            "2 <= folds <= scenes (add scenes or frames, or lower probe.folds)"
        )
    held = [[s for i, s in enumerate(scenes) if i % folds == f] for f in range(folds)]
    return [([s for s in scenes if s not in held[f]], held[f]) for f in range(folds)]


def scored_disparity(ground_truth_left, *, sign: int) -> np.ndarray:
    """The left view's disparity on :math:`\\Omega` (paper Sec. 2.2), NaN elsewhere."""
    d = np.asarray(ground_truth_left["disparity"], dtype=np.float64)
    omega = valid_set(d, sign=sign, valid=np.asarray(ground_truth_left["valid"]))
    return np.where(omega, d, np.nan)


def training_frames(left, right, ground_truth_left, *, sign: int) -> list[TrainingFrame]:
    """One :class:`~stereovar.probe.training.TrainingFrame` per seed index of a scene.

    Parameters
    ----------
    left, right : numpy.ndarray, shape (N, H, W, 3)
        The scene's renders of each view, seed index first.
    ground_truth_left : mapping
        ``disparity`` and ``valid`` of the left view.
    sign : int, keyword-only
    """
    if np.shape(left) != np.shape(right):
        raise ValueError(f"left and right renders differ: {np.shape(left)} vs {np.shape(right)}")
    d = scored_disparity(ground_truth_left, sign=sign).astype(np.float32)
    return [
        TrainingFrame(network_input(l_), network_input(r_), d, int(sign))
        for l_, r_ in zip(left, right, strict=True)
    ]


def _camera_residual(mean, scene, view, frame, settings: TestSettings) -> np.ndarray:
    seed = derive_seed("probe-camera", settings.seed, scene, view, frame)
    noisy = camera_noise(mean, gain=settings.gain, read_noise=settings.read_noise, rng_seed=seed)
    return noisy.astype(np.float64) - mean


def test_scene(
    networks: dict,
    left,
    right,
    ground_truth_left,
    *,
    scene: str,
    sign: int,
    regions,
    settings: TestSettings,
) -> list[dict]:
    """Tile sums of every network on every test input of one held-out scene.

    Parameters
    ----------
    networks : dict
        ``(training condition, training seed) -> MatchingNet``.
    left, right : numpy.ndarray, shape (N, H, W, 3)
        The scene's renders of each view (N >= 2: the seed mean is taken over all of them).
    ground_truth_left : mapping
        ``disparity``, ``valid`` and ``glass`` of the left view.
    scene : str, keyword-only
    sign : int, keyword-only
    regions : sequence of str, keyword-only
        Regions of :func:`stereovar.statistics.regions.region_masks`.
    settings : TestSettings, keyword-only

    Returns
    -------
    list of dict
        One per (network, test input, region, tile): ``network``, ``train_seed``,
        ``test_input``, ``region``, ``scene``, ``tile`` and the sums of
        :func:`stereovar.probe.scoring.tile_sums` pooled over the test frames.
    """
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    if left.shape != right.shape or left.ndim != 4 or left.shape[0] < 2:
        raise ValueError(
            f"need (N >= 2, H, W, 3) renders of both views, got {left.shape} and {right.shape}"
        )
    n_frames = min(int(settings.test_frames), left.shape[0])
    mean_l, mean_r = left.mean(axis=0), right.mean(axis=0)
    d_gt = scored_disparity(ground_truth_left, sign=sign)
    masks = region_masks(ground_truth_left, np.isfinite(d_gt), regions=tuple(regions))
    labels = tile_labels(d_gt.shape, settings.tile)
    pooled: dict = {}
    for frame in range(n_frames):
        camera = (
            _camera_residual(mean_l, scene, "left", frame, settings),
            _camera_residual(mean_r, scene, "right", frame, settings),
        )
        pairs = {}
        for test_input in settings.inputs:
            a, b = counterfactual_pair(
                test_input,
                left[frame],
                right[frame],
                mean_l,
                mean_r,
                sign=sign,
                block=settings.block,
                shuffle_seed=settings.shuffle_seed,
                conflict_shift=settings.conflict_shift,
                camera=camera,
            )
            pairs[test_input] = (network_input(a), network_input(b))
        for (network, train_seed), net in networks.items():
            kept = None  # the left features shared by the inputs that keep the left render
            for test_input, (xa, xb) in pairs.items():
                if test_input in LEFT_KEPT:
                    kept = dense_features(net, xa) if kept is None else kept
                    fl = kept
                else:
                    fl = dense_features(net, xa)
                d_hat = wta_from_features(
                    fl,
                    dense_features(net, xb),
                    sign=sign,
                    max_disparity=settings.max_disparity,
                    border_px=border(net.layers, net.kernel),
                )
                for region, mask in masks.items():
                    sums = tile_sums(
                        d_hat, d_gt, mask, labels, conflict_shift=settings.conflict_shift
                    )
                    for i, tile in enumerate(sums["tile"]):
                        key = (network, train_seed, test_input, region, int(tile))
                        acc = pooled.setdefault(key, dict.fromkeys(SUMS, 0))
                        for s in SUMS:
                            acc[s] += sums[s][i].item()
    return [
        {
            "network": network,
            "train_seed": int(train_seed),
            "test_input": test_input,
            "region": region,
            "scene": scene,
            "tile": tile,
            **sums,
        }
        for (network, train_seed, test_input, region, tile), sums in pooled.items()
    ]
