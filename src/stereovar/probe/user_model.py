"""The user's own stereo network on the counterfactual inputs: does *it* use the Monte Carlo cue?

A team's network is a PyTorch module built by a factory it names
(``package.module:factory``) with weights from a file (loaded by
:mod:`stereovar.probe.user_loading`). It must map a batch of stereo pairs to disparity:

.. math::

    f:\\ (L, R) \\in [0, 1]^{B \\times 3 \\times H \\times W} \\times
        [0, 1]^{B \\times 3 \\times H \\times W}
    \\;\\mapsto\\; \\hat d \\in \\mathbb R^{B \\times 1 \\times H \\times W}
    \\ \\text{or}\\ \\mathbb R^{B \\times H \\times W},

with :math:`L, R` the sRGB-encoded display images (linear radiance clipped to [0, 1], then
:func:`stereovar.io.transfer.linear_to_srgb`) and :math:`\\hat d \\ge 0` in the conventional
sign: the right pixel of left pixel :math:`x` is at :math:`x - \\hat d`. Frames of the
other sign (:math:`s = +1`, the paper's) are mirrored, both views, before the network and
its output mirrored back, which turns :math:`x + d` into :math:`x' - d`.

Each test frame (one render :math:`n` of a frame, or scene) is run on four counterfactual
inputs (:func:`stereovar.probe.inputs.counterfactual_pair`): ``normal``, ``shuffled`` (the
right view's Monte Carlo residual permuted within intensity strata), ``camera`` (the
reference mean with camera-law noise of the renders' own level in both views) and
``camera_shuffled`` (that camera noise shuffled the same way). The question is answered by
two drops of accuracy (:math:`|\\hat d - d| < 1`) and the rise of the end-point error:

.. math::

    \\Delta_{MC} = A(\\text{normal}) - A(\\text{shuffled}), \\qquad
    \\Delta_{cam} = A(\\text{camera}) - A(\\text{camera\\_shuffled}), \\qquad
    \\Delta = \\Delta_{MC} - \\Delta_{cam}.

:math:`\\Delta_{cam}` is what the shuffle itself costs where there is no cue to break (the
same strata, the same noise law); :math:`\\Delta` is the part of the drop that only the
Monte Carlo residual's cross-view alignment explains. Intervals: a tile bootstrap
(:mod:`stereovar.statistics.bootstrap`) over the frames' tiles, stratified by frame (each
replicate draws every frame's own tiles with replacement; a tile holds all its test
renders), percentile intervals.

A prediction that is NaN or Inf is a miss, scored at the end-point error

.. math:: e_{\\max} = \\max\\bigl(1,\\ \\max_{\\Omega} d\\bigr)

(:func:`nonfinite_bound`, :func:`stereovar.probe.scoring.tile_sums`), and its share is
reported per input (``nonfinite_share``). Every input is thus scored on the same pixels
:math:`\\Omega` of the same test renders, so each drop compares the inputs pixel by pixel.
Were they left out, each input would be scored on the pixels where the model answered: a
model whose NaN follow the input (more of them under the shuffle, or on the pixels it would
get wrong) would have its inputs compared over different pixels, and the drop would measure
where its NaN fall, not what the shuffle costs it. The bound is the largest error of any
finite answer in the frame's disparity range (:math:`|\\hat d - d| \\le \\max_\\Omega d`
for :math:`\\hat d, d \\in [0, \\max_\\Omega d]`), and at least a miss's 1 px, so that
a NaN never scores better than an answer in range. A model with no finite prediction at all
on a frame stops the probe (:class:`~stereovar.probe.user_loading.ModelError`).

Beside the inputs, each frame is scored for its best constant answers, and the model is run
once more on the first test render with the right view moved by 2 px
(:mod:`stereovar.probe.user_checks`): a model no better than a constant disparity, or whose
output does not follow the move, reads *no use* whatever it is, and the reading
(:mod:`stereovar.probe.user_summary`, which also makes the table) says *not testable* instead.

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ..io.transfer import linear_to_srgb
from ..seeding import derive_seed
from ..statistics.bootstrap import tile_labels
from ..statistics.regions import valid_set
from .inputs import STRATA, camera_residual, counterfactual_pair, reference_mean
from .scoring import tile_sums
from .user_checks import (
    CONSTANT_ROW,
    RESPONSE_ROW,
    RESPONSE_SHIFT,
    best_constants,
    response_sums,
    shifted_right,
)
from .user_loading import ModelError, _one_line

__all__ = [
    "COMPARISONS",
    "MODEL_INPUTS",
    "MODEL_SUMS",
    "ModelSettings",
    "camera_stack",
    "check_output",
    "frame_law",
    "model_image",
    "model_pairs",
    "nonfinite_bound",
    "predict_user",
    "score_frame",
]

MODEL_INPUTS = ("normal", "shuffled", "camera", "camera_shuffled")
"""The counterfactual inputs the user's model is run on, in table order."""

