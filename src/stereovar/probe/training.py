"""Training the learned matcher on single renders with their ground-truth disparity.

Each step draws ``crops`` crops of ``crop_rows`` x ``crop_cols`` features from random
training frames (one seed's render of each view; the right crop reaches as far as the largest
disparity) and computes both views' features densely. Every left pixel of a crop with a
ground-truth disparity :math:`d` gives one triplet (Žbontar & LeCun 2016, Sec. 3.2): a positive
right pixel at :math:`x + s\\,\\mathrm{round}(d + o_+)`, :math:`o_+ \\sim U(-p, p)`, and a
negative one at :math:`x + s\\,\\mathrm{round}(d \\pm o_-)`, :math:`o_- \\sim U(n_{lo}, n_{hi})`
with a random sign, scored by the hinge loss

.. math::

    \\mathcal L = \\max\\bigl(0,\\ m + s(p_L, p_-) - s(p_L, p_+)\\bigr), \\qquad m = 0.2.

The offsets are MC-CNN's Middlebury values (:math:`p = 0.5`, :math:`n_{lo} = 1.5`,
:math:`n_{hi} = 6`), which fit disparities of 1-13 px: a positive is the nearest integer
right pixel, a negative lies 1-6 px off. Dense crops give each step thousands of triplets
for the price of one forward pass per view.

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from importlib import import_module

import numpy as np
import torch

from ..errors import ConfigError, MatcherFileError
from ..io.files import file_kind, open_regular
from .convergence import PlateauSettings, fixed_frames, train_to_plateau
from .network import MatchingNet, border, predict_matcher

__all__ = [
    "NETWORK_KINDS",
    "OPTIMISERS",
    "MatcherFileError",
    "TrainSettings",
    "TrainingFrame",
    "draw_batch",
    "hinge_loss",
    "load_matcher",
    "network_class",
    "network_kind",
    "save_matcher",
    "train_matcher",
    "validation_disparity",
]

OPTIMISERS = ("adam", "sgd")


@dataclass(frozen=True)
class TrainSettings(PlateauSettings):
    """``probe.training``: the cap on steps, crops per step, feature rows and columns per crop,
    the offsets :math:`p, n_{lo}, n_{hi}`, the margin :math:`m`, the optimiser, its learning
    rate and momentum (SGD), the Torch threads of the job, and the stop rule on a plateau of
    validation accuracy (:class:`~stereovar.probe.convergence.StopRule`: a check every
    ``check_every`` steps, ``patience`` checks without a gain above ``min_delta``, not before
    ``min_steps``), used when the training gets validation frames."""

    steps: int = 200
    crops: int = 4
    crop_rows: int = 16
    crop_cols: int = 64
    pos: float = 0.5
    neg_low: float = 1.5
    neg_high: float = 6.0
    margin: float = 0.2
    optimiser: str = "adam"
    learning_rate: float = 1e-3
    momentum: float = 0.9
    threads: int = 1

    def __post_init__(self):
        if self.optimiser not in OPTIMISERS:
            raise ValueError(
                f"probe.training.optimiser {self.optimiser!r} is unknown; use one of "
                + ", ".join(OPTIMISERS)
            )
        if not 0 <= self.pos < self.neg_low < self.neg_high:
            raise ValueError(
                "probe.training needs 0 <= pos < neg_low < neg_high, got "
                f"{self.pos}, {self.neg_low}, {self.neg_high}"
            )
        for name in ("steps", "crops", "crop_rows", "crop_cols", "threads"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"probe.training.{name} must be >= 1")
        try:
            self.stop_rule()
        except ValueError as err:
            raise ValueError(f"probe.training: {err}") from None


@dataclass(frozen=True)
class TrainingFrame:
    """One training pair: network inputs ``left`` and ``right`` (H, W) float32
    (:func:`stereovar.probe.inputs.network_input`), the left view's ``disparity`` (H, W),
    NaN outside the scored set, the ground truth's ``sign``, and ``redraw``: for a cue-blind
    twin, a function of a generator that returns a fresh right input (the right render's
    residual drawn again), used at every draw in place of ``right``."""

    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    sign: int
    redraw: Callable[[np.random.Generator], np.ndarray] | None = None

    def __post_init__(self):
        shapes = {np.shape(self.left), np.shape(self.right), np.shape(self.disparity)}
        if len(shapes) != 1 or np.ndim(self.left) != 2:
            raise ValueError(f"a training frame needs three (H, W) arrays, got {sorted(shapes)}")
        if int(self.sign) not in (1, -1):
            raise ValueError(f"sign must be 1 or -1, got {self.sign}")

    def right_input(self, rng: np.random.Generator) -> np.ndarray:
        """The right network input of one draw: ``redraw(rng)`` (a cue-blind twin's frame,
        whose right residual is drawn again at every use), else the fixed ``right``.

        Examples
        --------
        >>> z = np.zeros((2, 3), np.float32)
        >>> TrainingFrame(z, z, z, 1).right_input(np.random.default_rng(0)) is z
        True
        >>> twin = TrainingFrame(z, z, z, 1, redraw=lambda rng: z + rng.integers(1, 2))
        >>> float(twin.right_input(np.random.default_rng(0)).max())
        1.0
        """
        return self.right if self.redraw is None else self.redraw(rng)


def hinge_loss(s_pos: torch.Tensor, s_neg: torch.Tensor, margin: float) -> torch.Tensor:
    """Mean of :math:`\\max(0, m + s_- - s_+)`.

    Examples
    --------
    >>> round(float(hinge_loss(torch.tensor([1.0, 0.5]), torch.tensor([0.0, 0.5]), 0.2)), 6)
    0.1
    """
    return torch.relu(margin + s_neg - s_pos).mean()


def _reach(frames, settings: TrainSettings) -> int:
    """Columns a right crop extends past its left crop: the largest disparity plus the
    largest offset."""
    d_max = max(float(np.nanmax(f.disparity, initial=0.0)) for f in frames)
    return int(np.ceil(d_max + settings.neg_high)) + 1


def _crop_batch(
    frames, settings: TrainSettings, b: int, reach: int, rng: np.random.Generator, redraw_rng
):
    """Left crops (S, 1, rows + 2b, cols + 2b), right crops ``reach`` columns wider on the
    side of the disparity sign, the left crops' disparities (S, rows, cols), the column of
    each left feature in its right crop's feature map (S, 1, cols) and the signs (S,).
    ``rng`` draws the frames and positions, ``redraw_rng`` a twin frame's right input."""
    rows, cols = int(settings.crop_rows), int(settings.crop_cols)
    lefts, rights, disps, starts, signs = [], [], [], [], []
    for _ in range(int(settings.crops)):
        frame = frames[int(rng.integers(len(frames)))]
        height, width = frame.left.shape
        sign = int(frame.sign)
        lo = reach if sign < 0 else 0
        hi = width - (cols + 2 * b) - (reach if sign > 0 else 0)
        x0 = int(rng.integers(lo, hi + 1))
        y0 = int(rng.integers(0, height - rows - 2 * b + 1))
        xr0 = x0 - reach if sign < 0 else x0
        ys = slice(y0, y0 + rows + 2 * b)
        lefts.append(frame.left[ys, x0 : x0 + cols + 2 * b])
        right = frame.right_input(redraw_rng)
        rights.append(right[ys, xr0 : xr0 + cols + 2 * b + reach])
        disps.append(frame.disparity[y0 + b : y0 + b + rows, x0 + b : x0 + b + cols])
        starts.append(x0 - xr0 + np.arange(cols))
        signs.append(sign)
    as_t = lambda arrays: torch.from_numpy(np.stack(arrays)[:, None].astype(np.float32))  # noqa: E731
    starts = np.stack(starts)[:, None, :]
    return as_t(lefts), as_t(rights), np.stack(disps), starts, np.asarray(signs)


