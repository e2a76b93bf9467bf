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

from ..calibration.synthesis import camera_law, channel_correlation
from ..errors import ConfigError
from ..seeding import derive_seed
from ..statistics.bootstrap import tile_labels
from ..statistics.regions import region_masks, valid_set
from .folds import fold_scenes
from .inputs import (
    STRATA,
    TEST_INPUTS,
    camera_residual,
    counterfactual_pair,
    network_input,
    noise_scale,
    reference_mean,
    stratified_shuffle,
)
from .planted import planted_views
from .scoring import SUMS, tile_sums
from .training import TrainingFrame

__all__ = [
    "MIN_RENDERS",
    "TWIN_POOL",
    "TestSettings",
    "channel_correlation",
    "check_renders",
    "fold_scenes",
    "grey_stack",
    "planted_stacks",
    "scene_law",
    "scored_disparity",
    "split_validation",
    "test_pairs",
    "test_scene",
    "training_frames",
    "validation_band",
]


MIN_RENDERS = 4
"""Renders per view the probe needs: its reference mean of the other :math:`N - 1` renders
keeps :math:`1/(N - 1)` of the aligned noise variance in every shuffled input (a half at
:math:`N = 3`, all of it at :math:`N = 2`)."""

TWIN_POOL = 16
"""Stratified shuffles of each training frame's right residual that a twin picks from."""


@dataclass(frozen=True)
class TestSettings:
    """``probe`` test options: seed indices tested per scene, disparities scored
    (:math:`0..D`), the intensity strata and seed of the residual shuffle, the conflict shift
    :math:`k`, the bootstrap tile and the seed of the camera-law draws."""

    test_frames: int = 2
    max_disparity: int = 20
    strata: int = STRATA
    shuffle_seed: int = 0
    conflict_shift: int = 3
    tile: int = 16
    seed: int = 0
    inputs: tuple = TEST_INPUTS


def scored_disparity(ground_truth_left, *, sign: int) -> np.ndarray:
    """The left view's disparity on :math:`\\Omega` (paper Sec. 2.2), NaN elsewhere."""
    d = np.asarray(ground_truth_left["disparity"], dtype=np.float64)
    omega = valid_set(d, sign=sign, valid=np.asarray(ground_truth_left["valid"]))
    return np.where(omega, d, np.nan)


def check_renders(n: int, what: str) -> None:
    """One line when ``n`` renders per view are too few for the probe's shuffles.

    Raises
    ------
    ConfigError
        ``n`` below :data:`MIN_RENDERS`, naming ``what`` set it and the fix.

    Examples
    --------
    >>> check_renders(8, "render.n_seeds")
    >>> check_renders(3, "render.n_seeds")
    Traceback (most recent call last):
    ...
    stereovar.errors.ConfigError: render.n_seeds is 3: the probe needs at least 4 renders ...
    """
    n = int(n)
    if n < MIN_RENDERS:
        share = f"{100 / (n - 1):.0f}%" if n > 1 else "all of it"
        raise ConfigError(
            f"{what} is {n}: the probe needs at least {MIN_RENDERS} renders per view (its "
            "reference mean of the other N - 1 renders keeps 1/(N - 1) of the aligned noise "
            f"in every shuffled input, {share} at N = {n}); render more seeds per view"
        )


def grey_stack(stack) -> np.ndarray:
    """The RGB mean of a stack of renders (N, H, W, 3) -> (N, H, W), float64."""
    a = np.asarray(stack, dtype=np.float64)
    return a.mean(axis=-1) if a.ndim == 4 else a