COMPARISONS = {
    "mc_shuffle": ("normal", "shuffled"),
    "camera_shuffle": ("camera", "camera_shuffled"),
}
"""Each drop: (before, after) the shuffle."""

MODEL_SUMS = ("n", "hits", "abs_error", "nonfinite")
"""The per-tile sums kept (:func:`stereovar.probe.scoring.tile_sums`): scored pixels, hits,
summed end-point error, NaN or Inf predictions."""


@dataclass(frozen=True)
class ModelSettings:
    """How the user's model is tested.

    Attributes
    ----------
    test_frames : int
        Renders of each frame used as test frames (the first ones; each against the mean
        of the others).
    strata : int
        Intensity strata of the shuffle (:func:`stereovar.probe.inputs.stratified_shuffle`).
    tile : int
        Bootstrap tile side in pixels.
    reps : int
        Bootstrap replicates.
    seed : int
        Seed of the shuffles, the camera noise and the bootstrap.
    batch : int
        Pairs per forward pass.
    level : float
        Interval coverage.
    """

    test_frames: int = 4
    strata: int = STRATA
    tile: int = 16
    reps: int = 1000
    seed: int = 0
    batch: int = 4
    level: float = 0.95


# --------------------------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------------------------


def model_image(render) -> np.ndarray:
    """The model's input of one linear render: sRGB-encoded RGB in [0, 1], channels first.

    .. math:: u_c = \\mathrm{sRGB}\\bigl(\\min(\\max(c, 0), 1)\\bigr)

    Non-finite pixels become 0.

    Parameters
    ----------
    render : array_like, shape (H, W, 3)

    Returns
    -------
    numpy.ndarray, float32, shape (3, H, W)

    Examples
    --------
    >>> model_image(np.array([[[0.0, 1.0, 2.0]]])).ravel().tolist()
    [0.0, 1.0, 1.0]
    """
    a = np.asarray(render, dtype=np.float64)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"a render must have shape (H, W, 3), got {a.shape}")
    a = np.clip(np.where(np.isfinite(a), a, 0.0), 0.0, 1.0)
    return np.ascontiguousarray(linear_to_srgb(a).transpose(2, 0, 1), dtype=np.float32)


def check_output(out, batch: int, height: int, width: int) -> torch.Tensor:
    """The model's output as (B, H, W); one line when it has another shape.

    Examples
    --------
    >>> tuple(check_output(torch.zeros(2, 1, 4, 5), 2, 4, 5).shape)
    (2, 4, 5)
    """
    if isinstance(out, (tuple, list)) and out and isinstance(out[-1], torch.Tensor):
        out = out[-1]  # iterative networks (RAFT-Stereo) return every refinement: the last
    if not isinstance(out, torch.Tensor):
        raise ModelError(
            f"the model returned {type(out).__name__}, not a tensor; it must return disparity "
            f"of shape ({batch}, 1, {height}, {width}) or ({batch}, {height}, {width})"
        )
    shape = tuple(out.shape)
    if shape == (batch, 1, height, width):
        return out[:, 0]
    if shape == (batch, height, width):
        return out
    raise ModelError(
        f"the model returned shape {shape} for inputs of shape ({batch}, 3, {height}, {width}); "
        f"it must return disparity of shape ({batch}, 1, {height}, {width}) or "
        f"({batch}, {height}, {width}) (pad or crop inside the model, upsample a low-resolution "
        "output)"
    )