def _columns(d, starts, signs, offset, width: int):
    """Right feature columns of the right pixels :math:`x + s\\,\\mathrm{round}(d + o)`."""
    col = starts + signs[:, None, None] * np.rint(d + offset)
    ok = np.isfinite(col) & (col >= 0) & (col <= width - 1)
    return np.where(ok, col, 0).astype(np.int64), ok


def _gather(features: torch.Tensor, cols: np.ndarray) -> torch.Tensor:
    idx = torch.from_numpy(cols).to(features.device)[:, None].expand(-1, features.shape[1], -1, -1)
    return torch.gather(features, 3, idx)


def draw_batch(
    frames, settings: TrainSettings, rng: np.random.Generator, *, reach=None, redraw_rng=None
):
    """One training batch: crops of both views and the right feature columns of each left
    pixel's positive and negative.

    Parameters
    ----------
    frames : sequence of TrainingFrame
    settings : TrainSettings
    rng : numpy.random.Generator
        The draws of crops and offsets.
    reach : int, optional
        Columns a right crop extends past its left crop (default: from the frames).
    redraw_rng : numpy.random.Generator, optional
        The draws of a twin frame's right input (:meth:`TrainingFrame.right_input`); default
        ``rng``. A generator of its own keeps ``rng``'s crops and offsets the same whether
        the frames redraw or not (common random numbers of a network and its twin).

    Returns
    -------
    left, right : torch.Tensor, (S, 1, rows + 2b, cols + 2b) and (S, 1, rows + 2b,
        cols + 2b + reach)
    c_pos, c_neg : numpy.ndarray of int64, (S, rows, cols)
        Right feature columns of the positive and the negative.
    keep : torch.Tensor of bool, (S, rows, cols)
        The left pixels with a ground truth and both right pixels inside the crop.
    """
    b = border()
    reach = _reach(frames, settings) if reach is None else int(reach)
    redraw_rng = rng if redraw_rng is None else redraw_rng
    left, right, d, starts, signs = _crop_batch(frames, settings, b, reach, rng, redraw_rng)
    width = int(right.shape[3]) - 2 * b
    o_pos = rng.uniform(-settings.pos, settings.pos, d.shape)
    o_neg = rng.uniform(settings.neg_low, settings.neg_high, d.shape)
    o_neg *= rng.choice((-1.0, 1.0), d.shape)
    c_pos, ok_pos = _columns(d, starts, signs, o_pos, width)
    c_neg, ok_neg = _columns(d, starts, signs, o_neg, width)
    return left, right, c_pos, c_neg, torch.from_numpy(ok_pos & ok_neg)