def training_frames(
    left,
    right,
    ground_truth_left,
    *,
    sign: int,
    twin: bool = False,
    strata: int = STRATA,
    pool: int = TWIN_POOL,
) -> list[TrainingFrame]:
    """One :class:`~stereovar.probe.training.TrainingFrame` per seed index of a scene.

    A twin's frame (``twin=True``) redraws its right view at every use: the seed-``n``
    render's residual against the other renders' mean, shuffled within intensity strata
    (:func:`~stereovar.probe.inputs.stratified_shuffle`),

    .. math::

        I_R' = \\bar I_R^{(-n)}
            + c\\,\\Pi_{\\text{strata}}\\bigl(I_R^{(n)} - \\bar I_R^{(-n)}\\bigr),

    with :math:`c` the :func:`~stereovar.probe.inputs.noise_scale` of a reference of
    :math:`N - 1` renders (the input keeps one render's noise variance), so the twin sees the
    same images and the same noise law with no cross-view alignment.

    Parameters
    ----------
    left, right : numpy.ndarray, shape (N, H, W, 3)
        The scene's renders of each view, seed index first.
    ground_truth_left : mapping
        ``disparity`` and ``valid`` of the left view.
    sign : int, keyword-only
    twin : bool, keyword-only
    strata : int, keyword-only
        Intensity strata of the shuffle.
    pool : int, keyword-only
        Shuffles drawn per frame for the twin (:data:`TWIN_POOL`).
    """
    if np.shape(left) != np.shape(right):
        raise ValueError(f"left and right renders differ: {np.shape(left)} vs {np.shape(right)}")
    d = scored_disparity(ground_truth_left, sign=sign).astype(np.float32)
    grey_right = grey_stack(right) if twin else None
    frames = []
    for n, (l_, r_) in enumerate(zip(left, right, strict=True)):
        redraw = None
        if twin:
            redraw = _twin_redraw(grey_right, n, int(strata), int(pool))
        frames.append(
            TrainingFrame(network_input(l_), network_input(r_), d, int(sign), redraw=redraw)
        )
    return frames


def _twin_redraw(grey_right: np.ndarray, n: int, strata: int, pool: int):
    """The redraw of frame ``n``'s right input: one of ``pool`` stratified shuffles of its
    residual, drawn once (from a generator of the frame's own) and picked at random at each
    use, so a step pays an index, not a shuffle of the whole frame."""
    mean = reference_mean(grey_right[..., None], n)[..., 0]
    scale = noise_scale(grey_right.shape[0] - 1, residual=True)
    residual = scale * (grey_right[n] - mean)
    rng = np.random.default_rng([int(n), int(strata), 35])
    inputs = np.stack(
        [
            network_input(mean + stratified_shuffle(residual, mean, rng=rng, strata=strata))
            for _ in range(int(pool))
        ]
    )

    def redraw(rng: np.random.Generator) -> np.ndarray:
        return inputs[int(rng.integers(len(inputs)))]

    return redraw


def split_validation(frames_by_scene) -> tuple[list, list]:
    """Training and validation frames: the last seed index of every scene with at least two
    is held out for the plateau of validation accuracy (:mod:`~stereovar.probe.convergence`).

    Examples
    --------
    >>> split_validation([[1, 2, 3], [4]])
    ([1, 2, 4], [3])
    """
    train, validation = [], []
    for frames in frames_by_scene:
        frames = list(frames)
        if len(frames) >= 2:
            train += frames[:-1]
            validation.append(frames[-1])
        else:
            train += frames
    return train, validation


def validation_band(frames, *, rows: int | None = 64) -> list[TrainingFrame]:
    """The middle ``rows`` rows of each validation frame (all of a frame no taller; None:
    the whole frames): a cheaper plateau check on the same held-out frames.

    Examples
    --------
    >>> f = TrainingFrame(np.zeros((10, 4)), np.zeros((10, 4)), np.ones((10, 4)), -1)
    >>> [b.left.shape for b in validation_band([f], rows=4)]
    [(4, 4)]
    """
    out = []
    for frame in frames:
        height = frame.left.shape[0]
        if rows is None or height <= int(rows):
            out.append(frame)
            continue
        top = (height - int(rows)) // 2
        band = slice(top, top + int(rows))
        redraw = frame.redraw
        out.append(
            TrainingFrame(
                frame.left[band],
                frame.right[band],
                frame.disparity[band],
                frame.sign,
                redraw=None if redraw is None else (lambda rng, r=redraw, b=band: r(rng)[b]),
            )
        )
    return out