@torch.no_grad()
def predict_user(model, pairs, *, sign: int, batch: int = 4, device: str = "cpu") -> list:
    """The model's disparity of every pair of linear renders, in batches.

    Parameters
    ----------
    model : torch.nn.Module
        :math:`(L, R) \\mapsto \\hat d`, conventional sign (module docstring).
    pairs : list of (numpy.ndarray, numpy.ndarray)
        Linear renders (H, W, 3) of the left and right view, all of one shape.
    sign : {1, -1}, keyword-only
        The frames' ``disparity_sign``; with +1 both views are mirrored in and out.
    batch : int, keyword-only
    device : str, keyword-only

    Returns
    -------
    list of numpy.ndarray, float64, shape (H, W)
        :math:`\\hat d` in the left view's pixels.
    """
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    out = []
    for start in range(0, len(pairs), max(int(batch), 1)):
        chunk = pairs[start : start + max(int(batch), 1)]
        left = np.stack([model_image(a) for a, _ in chunk])
        right = np.stack([model_image(b) for _, b in chunk])
        if sign == 1:
            left, right = left[..., ::-1], right[..., ::-1]
        b, _, h, w = left.shape
        x_l = torch.from_numpy(np.ascontiguousarray(left)).to(device)
        x_r = torch.from_numpy(np.ascontiguousarray(right)).to(device)
        try:
            raw = model(x_l, x_r)
        except ModelError:
            raise
        except Exception as err:
            raise ModelError(
                f"the model failed on inputs of shape ({b}, 3, {h}, {w}) ({_one_line(err)}); it "
                "must take (left, right) sRGB images in [0, 1] of shape (B, 3, H, W)"
            ) from None
        d_hat = check_output(raw, b, h, w).detach().to("cpu", torch.float64).numpy()
        if sign == 1:
            d_hat = d_hat[..., ::-1]
        out += [np.ascontiguousarray(d) for d in d_hat]
    return out


def camera_stack(stack, law, *, seed) -> np.ndarray:
    """Renders of a camera at the renders' noise level: the mean of the renders plus fresh
    camera-law noise, one draw per render.

    .. math:: C^{(m)} = \\bar I + \\eta^{(m)}, \\qquad m = 1, \\dots, N,

    with :math:`\\bar I` the mean of all :math:`N` renders and :math:`\\eta^{(m)}`
    :func:`~stereovar.probe.inputs.camera_residual` at ``law`` and the renders' channel
    correlation (:func:`~stereovar.probe.experiment.channel_correlation`).
    """
    from .experiment import channel_correlation

    stack = np.asarray(stack, dtype=np.float64)
    mean = stack.mean(axis=0)
    rho = channel_correlation(stack)
    rng = np.random.default_rng(int(seed))
    return np.stack(
        [
            mean + camera_residual(mean, law, rng, channel_correlation=rho)
            for _ in range(stack.shape[0])
        ]
    )


