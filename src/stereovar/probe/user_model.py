"""The user's own stereo network on the counterfactual inputs: does *it* use the Monte Carlo cue?

A team's network is a PyTorch module built by a factory it names
(``package.module:factory``) with weights from a file. It must map a batch of
stereo pairs to disparity:

.. math::

    f:\\ (L, R) \\in [0, 1]^{B \\times 3 \\times H \\times W} \\times
        [0, 1]^{B \\times 3 \\times H \\times W}
    \\;\\mapsto\\; \\hat d \\in \\mathbb R^{B \\times 1 \\times H \\times W}
    \\ \\text{or}\\ \\mathbb R^{B \\times H \\times W},

with :math:`L, R` the sRGB-encoded display images (linear radiance clipped to [0, 1], then
:func:`stereovar.io.images.linear_to_srgb`) and :math:`\\hat d \\ge 0` in the conventional
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
on a frame stops the probe (:class:`ModelError`).

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

import importlib
import importlib.util
import math
import os
import stat
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from ..errors import StereovarError
from ..io.images import file_kind, linear_to_srgb
from ..seeding import derive_seed
from ..statistics.bootstrap import draw_counts, percentile_interval, tile_labels
from ..statistics.regions import valid_set
from .inputs import STRATA, camera_residual, counterfactual_pair, reference_mean
from .scoring import tile_sums

__all__ = [
    "COMPARISONS",
    "MODEL_INPUTS",
    "MODEL_SUMS",
    "ModelError",
    "ModelSettings",
    "camera_stack",
    "check_output",
    "check_weights_file",
    "frame_law",
    "load_user_model",
    "model_image",
    "model_reading",
    "model_rows",
    "nonfinite_bound",
    "nonfinite_warning",
    "predict_user",
    "score_frame",
    "model_pairs",
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

WEIGHTS_SUFFIXES = (".pt", ".pth", ".ckpt", ".tar", ".bin")
"""Usual extensions of a file written by ``torch.save`` (offered from a folder given as
weights)."""

FACTORY_FORMAT = "package.module:factory (or path/to/file.py:factory)"


class ModelError(StereovarError):
    """The user's model cannot be imported, built, loaded or run as the probe needs it; the
    message is one line naming the fix."""


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
# loading
# --------------------------------------------------------------------------------------------


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _split_factory(spec: str) -> tuple[str, str]:
    """``module:attribute`` of a factory spec; one line when it has another form.

    Examples
    --------
    >>> _split_factory("mypkg.models:build")
    ('mypkg.models', 'build')
    """
    module, sep, attr = str(spec).rpartition(":")
    if not sep or not module or not attr or not all(p.isidentifier() for p in attr.split(".")):
        raise ModelError(f"model {spec!r} is not {FACTORY_FORMAT}; give e.g. mypkg.nets:build")
    return module, attr


def _import_module(module: str):
    if module.endswith(".py"):
        path = Path(module)
        if not path.is_file():
            raise ModelError(f"model file {module} does not exist; give an existing .py file")
        name = f"_stereovar_user_model_{abs(hash(str(path.resolve())))}"
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        try:
            sys.modules[name] = mod
            spec.loader.exec_module(mod)
        except Exception as err:
            sys.modules.pop(name, None)
            raise ModelError(
                f"model file {module} does not import ({_one_line(err)}); run it with python "
                "to see the traceback"
            ) from None
        return mod
    try:
        return importlib.import_module(module)
    except Exception as err:
        raise ModelError(
            f"model module {module!r} does not import ({_one_line(err)}); install its package "
            "or add its folder to PYTHONPATH"
        ) from None


def _factory(spec: str):
    module, attr = _split_factory(spec)
    obj = _import_module(module)
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ModelError(
                f"model module {module!r} has no attribute {attr!r}; name the function or "
                f"class that builds the model ({FACTORY_FORMAT})"
            )
        obj = getattr(obj, part)
    if not callable(obj):
        raise ModelError(f"model factory {spec!r} is not callable; name a function or class")
    return obj


def _state_dict(payload, weights) -> dict:
    if isinstance(payload, dict) and isinstance(payload.get("state_dict"), dict):
        payload = payload["state_dict"]
    if not isinstance(payload, dict) or not all(
        isinstance(v, torch.Tensor) for v in payload.values()
    ):
        raise ModelError(
            f"weights file {weights} holds no state_dict (a dict of tensors, or a dict with "
            "'state_dict'); save it with torch.save(model.state_dict(), FILE)"
        )
    return payload


def check_weights_file(weights) -> Path:
    """``weights`` as a path, once it is known to be a regular file (a link to one counts);
    nothing is opened, so a named pipe is refused without waiting on it.

    Parameters
    ----------
    weights : str or path

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ModelError
        One line: the path does not exist, cannot be looked at, is a directory (naming the
        weights files inside it, if any), or is a named pipe, a device or a socket
        (:func:`stereovar.io.images.file_kind`).
    """
    path = Path(weights)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise ModelError(
            f"weights file {path} does not exist; give the model's saved weights"
        ) from None
    except OSError as err:
        raise ModelError(
            f"weights file {path} cannot be looked at ({err.strerror or err}); give a readable "
            "path to the model's saved weights"
        ) from None
    if stat.S_ISDIR(mode):
        raise ModelError(f"weights {path} is a directory; {_inside(path)}")
    if not stat.S_ISREG(mode):
        raise ModelError(
            f"weights {path} is {file_kind(mode)}, not a file; give the model's weights file "
            "saved with torch.save"
        )
    return path


def _inside(folder: Path) -> str:
    """The fix for a folder given as weights: the file inside it to give, named where the
    folder holds files with a :data:`WEIGHTS_SUFFIXES` extension."""
    try:
        found = sorted(
            p for p in folder.iterdir() if p.suffix.lower() in WEIGHTS_SUFFIXES and p.is_file()
        )
    except OSError:
        found = []
    if not found:
        return "give the weights file inside it (the file torch.save wrote, e.g. model.pt)"
    listed = ", ".join(str(p) for p in found[:3]) + (", ..." if len(found) > 3 else "")
    return f"give the weights file inside it: {listed}"


def load_user_model(factory: str, weights, *, device: str = "cpu") -> torch.nn.Module:
    """The user's model: ``factory()`` with the weights of ``weights``, in eval mode.

    Parameters
    ----------
    factory : str
        ``package.module:factory`` (or ``path/to/file.py:factory``): a callable without
        arguments that returns a :class:`torch.nn.Module`.
    weights : str or path
        A file saved with ``torch.save``: the model's ``state_dict``, or a dict holding it as
        ``"state_dict"``; read with ``torch.load(weights_only=True)``.
    device : str, keyword-only

    Returns
    -------
    torch.nn.Module

    Raises
    ------
    ModelError
        One line each: the weights file is missing or not a file (:func:`check_weights_file`),
        the spec is malformed, the module does not import, it has no such attribute, the
        factory raises or returns no module, the weights do not load or do not fit the model.
    """
    weights = check_weights_file(weights)
    build = _factory(factory)
    try:
        model = build()
    except Exception as err:
        raise ModelError(
            f"model factory {factory!r} raised {_one_line(err)}; it must build the model "
            "without arguments (wrap it in a function that passes them)"
        ) from None
    if not isinstance(model, torch.nn.Module):
        raise ModelError(
            f"model factory {factory!r} returned {type(model).__name__}, not a torch.nn.Module"
        )
    try:
        payload = torch.load(weights, map_location="cpu", weights_only=True)
    except Exception as err:
        raise ModelError(
            f"weights file {weights} does not load with torch.load(weights_only=True) "
            f"({_one_line(err)}); save the state_dict with torch.save"
        ) from None
    state = _state_dict(payload, weights)
    try:
        model.load_state_dict(state)
    except Exception as err:
        raise ModelError(
            f"weights file {weights} does not fit the model of {factory!r} ({_one_line(err)})"
        ) from None
    return model.to(_device(device)).eval()


def _device(device) -> torch.device:
    """``device`` as a torch device PyTorch can use here, else one line."""
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError) as err:
        raise ModelError(
            f"device {device!r} is not a torch device ({_one_line(err)}); use cpu, cuda or "
            "cuda:N"
        ) from None
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise ModelError(
            f"device {device!r}: PyTorch sees no CUDA GPU here (torch {torch.__version__}); "
            "use --device cpu, or a machine with a GPU and a CUDA build of PyTorch"
        )
    return dev


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
        :func:`nonfinite_bound` (module docstring).

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
    d_hats = predict_user(
        model, [pairs[k] for k in keys], sign=sign, batch=settings.batch, device=device
    )
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
    return [
        {"scene": scene, "test_input": kind, "tile": tile, **sums}
        for (kind, tile), sums in pooled.items()
    ]


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


# --------------------------------------------------------------------------------------------
# summary
# --------------------------------------------------------------------------------------------


def _sums_matrix(rows) -> tuple[np.ndarray, list]:
    """(input, tile, sum) array over the (scene, tile) keys of ``rows`` (zeros where an input
    scored no pixel of a tile) and the scene of each tile."""
    keys = sorted({(r["scene"], int(r["tile"])) for r in rows})
    index = {k: i for i, k in enumerate(keys)}
    out = np.zeros((len(MODEL_INPUTS), len(keys), len(MODEL_SUMS)))
    for r in rows:
        if r["test_input"] not in MODEL_INPUTS:
            continue
        i = MODEL_INPUTS.index(r["test_input"])
        out[i, index[(r["scene"], int(r["tile"]))]] += [float(r.get(s, 0)) for s in MODEL_SUMS]
    return out, [k[0] for k in keys]


def _stratified_counts(scenes, reps: int, seed) -> np.ndarray:
    """Bootstrap draw counts (reps, tiles): each scene's tiles drawn with replacement among
    themselves (:func:`stereovar.statistics.bootstrap.draw_counts` per scene)."""
    scenes = np.asarray(scenes, dtype=object)
    counts = np.zeros((int(reps), scenes.size))
    for j, scene in enumerate(dict.fromkeys(scenes.tolist())):
        cols = np.flatnonzero(scenes == scene)
        counts[:, cols] = draw_counts(cols.size, int(reps), [int(seed), j])
    return counts


def _metrics(sums) -> dict:
    """Accuracy and EPE of each input from summed (..., input, sum) arrays."""
    n = sums[..., 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        acc = np.where(n > 0, sums[..., 1] / n, np.nan)
        epe = np.where(n > 0, sums[..., 2] / n, np.nan)
    return {"accuracy": acc, "epe": epe}


def model_rows(rows, *, reps: int = 1000, seed: int = 0, level: float = 0.95) -> list[dict]:
    """The user model's table: accuracy and EPE per input, and the drops under each shuffle.

    Rows ``normal``, ``shuffled``, ``camera``, ``camera_shuffled`` give

    .. math:: A = \\frac{\\sum_t \\mathrm{hits}_t}{\\sum_t n_t}, \\qquad
        \\mathrm{EPE} = \\frac{\\sum_t |\\hat d - d|_t}{\\sum_t n_t};

    rows ``mc_shuffle`` and ``camera_shuffle`` the drop of accuracy and the rise of EPE
    under each shuffle (:data:`COMPARISONS`: before minus after, after minus before), and row
    ``mc_minus_camera`` the difference of the two. Each with a percentile interval of a tile
    bootstrap stratified by frame (``*_low``, ``*_high``); the inputs are paired by tile in
    every replicate. A NaN or Inf prediction is one of the :math:`n_t` pixels, a miss, and
    adds :func:`nonfinite_bound` to the EPE's sum (module docstring); ``nonfinite_share``
    is their share of the scored pixels of an input (its rise under a comparison's shuffle;
    the difference of the two rises for ``mc_minus_camera``).

    Parameters
    ----------
    rows : list of dict
        :func:`score_frame`'s rows of every frame.
    reps, seed, level : keyword-only

    Returns
    -------
    list of dict
        ``row``, ``accuracy``, ``accuracy_low``, ``accuracy_high``, ``epe``, ``epe_low``,
        ``epe_high``, ``nonfinite_share``, ``n_pixels``, ``n_tiles``, ``frames``.
    """
    sums, scenes = _sums_matrix(list(rows))
    if not scenes:
        raise ValueError("no scored pixel: the frames have no valid ground truth")
    counts = _stratified_counts(scenes, reps, seed)
    total = sums.sum(axis=1)  # (input, sum)
    point = _metrics(total)
    nonfinite = total[:, MODEL_SUMS.index("nonfinite")]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total[:, 0] > 0, nonfinite / total[:, 0], np.nan)  # (input,)
    boot = _metrics(np.einsum("rt,its->ris", counts, sums))  # (reps, input)

    def drop(values, before, after, axis_last=True):
        i, j = MODEL_INPUTS.index(before), MODEL_INPUTS.index(after)
        return values[..., i] - values[..., j]

    def summary(acc_p, acc_b, epe_p, epe_b) -> dict:
        lo_a, hi_a = percentile_interval(acc_b, level)
        lo_e, hi_e = percentile_interval(epe_b, level)
        return {
            "accuracy": float(acc_p),
            "accuracy_low": lo_a,
            "accuracy_high": hi_a,
            "epe": float(epe_p),
            "epe_low": lo_e,
            "epe_high": hi_e,
        }

    common = {"n_tiles": len(scenes), "frames": len(set(scenes))}
    out = []
    for i, kind in enumerate(MODEL_INPUTS):
        out.append(
            {
                "row": kind,
                **summary(
                    point["accuracy"][i], boot["accuracy"][:, i], point["epe"][i], boot["epe"][:, i]
                ),
                "nonfinite_share": float(share[i]),
                "n_pixels": int(sums[i, :, 0].sum()),
                **common,
            }
        )
    diffs, rises = {}, {}
    for name, (before, after) in COMPARISONS.items():
        diffs[name] = (
            drop(point["accuracy"], before, after),
            drop(boot["accuracy"], before, after),
            -drop(point["epe"], before, after),
            -drop(boot["epe"], before, after),
        )
        rises[name] = -drop(share, before, after)
    mc, cam = diffs["mc_shuffle"], diffs["camera_shuffle"]
    diffs["mc_minus_camera"] = tuple(a - b for a, b in zip(mc, cam, strict=True))
    rises["mc_minus_camera"] = rises["mc_shuffle"] - rises["camera_shuffle"]
    for name, values in diffs.items():
        out.append(
            {
                "row": name,
                **summary(*values),
                "nonfinite_share": float(rises[name]),
                "n_pixels": int(sums[0, :, 0].sum()),
                **common,
            }
        )
    return out


def _points(value, low, high, scale=100.0) -> str:
    return f"{scale * value:+.2f} [{scale * low:+.2f}, {scale * high:+.2f}]"


def _share(value: float) -> str:
    """A share in percent, one decimal; a share that rounds to 0 or 100 % but is not says
    so.

    Examples
    --------
    >>> _share(0.5), _share(0.0), _share(2e-5), _share(1.0)
    ('50.0 %', '0 %', '< 0.1 %', '100 %')
    """
    if value <= 0 or value >= 1:
        return f"{100 * value:.0f} %"
    if value < 0.0005:
        return "< 0.1 %"
    if value > 0.9995:
        return "> 99.9 %"
    return f"{100 * value:.1f} %"


def nonfinite_warning(rows) -> str | None:
    """The one-line warning when the model returned NaN or Inf at any scored pixel, with the
    share of each input (:func:`model_rows`' ``nonfinite_share``); None when it never did.

    Examples
    --------
    >>> rows = [{"row": k, "nonfinite_share": s} for k, s in zip(MODEL_INPUTS, (0, 0.5, 0, 0))]
    >>> nonfinite_warning(rows)[:85]
    'the model returned NaN or Inf disparity at scored pixels (normal 0 %, shuffled 50.0 %'
    >>> nonfinite_warning(rows[:1]) is None
    True
    """
    shares = {r["row"]: r["nonfinite_share"] for r in rows if r["row"] in MODEL_INPUTS}
    if not any(s > 0 for s in shares.values()):
        return None
    listed = ", ".join(f"{kind} {_share(s)}" for kind, s in shares.items())
    return (
        f"the model returned NaN or Inf disparity at scored pixels ({listed}); they "
        "count as misses at an end-point error of the frame's largest disparity (column "
        "nonfinite_share); check the model for a division by zero or a log of a negative "
        "number"
    )


def model_reading(rows) -> str:
    """One sentence: does the model use the Monte Carlo cue, from :func:`model_rows`.

    It does when the accuracy drop under the Monte Carlo shuffle is above 0 and above the
    camera shuffle's (the interval of ``mc_minus_camera`` lies above 0); it shows no use when
    that interval holds 0; and the shuffle helps it when the interval lies below 0.
    """
    by = {r["row"]: r for r in rows}
    mc, cam, diff = by["mc_shuffle"], by["camera_shuffle"], by["mc_minus_camera"]
    numbers = (
        f"accuracy drop under the Monte Carlo shuffle "
        f"{_points(mc['accuracy'], mc['accuracy_low'], mc['accuracy_high'])} points, under the "
        "camera-noise shuffle "
        f"{_points(cam['accuracy'], cam['accuracy_low'], cam['accuracy_high'])}"
        f", difference {_points(diff['accuracy'], diff['accuracy_low'], diff['accuracy_high'])}"
        f" (EPE rise {mc['epe']:+.3f} vs {cam['epe']:+.3f} px)"
    )
    low, high = diff["accuracy_low"], diff["accuracy_high"]
    if not (math.isfinite(low) and math.isfinite(high)):
        verdict = "not determined (too few tiles for an interval)"
    elif low > 0:
        verdict = "the model uses the Monte Carlo cue"
    elif high < 0:
        verdict = "the shuffle helps the model more than camera noise's (not a cue use)"
    else:
        verdict = "no use of the Monte Carlo cue detected"
    return f"{verdict}: {numbers}, over {diff['frames']} frames ({diff['n_tiles']} tiles)."


def frame_law(left, valid=None) -> tuple[float, float]:
    """The camera law :math:`\\sigma^2 = a\\mu + b` of a frame's left renders: one render's
    noise variance, as the learned probe takes it
    (:func:`stereovar.probe.experiment.scene_law`)."""
    from .experiment import scene_law

    return scene_law(left, valid)