def train_matcher(
    frames, settings: TrainSettings | None = None, *, seed: int, device="cpu", validation=None
):
    """Train one :class:`~stereovar.probe.network.MatchingNet` on ``frames``.

    Without ``validation`` it takes ``settings.steps`` steps. With it, it checks the network's
    accuracy on the validation frames every ``check_every`` steps
    (:func:`~stereovar.probe.convergence.validation_accuracy`, winner-take-all over
    :math:`0..D` with :math:`D = \\lceil d_{max} \\rceil + \\lceil n_{hi} \\rceil`, the
    training's search range), stops on a plateau (:class:`~stereovar.probe.convergence.Plateau`)
    or at ``settings.steps`` (the cap), and returns the weights of the best check.

    Parameters
    ----------
    frames : sequence of TrainingFrame
        Of one width; each at least ``crop_rows + 8`` rows high. A frame with a ``redraw``
        (a cue-blind twin's) draws its right input again for every crop.
    settings : TrainSettings, optional
    seed : int, keyword-only
        Seeds Torch's initialisation, the draws of crops and offsets (generator
        ``[seed, 1]``) and the redraws of right inputs (generator ``[seed, 2]``), so a
        network and its twin of one seed see the same crops and offsets; the same seed,
        data and thread count give the same weights on one machine.
    device : str or torch.device, keyword-only, default "cpu"
        Where the network trains (``"cuda"`` for a GPU). The weights are initialised on the
        CPU and the crops are drawn there, so only the arithmetic moves.
    validation : sequence of TrainingFrame, optional, keyword-only
        Held-out frames (one seed index per scene) for the stop rule; a frame with a
        ``redraw`` gets its right input drawn once
        (:func:`~stereovar.probe.convergence.fixed_frames`).

    Returns
    -------
    net : MatchingNet
        On the CPU, whatever ``device`` trained it; the best check's weights with
        ``validation``.
    history : dict
        ``loss`` and ``triplets`` per step, ``seconds`` of the loop (checks included),
        ``step_seconds`` (per step taken), ``steps`` taken, ``best_step`` (the step whose
        weights are returned), ``validation`` as ``(step, accuracy)`` per check and
        ``validation_seconds``.

    Raises
    ------
    ConfigError
        The loss or the weights stop being finite (the training diverged): one line with the
        step, the loss and the fix (a lower ``probe.training.learning_rate``).
    """
    settings = settings or TrainSettings()
    frames = list(frames)
    if not frames:
        raise ValueError("no training frame; the probe needs at least one scene to train on")
    widths = {f.left.shape[1] for f in frames}
    heights = {f.left.shape[0] for f in frames}
    if len(widths) != 1:
        raise ValueError(f"training frames differ in width: {sorted(widths)}")
    device = torch.device(device)
    net = _seeded_net(seed).to(device)
    b = border(net.layers, net.kernel)
    reach = _reach(frames, settings)
    if (
        min(heights) < settings.crop_rows + 2 * b
        or min(widths) < settings.crop_cols + 2 * b + reach
    ):
        raise ValueError(
            f"training frames of {min(heights)}x{min(widths)} px are too small for crops of "
            f"{settings.crop_rows}x{settings.crop_cols} features and {reach} px of disparity "
            "reach; lower probe.training.crop_rows or crop_cols"
        )
    torch.set_num_threads(int(settings.threads))
    if settings.optimiser == "adam":
        opt = torch.optim.Adam(net.parameters(), lr=settings.learning_rate)
    else:
        opt = torch.optim.SGD(
            net.parameters(), lr=settings.learning_rate, momentum=settings.momentum
        )
    rng = np.random.default_rng([int(seed), 1])
    redraw_rng = np.random.default_rng([int(seed), 2])
    held = fixed_frames(validation) if validation is not None else []
    max_d = validation_disparity(frames + held, settings)
    losses, counts = [], []
    loop = train_to_plateau(
        net,
        lambda step: _train_step(
            net, opt, frames, settings, rng, redraw_rng, reach, device, step, losses, counts
        ),
        steps=int(settings.steps),
        rule=settings.stop_rule(),
        held=held,
        predict=predict_matcher,
        max_disparity=max_d,
    )
    bad = nonfinite_weights(net)
    if bad:
        what = f"after step {loop['steps']} the weights {bad} are NaN or Inf"
        raise ConfigError(_diverged(f"probe training diverged: {what}", settings))
    net.to("cpu").eval()
    history = {"loss": losses, "triplets": counts, **loop}
    return net, history