def model_pairs(left, right, *, scene: str, sign: int, law, settings: ModelSettings) -> dict:
    """The four inputs of :data:`MODEL_INPUTS` for each test render of one frame, linear:
    ``(n, input) -> (left, right)``.

    ``normal`` and ``shuffled`` are :func:`~stereovar.probe.inputs.counterfactual_pair`'s,
    render :math:`n` against the mean of the other renders
    (:func:`~stereovar.probe.inputs.reference_mean`). ``camera`` and ``camera_shuffled`` are
    the same two inputs made from camera stacks (:func:`camera_stack` of each view at the
    frame's ``law``) instead of the renders:

    .. math::

        \\text{camera} = (C_L^{(n)}, C_R^{(n)}), \\qquad
        \\text{camera\\_shuffled} = \\bigl(C_L^{(n)}, \\bar C_R^{(-n)} +
            \\Pi_S(C_R^{(n)} - \\bar C_R^{(-n)})\\bigr),

    so that the control goes through every step of the Monte Carlo shuffle. Both shuffles
    scale the residual (``reference_renders`` :math:`N - 1`,
    :func:`~stereovar.probe.inputs.noise_scale`) so that the shuffled right view has one
    render's noise variance. The shuffles and the noise are drawn from seeds
    derived from ``settings.seed``, the frame and :math:`n`.
    """
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    if left.shape != right.shape or left.ndim != 4 or left.shape[0] < 2:
        raise ValueError(
            f"need (N >= 2, H, W, 3) renders of both views, got {left.shape} and {right.shape}"
        )
    cam_l, cam_r = (
        camera_stack(stack, law, seed=derive_seed("probe-model-camera", settings.seed, scene, v))
        for v, stack in (("left", left), ("right", right))
    )
    names = (("normal", "shuffled"), ("camera", "camera_shuffled"))
    pairs = {}
    for n in range(min(int(settings.test_frames), left.shape[0])):
        shuffle_seed = derive_seed("probe-model-shuffle", settings.seed, scene, n)
        for (a, b), kinds in zip(((left, right), (cam_l, cam_r)), names, strict=True):
            mean_l, mean_r = reference_mean(a, n), reference_mean(b, n)
            for change, kind in zip(("normal", "shuffled"), kinds, strict=True):
                pairs[(n, kind)] = counterfactual_pair(
                    change,
                    a[n],
                    b[n],
                    mean_l,
                    mean_r,
                    sign=sign,
                    shuffle_seed=shuffle_seed,
                    strata=settings.strata,
                    reference_renders=a.shape[0] - 1,
                )
    return pairs


def score_frame(
    model,
    left,
    right,
    truth_left,
    *,
    scene: str,
    sign: int,
    law,
    settings: ModelSettings,
    device: str = "cpu",
) -> list[dict]:
    """Per-tile sums of the model's predictions on every input of one frame, pooled over its
    test renders.

    Parameters
    ----------
    model : torch.nn.Module
    left, right : numpy.ndarray, shape (N, H, W, 3)
        The frame's renders of each view, linear.
    truth_left : mapping
        ``disparity`` and ``valid`` of the left view (magnitudes).
    scene : str, keyword-only
        The frame's name (the bootstrap's stratum).
    sign : int, keyword-only
    law : (a, b), keyword-only
        The frame's camera law (:func:`stereovar.calibration.synthesis.camera_law`).
    settings : ModelSettings, keyword-only
    device : str, keyword-only

    Returns
    -------
    list of dict
        ``scene``, ``test_input``, ``tile`` and :data:`MODEL_SUMS`: the pixels of
        :math:`\\Omega` (paper Sec. 2.2), a NaN or Inf prediction a miss at
        :func:`nonfinite_bound` (module docstring); with ``test_input``
        :data:`~stereovar.probe.user_checks.CONSTANT_ROW`, the best constant answers of the
        frame (:func:`~stereovar.probe.user_checks.best_constants`) on the same pixels, as
        many times as there are test renders; and one row with ``test_input``
        :data:`~stereovar.probe.user_checks.RESPONSE_ROW` and tile -1: the change of the
        model's disparity when the first test render's right view is moved
        (:func:`~stereovar.probe.user_checks.response_sums`; one more forward pass).

    Raises
    ------
    ModelError
        No prediction of the frame, on any input, has a finite pixel (one line).
    """
    pairs = model_pairs(left, right, scene=scene, sign=sign, law=law, settings=settings)
    d = np.asarray(truth_left["disparity"], dtype=np.float64)
    omega = valid_set(d, sign=sign, valid=np.asarray(truth_left["valid"]))
    d_gt = np.where(omega, d, np.nan)
    labels = tile_labels(d_gt.shape, settings.tile)
    keys = list(pairs)
    first_l, first_r = pairs[(0, "normal")]
    moved = (first_l, shifted_right(first_r, sign=sign, shift=RESPONSE_SHIFT))
    d_hats = predict_user(
        model, [pairs[k] for k in keys] + [moved], sign=sign, batch=settings.batch,
        device=device,
    )
    d_moved = d_hats.pop()
    if not any(np.isfinite(d_hat).any() for d_hat in d_hats):
        raise ModelError(_no_finite_message(d_hats, keys, scene))
    bound = nonfinite_bound(d_gt)
    pooled: dict = {}
    for (_, kind), d_hat in zip(keys, d_hats, strict=True):
        sums = tile_sums(d_hat, d_gt, omega, labels, conflict_shift=0, nonfinite_error=bound)
        for i, tile in enumerate(sums["tile"]):
            acc = pooled.setdefault((kind, int(tile)), dict.fromkeys(MODEL_SUMS, 0))
            for s in MODEL_SUMS:
                acc[s] += sums[s][i].item()
    renders = len({n for n, _ in keys})
    for tile, sums in _constant_sums(d_gt, omega, labels).items():
        pooled[(CONSTANT_ROW, tile)] = {s: renders * v for s, v in sums.items()}
    first = d_hats[keys.index((0, "normal"))]
    response = response_sums(first, d_moved, d_gt, omega, sign=sign, shift=RESPONSE_SHIFT)
    return [
        {"scene": scene, "test_input": kind, "tile": tile, **sums}
        for (kind, tile), sums in pooled.items()
    ] + [{"scene": scene, "test_input": RESPONSE_ROW, "tile": -1, **response}]