def scene_law(left, valid=None) -> tuple[float, float]:
    """The camera law :math:`\\sigma^2 = a\\mu + b` of a scene's left renders: one
    render's noise variance.

    .. math::

        (a, b) = k\\,(\\hat a, \\hat b), \\qquad
        k = \\operatorname{mean}_{r_p \\le q_{0.999}} r_p, \\quad
        r_p = \\frac{s^2_p}{\\hat a \\mu_p + \\hat b},

    with :math:`(\\hat a, \\hat b)` the calibration's law
    (:func:`stereovar.calibration.synthesis.camera_law`, fitted to bin medians) on the
    unbiased sample variance over seeds :math:`s^2_p` (the Eq. 1 field times
    :math:`N/(N-1)`): a median of a sample variance lies below its mean, so :math:`k` puts
    the law back at the mean, without the top 0.1% of ratios (fireflies).
    """
    stack = np.asarray(left, dtype=np.float64)
    n = stack.shape[0]
    if n < 2:
        raise ValueError(f"a camera law needs N >= 2 renders, got {n}")
    mean = stack.mean(axis=0)
    mu = mean.mean(axis=-1)
    variance = ((stack - mean) ** 2).mean(axis=(0, 3)) * n / (n - 1)
    a, b = camera_law(variance, mu, valid)
    ratio = variance / (a * np.maximum(mu, 0.0) + b)
    ok = np.isfinite(ratio) & (True if valid is None else np.asarray(valid, dtype=bool))
    r = ratio[ok]
    k = float(r[r <= np.quantile(r, 0.999)].mean()) if r.size else 1.0
    return a * k, b * k


def planted_stacks(left, right, truth_left, truth_right, *, sign, law, strength, seed) -> tuple:
    """The planted positive control of one scene: N frames per view around the renders' seed
    means with camera-law noise whose variance carries a cross-view pattern of ``strength``
    and whose channels correlate as the renders' (:func:`channel_correlation`;
    :func:`stereovar.probe.planted.planted_views`), drawn from ``seed``."""
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    return planted_views(
        left.mean(axis=0),
        right.mean(axis=0),
        truth_left,
        truth_right,
        sign=int(sign),
        law=tuple(law),
        strength=float(strength),
        n=left.shape[0],
        rng=np.random.default_rng(int(seed)),
        channel_correlation=channel_correlation(left, truth_left.get("valid")),
    )


def _camera_residual(mean, law, rho, scene, view, frame, settings: TestSettings) -> np.ndarray:
    seed = derive_seed("probe-camera", settings.seed, scene, view, frame)
    return camera_residual(mean, law, np.random.default_rng(seed), channel_correlation=rho)


def test_pairs(
    left, right, *, scene: str, sign: int, law, settings: TestSettings, correlation: float = 1.0
) -> dict:
    """Every counterfactual input of the first ``test_frames`` seed indices, as network
    inputs: ``(frame, test input) -> (left, right)``.

    Each frame's clean image is the mean of the other renders (it excludes the frame,
    :func:`~stereovar.probe.inputs.reference_mean`); the camera inputs draw camera-law noise
    at the scene's law and channel ``correlation``; the shuffles are drawn per frame from
    ``shuffle_seed``; the noise
    each counterfactual adds is scaled so that every input holds one render's noise variance
    (:func:`~stereovar.probe.inputs.noise_scale`). The reference keeps :math:`1/(N - 1)` of
    the noise variance aligned across the views, so a shuffled input removes
    :math:`(N - 2)/(N - 1)` of the aligned share."""
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    if left.shape != right.shape or left.ndim != 4 or left.shape[0] < 2:
        raise ValueError(
            f"need (N >= 2, H, W, 3) renders of both views, got {left.shape} and {right.shape}"
        )
    pairs = {}
    for frame in range(min(int(settings.test_frames), left.shape[0])):
        mean_l, mean_r = reference_mean(left, frame), reference_mean(right, frame)
        camera = (
            _camera_residual(mean_l, law, correlation, scene, "left", frame, settings),
            _camera_residual(mean_r, law, correlation, scene, "right", frame, settings),
        )
        for test_input in settings.inputs:
            a, b = counterfactual_pair(
                test_input,
                left[frame],
                right[frame],
                mean_l,
                mean_r,
                sign=sign,
                shuffle_seed=derive_seed("probe-shuffle", settings.shuffle_seed, scene, frame),
                strata=settings.strata,
                conflict_shift=settings.conflict_shift,
                camera=camera,
                reference_renders=left.shape[0] - 1,
            )
            pairs[(frame, test_input)] = (network_input(a), network_input(b))
    return pairs