def validation_disparity(frames, settings: TrainSettings) -> int:
    """:math:`D` of the validation checks: :math:`\\lceil d_{max} \\rceil +
    \\lceil n_{hi} \\rceil`, the largest disparity of the frames plus the farthest negative
    the training scores.

    Examples
    --------
    >>> z = np.zeros((2, 2), np.float32)
    >>> validation_disparity([TrainingFrame(z, z, z + 4.2, 1)], TrainSettings())
    11
    """
    d_max = max(float(np.nanmax(f.disparity, initial=0.0)) for f in frames)
    return int(np.ceil(d_max)) + int(np.ceil(settings.neg_high))


def _train_step(net, opt, frames, settings, rng, redraw_rng, reach, device, step, losses, counts):
    """One optimiser step on one drawn batch; appends its loss and triplet count (NaN and 0
    for a batch without a triplet, which is skipped)."""
    left, right, c_pos, c_neg, keep = draw_batch(
        frames, settings, rng, reach=reach, redraw_rng=redraw_rng
    )
    left, right, keep = left.to(device), right.to(device), keep.to(device)
    if not bool(keep.any()):  # no triplet in this batch: NaN marks the skipped step
        losses.append(float("nan"))
        counts.append(0)
        return
    fl, fr = net(left), net(right)
    s_pos = (fl * _gather(fr, c_pos)).sum(1)[keep]
    s_neg = (fl * _gather(fr, c_neg)).sum(1)[keep]
    loss = hinge_loss(s_pos, s_neg, settings.margin)
    value = float(loss.detach())
    if not np.isfinite(value):
        raise ConfigError(
            _diverged(f"probe training diverged: at step {step} the loss is {value}", settings)
        )
    opt.zero_grad()
    loss.backward()
    opt.step()
    losses.append(value)
    counts.append(int(keep.sum()))


def _seeded_net(seed: int) -> MatchingNet:
    torch.manual_seed(int(seed))
    return MatchingNet()


def _diverged(what: str, settings: TrainSettings) -> str:
    """``what`` went wrong in a diverged training, and the fix."""
    return (
        f"{what}; lower probe.training.learning_rate (now {settings.learning_rate:g}, default "
        f"{TrainSettings.learning_rate:g}) and train again"
    )


def nonfinite_weights(net: torch.nn.Module) -> str | None:
    """The first parameter or buffer of ``net`` with a NaN or Inf entry, by name, else None.

    Parameters
    ----------
    net : torch.nn.Module
        A network (its ``state_dict``'s floating-point tensors are checked).

    Returns
    -------
    str or None
        The name in ``state_dict`` order (``"body.0.bias"``), or None when every entry is
        finite.

    Examples
    --------
    >>> net = MatchingNet(features=2, layers=1)
    >>> nonfinite_weights(net) is None
    True
    >>> _ = net.body[0].bias.data.fill_(float("nan"))
    >>> nonfinite_weights(net)
    'body.0.bias'
    """
    for name, value in net.state_dict().items():
        if value.is_floating_point() and not bool(torch.isfinite(value).all()):
            return name
    return None


NETWORK_KINDS = {
    "mccnn": "stereovar.probe.network:MatchingNet",
    "costvolume": "stereovar.probe.costvolume:CostVolumeNet",
}
"""The class of each probe network kind a file records (``architecture["kind"]``)."""