def _constant_sums(d_gt, omega, labels) -> dict:
    """Per tile, :data:`MODEL_SUMS` of the frame's best constant answers: the hits of
    :math:`c_A`, the end-point error of :math:`c_E`
    (:func:`~stereovar.probe.user_checks.best_constants`), on the pixels the inputs are
    scored on."""
    scored = omega & np.isfinite(d_gt)
    if not scored.any():
        return {}
    c_acc, c_epe = best_constants(d_gt[scored])
    hits = tile_sums(np.full_like(d_gt, c_acc), d_gt, omega, labels, conflict_shift=0)
    errors = tile_sums(np.full_like(d_gt, c_epe), d_gt, omega, labels, conflict_shift=0)
    return {
        int(tile): {
            "n": errors["n"][i].item(),
            "hits": hits["hits"][i].item(),
            "abs_error": errors["abs_error"][i].item(),
            "nonfinite": 0,
        }
        for i, tile in enumerate(errors["tile"])
    }


def nonfinite_bound(d_gt) -> float:
    """The end-point error charged to a NaN or Inf prediction of a frame: its largest
    ground-truth disparity, at least 1 px (module docstring).

    .. math:: e_{\\max} = \\max\\bigl(1,\\ \\max_{\\Omega} d\\bigr)

    Parameters
    ----------
    d_gt : array_like
        The frame's ground-truth disparity magnitudes, NaN outside :math:`\\Omega`.

    Examples
    --------
    >>> nonfinite_bound([[2.0, 7.5, np.nan]]), nonfinite_bound([[0.25, np.nan]])
    (7.5, 1.0)
    """
    d = np.asarray(d_gt, dtype=np.float64)
    d = d[np.isfinite(d)]
    return max(1.0, float(d.max())) if d.size else 1.0


def _no_finite_message(d_hats, keys, scene: str) -> str:
    """One line: every prediction of a frame is NaN or Inf (which, how many, of what size)."""
    stack = np.stack(d_hats)
    if np.isnan(stack).all():
        what = "NaN"
    elif np.isinf(stack).all():
        what = "Inf"
    else:
        what = "NaN or Inf"
    inputs = list(dict.fromkeys(kind for _, kind in keys))
    renders = len({n for n, _ in keys})
    h, w = stack.shape[1:]
    return (
        f"the model returned no finite disparity: all {len(d_hats)} of its predictions on "
        f"frame {scene} ({renders} test renders x {len(inputs)} inputs: {', '.join(inputs)}; "
        f"{h}x{w} pixels each) are "
        f"{what} at every pixel; check that it runs on sRGB images in [0, 1] of shape "
        "(B, 3, H, W) and that its weights are finite (a NaN weight or a division by zero "
        "gives NaN)"
    )


def frame_law(left, valid=None) -> tuple[float, float]:
    """The camera law :math:`\\sigma^2 = a\\mu + b` of a frame's left renders: one render's
    noise variance, as the learned probe takes it
    (:func:`stereovar.probe.experiment.scene_law`)."""
    from .experiment import scene_law

    return scene_law(left, valid)