def test_scene(
    networks: dict,
    predict,
    left,
    right,
    ground_truth_left,
    *,
    scene: str,
    sign: int,
    regions,
    law,
    settings: TestSettings,
    correlation: float = 1.0,
) -> list[dict]:
    """Tile sums of every network on every test input of one held-out scene.

    Parameters
    ----------
    networks : dict
        ``(training condition, variant, training seed) -> network``.
    predict : callable
        ``predict(net, pairs, sign=, max_disparity=) -> list of d̂``: the architecture's
        batched prediction (:class:`~stereovar.probe.architectures.Architecture`).
    left, right : numpy.ndarray, shape (N, H, W, 3)
        The scene's renders of each view (N >= 2).
    ground_truth_left : mapping
        ``disparity``, ``valid`` and ``glass`` of the left view.
    scene : str, keyword-only
    sign : int, keyword-only
    regions : sequence of str, keyword-only
        Regions of :func:`stereovar.statistics.regions.region_masks`.
    law : (a, b), keyword-only
        The scene's camera law, for the ``camera`` inputs.
    settings : TestSettings, keyword-only
    correlation : float, keyword-only
        The renders' channel correlation (:func:`channel_correlation`), for the ``camera``
        inputs.

    Returns
    -------
    list of dict
        One per (network, variant, training seed, test input, region, tile): ``network``,
        ``variant``, ``train_seed``, ``test_input``, ``region``, ``scene``, ``tile`` and the
        sums of :func:`stereovar.probe.scoring.tile_sums` pooled over the test frames.
    """
    pairs = test_pairs(
        left, right, scene=scene, sign=sign, law=law, settings=settings, correlation=correlation
    )
    d_gt = scored_disparity(ground_truth_left, sign=sign)
    masks = region_masks(ground_truth_left, np.isfinite(d_gt), regions=tuple(regions))
    labels = tile_labels(d_gt.shape, settings.tile)
    keys = list(pairs)
    pooled: dict = {}
    for (network, variant, train_seed), net in networks.items():
        d_hats = predict(
            net, [pairs[k] for k in keys], sign=sign, max_disparity=settings.max_disparity
        )
        for (_, test_input), d_hat in zip(keys, d_hats, strict=True):
            for region, mask in masks.items():
                sums = tile_sums(d_hat, d_gt, mask, labels, conflict_shift=settings.conflict_shift)
                for i, tile in enumerate(sums["tile"]):
                    key = (network, variant, train_seed, test_input, region, int(tile))
                    acc = pooled.setdefault(key, dict.fromkeys(SUMS, 0))
                    for s in SUMS:
                        acc[s] += sums[s][i].item()
    return [
        {
            "network": network,
            "variant": variant,
            "train_seed": int(train_seed),
            "test_input": test_input,
            "region": region,
            "scene": scene,
            "tile": tile,
            **sums,
        }
        for (network, variant, train_seed, test_input, region, tile), sums in pooled.items()
    ]