def network_class(kind: str) -> type:
    """The network class of ``kind`` (imported when asked: ``costvolume`` lives in its own
    module).

    Raises
    ------
    ValueError
        An unknown kind, with the known ones.

    Examples
    --------
    >>> network_class("mccnn").__name__
    'MatchingNet'
    """
    if kind not in NETWORK_KINDS:
        raise ValueError(
            f"unknown probe network kind {kind!r}; known: {', '.join(NETWORK_KINDS)}"
        )
    module, _, name = NETWORK_KINDS[kind].partition(":")
    return getattr(import_module(module), name)


def network_kind(net: torch.nn.Module) -> str:
    """The kind of ``net`` (a key of :data:`NETWORK_KINDS`).

    Raises
    ------
    TypeError
        ``net`` is none of the probe's networks.

    Examples
    --------
    >>> network_kind(MatchingNet(features=2, layers=1))
    'mccnn'
    """
    if isinstance(net, MatchingNet):
        return "mccnn"
    for kind in NETWORK_KINDS:
        if kind != "mccnn" and type(net).__name__ == NETWORK_KINDS[kind].partition(":")[2]:
            if isinstance(net, network_class(kind)):
                return kind
    raise TypeError(f"{type(net).__name__} is not a probe network ({', '.join(NETWORK_KINDS)})")


def save_matcher(path, net, *, settings, seed: int, meta: dict):
    """Write a trained network with its architecture (``{"kind": ..., **net.config()}``,
    :data:`NETWORK_KINDS`), training settings (a dataclass, :class:`TrainSettings` or the
    cost-volume network's), seed and ``meta`` (condition, training scenes, ...) to ``path``
    atomically (a ``torch.save`` file).

    Raises
    ------
    ConfigError
        A weight is NaN or Inf (a diverged training); nothing is written.
    """
    from ..io.store import write_file

    bad = nonfinite_weights(net)
    if bad:
        what = f"{path}: not written, the network's weights {bad} are NaN or Inf (diverged)"
        raise ConfigError(_diverged(what, settings))
    payload = {
        "state_dict": net.state_dict(),
        "architecture": {"kind": network_kind(net), **net.config()},
        "settings": asdict(settings),
        "seed": int(seed),
        "meta": dict(meta),
        # a plain str: torch.__version__ is a TorchVersion, which weights_only loading refuses
        "torch": str(torch.__version__),
    }
    return write_file(path, lambda tmp: torch.save(payload, tmp))


def load_matcher(path) -> tuple[torch.nn.Module, dict]:
    """A network written by :func:`save_matcher` and its record (architecture, settings,
    seed, meta): built by the recorded kind (a file without one holds a ``mccnn``), loaded
    with ``weights_only=True``.

    Raises
    ------
    ~stereovar.errors.MatcherFileError
        A :class:`ValueError` and :class:`~stereovar.errors.StoreError`: ``path`` is missing,
        not a regular file (a named pipe, which reading would wait on forever, a directory, a
        device: refused on the open file, which is then the file read), not such a file, or
        holds NaN or Inf weights (one line naming it and the fix).
    """
    with open_regular(path, unopenable=_unreadable, not_regular=_not_regular) as f:
        try:
            payload = torch.load(f, map_location="cpu", weights_only=True)
            config = dict(payload["architecture"])
            net = network_class(config.pop("kind", "mccnn"))(**config)
            net.load_state_dict(payload["state_dict"])
        except Exception as err:  # torch.load raises many types (EOFError, UnpicklingError)
            detail = " ".join(str(err).split())[:160]  # torch's messages span several lines
            raise MatcherFileError(
                f"{path}: not a stereovar probe network ({type(err).__name__}: {detail}); "
                "delete it and rerun the probe to train it again"
            ) from None
    bad = nonfinite_weights(net)
    if bad:
        raise MatcherFileError(
            f"{path}: the probe network's weights {bad} are NaN or Inf (its training "
            "diverged); delete it and rerun the probe with a lower "
            "probe.training.learning_rate"
        )
    net.eval()
    record = {k: v for k, v in payload.items() if k != "state_dict"}
    return net, record


def _unreadable(path, err: OSError) -> MatcherFileError:
    return MatcherFileError(
        f"{path}: cannot read the probe network ({err.strerror or err}); rerun the probe to "
        "train it"
    )


def _not_regular(path, mode: int) -> MatcherFileError:
    return MatcherFileError(
        f"{path}: not a regular file ({file_kind(mode)}), so not a probe network; remove it "
        "and rerun the probe to train the network"
    )
