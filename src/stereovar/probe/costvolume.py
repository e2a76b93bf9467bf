"""The second probe architecture: a small end-to-end cost-volume network.

MC-CNN fast (:mod:`~stereovar.probe.network`) sees a 9x9 patch and decides each pixel on its
own. Stereo networks trained today build a cost volume over disparities from learned features
and regularise it with 3-D convolutions, so each disparity sees a wide context. This is such a
network at a size that trains on a CPU, after StereoNet (Khamis et al., ECCV 2018) and AnyNet
(Wang et al., ICRA 2019):

1. a 2-D feature extractor shared by both views, downsampling by :math:`f` (2 or 4);
2. a difference cost volume over the disparity levels :math:`k = 0, \\dots, \\lceil D/f
   \\rceil`, :math:`V_k(x) = \\phi_L(x) - \\phi_R(x - k)` (conventional sign: the right pixel
   at :math:`x - d`);
3. 3-D convolutions that turn :math:`V` into one matching cost :math:`C_k` per level;
4. the soft-argmin (:func:`soft_argmin`) of :math:`C`, times :math:`f`, upsampled bilinearly
   to full resolution;
5. a light refinement: dilated 2-D convolutions of the upsampled disparity and the left image
   add a residual (StereoNet Sec. 3.3).

Training (:func:`train_costvolume`) regresses the disparity with the smooth L1 loss on the
pixels with a ground truth and stops on a plateau of validation accuracy; prediction
(:func:`predict_costvolume`) is batched and handles the sign :math:`s = +1` (right pixel at
:math:`x + d`) by mirroring both views.

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from ..errors import ConfigError
from .convergence import PlateauSettings, fixed_frames, train_to_plateau

__all__ = [
    "CostVolumeNet",
    "CostVolumeSettings",
    "cost_volume",
    "draw_crops",
    "parameter_count",
    "predict_costvolume",
    "smooth_l1",
    "soft_argmin",
    "train_costvolume",
]

DISPARITY_INPUT_SCALE = 0.1
"""The refinement sees the disparity times this (an input of order 1 for 1-20 px)."""


def soft_argmin(cost: torch.Tensor) -> torch.Tensor:
    """The expected disparity level under a softmax of the negated cost (Kendall et al. 2017).

    .. math::

        \\hat k(x, y) = \\sum_{k=0}^{L-1} k\\,
            \\frac{e^{-C_k(x, y)}}{\\sum_{j=0}^{L-1} e^{-C_j(x, y)}}

    Differentiable, and sub-level accurate where the cost is peaked: a cost with a single
    minimum far below the others gives that level.

    Parameters
    ----------
    cost : torch.Tensor, shape (B, L, h, w)
        :math:`C_k`, level on axis 1.

    Returns
    -------
    torch.Tensor, shape (B, h, w)
        :math:`\\hat k`, in levels.

    Examples
    --------
    >>> c = torch.full((1, 5, 1, 1), 50.0)
    >>> c[0, 3] = 0.0
    >>> round(float(soft_argmin(c)), 6)
    3.0
    """
    levels = torch.arange(cost.shape[1], dtype=cost.dtype, device=cost.device)
    return (F.softmax(-cost, dim=1) * levels[None, :, None, None]).sum(1)


def cost_volume(feat_left: torch.Tensor, feat_right: torch.Tensor, levels: int) -> torch.Tensor:
    """The difference cost volume of the conventional sign (right pixel at :math:`x - k`).

    .. math::

        V_k(x, y) = \\begin{cases} \\phi_L(x, y) - \\phi_R(x - k, y) & x \\ge k \\\\
                    0 & x < k \\end{cases}, \\qquad k = 0, \\dots, L - 1

    Parameters
    ----------
    feat_left, feat_right : torch.Tensor, shape (B, C, h, w)
    levels : int
        :math:`L`.

    Returns
    -------
    torch.Tensor, shape (B, C, L, h, w)

    Examples
    --------
    >>> f = torch.arange(6.0).reshape(1, 1, 1, 6)
    >>> cost_volume(f, f - 2.0, 3)[0, 0, :, 0].tolist()
    [[2.0, 2.0, 2.0, 2.0, 2.0, 2.0], [0.0, 3.0, 3.0, 3.0, 3.0, 3.0], [0.0, 0.0, 4.0, 4.0, 4.0, 4.0]]
    """
    b, c, h, w = feat_left.shape
    out = feat_left.new_zeros(b, c, int(levels), h, w)
    for k in range(min(int(levels), w)):
        out[:, :, k, :, k:] = feat_left[:, :, :, k:] - feat_right[:, :, :, : w - k]
    return out


def _conv2d(cin: int, cout: int, kernel: int = 3, stride: int = 1, dilation: int = 1):
    return nn.Conv2d(
        cin, cout, kernel, stride, padding=dilation * (kernel - 1) // 2, dilation=dilation
    )


class _Residual2d(nn.Module):
    """Two 3x3 convolutions with a skip connection: :math:`x + c_2(\\mathrm{act}(c_1(x)))`."""

    def __init__(self, channels: int, dilation: int = 1):
        super().__init__()
        self.c1 = _conv2d(channels, channels, dilation=dilation)
        self.c2 = _conv2d(channels, channels, dilation=dilation)

    def forward(self, x):
        return F.leaky_relu(x + self.c2(F.leaky_relu(self.c1(x), 0.2)), 0.2)


class CostVolumeNet(nn.Module):
    """A StereoNet/AnyNet-like cost-volume network of a grey stereo pair.

    Parameters
    ----------
    features : int, keyword-only, default 16
        Channels of the 2-D feature extractor (and of the cost volume).
    blocks : int, keyword-only, default 2
        Residual blocks of the feature extractor after the downsampling.
    scale : {2, 4}, keyword-only, default 2
        :math:`f`, the downsampling of the cost volume (one stride-2 5x5 convolution per
        factor 2).
    volume_channels : int, keyword-only, default 8
        Channels of the 3-D regularisation.
    volume_layers : int, keyword-only, default 4
        3x3x3 convolutions of the regularisation (the last maps to one cost channel).
    refine_channels : int, keyword-only, default 16
        Channels of the refinement (0: no refinement).
    refine_dilations : tuple of int, keyword-only, default (1, 2, 4, 1)
        One residual block per dilation.
    max_disparity : int, keyword-only, default 20
        :math:`D`, the largest disparity in pixels that the cost volume covers unless
        :meth:`forward` is given another.

    Examples
    --------
    >>> net = CostVolumeNet()
    >>> parameter_count(net)
    38178
    >>> parameter_count(net) <= 500_000
    True
    >>> tuple(net(torch.zeros(2, 1, 30, 41), torch.zeros(2, 1, 30, 41)).shape)
    (2, 30, 41)
    >>> CostVolumeNet(**net.config()).config() == net.config()
    True
    """

    def __init__(
        self,
        *,
        features: int = 16,
        blocks: int = 2,
        scale: int = 2,
        volume_channels: int = 8,
        volume_layers: int = 4,
        refine_channels: int = 16,
        refine_dilations: tuple = (1, 2, 4, 1),
        max_disparity: int = 20,
    ):
        super().__init__()
        if int(scale) not in (2, 4):
            raise ValueError(f"scale must be 2 or 4, got {scale}")
        if int(volume_layers) < 1:
            raise ValueError(f"volume_layers must be >= 1, got {volume_layers}")
        self.features = int(features)
        self.blocks = int(blocks)
        self.scale = int(scale)
        self.volume_channels = int(volume_channels)
        self.volume_layers = int(volume_layers)
        self.refine_channels = int(refine_channels)
        self.refine_dilations = tuple(int(d) for d in refine_dilations)
        self.max_disparity = int(max_disparity)

        down, cin = [], 1
        for _ in range(self.scale // 2):
            down += [_conv2d(cin, self.features, kernel=5, stride=2), nn.LeakyReLU(0.2)]
            cin = self.features
        body = [_Residual2d(self.features) for _ in range(self.blocks)]
        self.extract = nn.Sequential(*down, *body, _conv2d(self.features, self.features))

        layers, cin = [], self.features
        for _ in range(self.volume_layers - 1):
            layers += [
                nn.Conv3d(cin, self.volume_channels, 3, padding=1),
                nn.LeakyReLU(0.2),
            ]
            cin = self.volume_channels
        layers.append(nn.Conv3d(cin, 1, 3, padding=1))
        self.regularise = nn.Sequential(*layers)

        if self.refine_channels > 0:
            self.refine = nn.Sequential(
                _conv2d(2, self.refine_channels),
                nn.LeakyReLU(0.2),
                *[_Residual2d(self.refine_channels, d) for d in self.refine_dilations],
                _conv2d(self.refine_channels, 1),
            )
        else:
            self.refine = None

    def config(self) -> dict:
        """The constructor's keyword arguments (``CostVolumeNet(**net.config())`` rebuilds it)."""
        return {
            "features": self.features,
            "blocks": self.blocks,
            "scale": self.scale,
            "volume_channels": self.volume_channels,
            "volume_layers": self.volume_layers,
            "refine_channels": self.refine_channels,
            "refine_dilations": list(self.refine_dilations),
            "max_disparity": self.max_disparity,
        }

    def levels(self, max_disparity: int | None = None) -> int:
        """Disparity levels of the cost volume, :math:`\\lceil D / f \\rceil + 1`."""
        d = self.max_disparity if max_disparity is None else int(max_disparity)
        return -(-d // self.scale) + 1

    def stages(self, left, right, max_disparity: int | None = None):
        """The upsampled soft-argmin disparity and the refined one, both (B, H, W) in pixels.

        Parameters
        ----------
        left, right : torch.Tensor, shape (B, 1, H, W)
            Network inputs (standardised grey), conventional sign (right pixel at
            :math:`x - d`).
        max_disparity : int, optional
            :math:`D` (default: the network's); the 3-D convolutions run over any number of
            levels.
        """
        if left.shape != right.shape or left.ndim != 4 or left.shape[1] != 1:
            raise ValueError(
                "left and right must be (B, 1, H, W) of one shape, got "
                f"{tuple(left.shape)} and {tuple(right.shape)}"
            )
        h, w = left.shape[-2:]
        f = self.scale
        pad = (0, (-w) % f, 0, (-h) % f)
        if any(pad):
            left = F.pad(left, pad, mode="replicate")
            right = F.pad(right, pad, mode="replicate")
        feats = self.extract(torch.cat([left, right], 0))
        fl, fr = feats.chunk(2, 0)
        cost = self.regularise(cost_volume(fl, fr, self.levels(max_disparity)))[:, 0]
        coarse = soft_argmin(cost)[:, None] * f
        up = F.interpolate(coarse, scale_factor=f, mode="bilinear", align_corners=False)
        if self.refine is None:
            refined = up
        else:
            x = torch.cat([up * DISPARITY_INPUT_SCALE, left], 1)
            refined = F.relu(up + self.refine(x))
        return up[:, 0, :h, :w], refined[:, 0, :h, :w]

    def forward(self, left, right, max_disparity: int | None = None) -> torch.Tensor:
        """The disparity (B, H, W) in pixels of network inputs (B, 1, H, W), conventional
        sign (right pixel at :math:`x - d`); see :meth:`stages`."""
        return self.stages(left, right, max_disparity)[1]


def parameter_count(net: nn.Module) -> int:
    """Trainable parameters of ``net``.

    Examples
    --------
    >>> parameter_count(torch.nn.Linear(3, 2))
    8
    """
    return sum(p.numel() for p in net.parameters() if p.requires_grad)


@dataclass(frozen=True)
class CostVolumeSettings(PlateauSettings):
    """Training of a :class:`CostVolumeNet`: ``crops`` crops of ``crop_rows`` x ``crop_cols``
    pixels per step, Adam with ``learning_rate``, at most ``steps`` steps, the plateau rule
    (validation accuracy checked every ``check_every`` steps; stop after ``patience`` checks
    without a gain of ``min_delta``, never before ``min_steps``), the smooth L1 loss's
    ``beta`` (pixels), the Torch ``threads``, ``max_disparity`` of the network (None: the
    largest ground-truth disparity of the frames plus ``disparity_margin``), and the network's
    ``scale`` (the cost volume's downsampling, 2 or 4) and 2-D ``features``."""

    crops: int = 4
    crop_rows: int = 48
    crop_cols: int = 96
    learning_rate: float = 1e-3
    steps: int = 2000
    beta: float = 1.0
    threads: int = 1
    max_disparity: int | None = None
    disparity_margin: int = 4
    scale: int = 2
    features: int = 16

    def network_config(self) -> dict:
        """The network's size from these settings (:class:`CostVolumeNet`'s ``scale`` and
        ``features``)."""
        return {"scale": int(self.scale), "features": int(self.features)}

    def __post_init__(self):
        self.stop_rule()  # checks the rule's fields
        for name in ("steps", "crops", "crop_rows", "crop_cols", "threads"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"probe costvolume training: {name} must be >= 1")
        if not self.learning_rate > 0:
            raise ValueError("probe costvolume training: learning_rate must be > 0")


def smooth_l1(pred: torch.Tensor, truth: torch.Tensor, keep: torch.Tensor, beta: float = 1.0):
    """The smooth L1 (Huber) loss over the pixels ``keep``.

    .. math::

        \\mathcal L = \\frac{1}{|K|} \\sum_{p \\in K} \\ell(\\hat d_p - d_p), \\qquad
        \\ell(e) = \\begin{cases} e^2 / (2\\beta) & |e| < \\beta \\\\
                   |e| - \\beta/2 & \\text{otherwise} \\end{cases}

    Parameters
    ----------
    pred, truth : torch.Tensor, one shape
        :math:`\\hat d` and :math:`d` (``truth`` may be NaN outside ``keep``).
    keep : torch.Tensor of bool, same shape
        :math:`K`, the pixels with a ground truth.
    beta : float, default 1.0

    Examples
    --------
    >>> p, t = torch.tensor([0.0, 0.5, 3.0]), torch.tensor([0.0, 0.0, 1.0])
    >>> float(smooth_l1(p, t, torch.tensor([True, True, True])))
    0.54166...
    """
    return F.smooth_l1_loss(pred[keep], truth[keep], beta=float(beta))


def _conventional(frame_left, frame_right, disparity, sign: int):
    """The arrays mirrored horizontally when the sign is +1 (x' = W - 1 - x turns the right
    pixel x + d into x' - d)."""
    if int(sign) > 0:
        return frame_left[:, ::-1], frame_right[:, ::-1], disparity[:, ::-1]
    return frame_left, frame_right, disparity


def draw_crops(frames, settings: CostVolumeSettings, rng, redraw_rng, *, max_disparity: int):
    """One training batch of crops in the conventional sign.

    Each crop is taken from a random frame at a random place, the same window in both
    views; a frame of sign +1 is mirrored first. Pixels are supervised where the ground truth
    is finite, at most :math:`D`, and its right pixel :math:`x - d` lies inside the crop.

    Parameters
    ----------
    frames : sequence of TrainingFrame
    settings : CostVolumeSettings
    rng : numpy.random.Generator
        Draws frames and crop windows.
    redraw_rng : numpy.random.Generator
        Draws a twin frame's right input (:meth:`TrainingFrame.right_input`), kept apart
        from ``rng`` so that a network and its twin see the same crops.
    max_disparity : int, keyword-only

    Returns
    -------
    left, right : torch.Tensor, (S, 1, rows, cols)
    disparity : torch.Tensor, (S, rows, cols)
        NaN where not supervised.
    keep : torch.Tensor of bool, (S, rows, cols)
    """
    rows, cols = int(settings.crop_rows), int(settings.crop_cols)
    lefts, rights, disps = [], [], []
    xs = np.arange(cols, dtype=np.float64)
    for _ in range(int(settings.crops)):
        frame = frames[int(rng.integers(len(frames)))]
        height, width = frame.left.shape
        y0 = int(rng.integers(0, height - rows + 1))
        x0 = int(rng.integers(0, width - cols + 1))
        right = frame.right_input(redraw_rng)
        left, right, d = _conventional(frame.left, right, frame.disparity, frame.sign)
        win = (slice(y0, y0 + rows), slice(x0, x0 + cols))
        d = np.array(d[win], dtype=np.float64)
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(d) | (d < 0) | (d > max_disparity) | (xs[None] - d < 0)
        d[bad] = np.nan
        lefts.append(left[win])
        rights.append(right[win])
        disps.append(d)
    as_t = lambda a: torch.from_numpy(np.ascontiguousarray(np.stack(a), dtype=np.float32))  # noqa: E731
    disparity = as_t(disps)
    return as_t(lefts)[:, None], as_t(rights)[:, None], disparity, torch.isfinite(disparity)


def _frames_max_disparity(frames, settings: CostVolumeSettings) -> int:
    if settings.max_disparity is not None:
        return int(settings.max_disparity)
    top = max(float(np.nanmax(f.disparity, initial=0.0)) for f in frames)
    return int(np.ceil(top)) + int(settings.disparity_margin)


def _train_step(net, opt, batch, settings: CostVolumeSettings, device, step: int):
    """One Adam step on one batch of :func:`draw_crops`; its loss and supervised pixels (NaN
    and 0 for a batch without a supervised pixel, which is skipped)."""
    left, right, d, keep = (t.to(device) for t in batch)
    if not bool(keep.any()):
        return float("nan"), 0
    up, refined = net.stages(left, right)
    loss = smooth_l1(up, d, keep, settings.beta) + smooth_l1(refined, d, keep, settings.beta)
    value = float(loss.detach())
    if not np.isfinite(value):
        raise ConfigError(
            f"probe costvolume training diverged: at step {step} the loss is {value}; lower "
            f"probe.costvolume.learning_rate (now {settings.learning_rate:g}) and train again"
        )
    opt.zero_grad()
    loss.backward()
    opt.step()
    return value, int(keep.sum())


def _seeded_net(seed: int, max_disparity: int, config: dict | None) -> CostVolumeNet:
    torch.manual_seed(int(seed))
    return CostVolumeNet(**{**(config or {}), "max_disparity": int(max_disparity)})


def train_costvolume(
    frames,
    settings: CostVolumeSettings | None = None,
    *,
    seed: int,
    device="cpu",
    validation=None,
    config: dict | None = None,
):
    """Train one :class:`CostVolumeNet` on ``frames``.

    Each step draws :func:`draw_crops` and takes one Adam step on the smooth L1 loss
    (:func:`smooth_l1`) of both stages, the upsampled soft-argmin :math:`\\hat d_0` and the
    refined :math:`\\hat d_1` (StereoNet's hierarchical loss):

    .. math::

        \\mathcal L = \\mathcal L_{\\beta}(\\hat d_0, d) + \\mathcal L_{\\beta}(\\hat d_1, d).

    With ``validation`` frames it checks the validation accuracy every ``check_every`` steps,
    stops on its plateau (at most ``steps`` steps) and returns the best check's weights;
    without, it runs ``steps`` steps.

    Parameters
    ----------
    frames : sequence of TrainingFrame
        At least ``crop_rows`` x ``crop_cols`` pixels each.
    settings : CostVolumeSettings, optional
    seed : int, keyword-only
        Seeds the initialisation and the crops (``default_rng([seed, 1])``); a twin frame's
        right inputs come from ``default_rng([seed, 2])``.
    device : str or torch.device, keyword-only, default "cpu"
    validation : sequence of TrainingFrame, optional, keyword-only
        Held-out frames (one seed index per scene) for the stop rule
        (:class:`~stereovar.probe.convergence.Plateau`, scored by
        :func:`~stereovar.probe.convergence.validation_accuracy`); a frame with a ``redraw``
        gets its right input drawn once (:func:`~stereovar.probe.convergence.fixed_frames`).
    config : dict, optional, keyword-only
        :class:`CostVolumeNet` keyword arguments (``max_disparity`` comes from ``settings``).

    Returns
    -------
    net : CostVolumeNet
        On the CPU, in eval mode.
    history : dict
        The keys of :func:`~stereovar.probe.training.train_matcher`: ``loss`` per step,
        ``triplets`` (here the supervised pixels per step), ``seconds`` of the loop (checks
        included), ``step_seconds`` (per step taken, checks excluded), ``steps`` taken,
        ``best_step`` (the step whose weights are returned), ``validation`` as
        ``(step, accuracy)`` per check and ``validation_seconds``.

    Raises
    ------
    ConfigError
        The loss stops being finite: one line with the step and the fix.
    """
    settings = settings or CostVolumeSettings()
    frames = list(frames)
    if not frames:
        raise ValueError("no training frame; the probe needs at least one scene to train on")
    small = [
        f.left.shape
        for f in frames
        if f.left.shape[0] < settings.crop_rows or f.left.shape[1] < settings.crop_cols
    ]
    if small:
        raise ValueError(
            f"training frames of {small[0][0]}x{small[0][1]} px are smaller than crops of "
            f"{settings.crop_rows}x{settings.crop_cols}; lower crop_rows or crop_cols"
        )
    held = fixed_frames(validation) if validation is not None else []
    d_max = _frames_max_disparity(frames + held, settings)
    device = torch.device(device)
    torch.set_num_threads(int(settings.threads))
    net = _seeded_net(seed, d_max, config or settings.network_config()).to(device)
    opt = torch.optim.Adam(net.parameters(), lr=settings.learning_rate)
    rng = np.random.default_rng([int(seed), 1])
    redraw_rng = np.random.default_rng([int(seed), 2])
    losses, counts = [], []

    def one_step(step: int) -> None:
        batch = draw_crops(frames, settings, rng, redraw_rng, max_disparity=d_max)
        value, count = _train_step(net, opt, batch, settings, device, step)
        losses.append(value)
        counts.append(count)

    loop = train_to_plateau(
        net, one_step, steps=int(settings.steps), rule=settings.stop_rule(), held=held,
        predict=predict_costvolume, max_disparity=d_max,
    )
    net.to("cpu").eval()
    history = {"loss": losses, "triplets": counts, **loop}
    return net, history


@torch.no_grad()
def predict_costvolume(
    net: CostVolumeNet, pairs, *, sign: int, max_disparity: int, batch: int = 8
) -> list[np.ndarray]:
    """Disparity maps of grey pairs, in batches.

    Pairs of one shape run together, ``batch`` at a time. For :math:`s = +1` (right pixel at
    :math:`x + d`) both views are mirrored, :math:`x' = W - 1 - x` turning :math:`x + d` into
    :math:`x' - d`, and the prediction is mirrored back.

    Parameters
    ----------
    net : CostVolumeNet
    pairs : sequence of (left, right)
        Network inputs (H, W) (:func:`stereovar.probe.inputs.network_input`).
    sign : {1, -1}, keyword-only
    max_disparity : int, keyword-only
        :math:`D` of the cost volume.
    batch : int, keyword-only, default 8
        Pairs per forward pass (bounds memory).

    Returns
    -------
    list of numpy.ndarray, float64, shape (H, W)
        :math:`\\hat d \\ge 0` for every pixel, in the order of ``pairs``.
    """
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    pairs = list(pairs)
    for left, right in pairs:
        if np.shape(left) != np.shape(right) or np.ndim(left) != 2:
            raise ValueError(
                f"left and right must be grey images of one shape, got {np.shape(left)} and "
                f"{np.shape(right)}"
            )
    device = next(net.parameters()).device
    net.eval()
    out: list = [None] * len(pairs)
    by_shape: dict = {}
    for i, (left, _) in enumerate(pairs):
        by_shape.setdefault(np.shape(left), []).append(i)
    for index in by_shape.values():
        for lo in range(0, len(index), int(batch)):
            chunk = index[lo : lo + int(batch)]
            views = [
                np.stack([np.asarray(pairs[i][v], dtype=np.float32) for i in chunk]) for v in (0, 1)
            ]
            if sign > 0:
                views = [v[:, :, ::-1] for v in views]
            left, right = (
                torch.from_numpy(np.ascontiguousarray(v))[:, None].to(device) for v in views
            )
            d = net(left, right, int(max_disparity)).cpu().numpy().astype(np.float64)
            if sign > 0:
                d = d[:, :, ::-1]
            for j, i in enumerate(chunk):
                out[i] = np.ascontiguousarray(d[j])
    return out
