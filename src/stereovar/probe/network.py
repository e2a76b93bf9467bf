"""The learned matcher: MC-CNN "fast" (Žbontar & LeCun, JMLR 2016, Sec. 3.2).

A siamese network maps a grey image to one unit feature vector per pixel; the matching score
of a left pixel and a right pixel is the dot product (cosine similarity) of their features.
Four 3x3 convolutions with 64 feature maps, ReLU between them and none after the last, see a
9x9 patch; no padding, so a feature map is 8 pixels narrower and shorter than its image and
feature :math:`(y, x)` belongs to image pixel :math:`(y + 4, x + 4)`.

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

__all__ = [
    "FEATURES",
    "KERNEL",
    "LAYERS",
    "MatchingNet",
    "border",
    "dense_features",
    "predict_matcher",
    "score_volume",
    "wta_disparity",
    "wta_from_features",
]

FEATURES = 64
"""Feature maps of every layer (MC-CNN fast)."""
LAYERS = 4
"""Convolutions."""
KERNEL = 3
"""Kernel side."""


def border(layers: int = LAYERS, kernel: int = KERNEL) -> int:
    """Pixels lost on each side by the unpadded convolutions: ``layers * (kernel - 1) / 2``.

    Examples
    --------
    >>> border()
    4
    """
    return int(layers) * (int(kernel) - 1) // 2


class MatchingNet(nn.Module):
    """MC-CNN fast: a 9x9 grey patch to a unit feature vector.

    .. math::

        f(P) = \\frac{g(P)}{\\lVert g(P) \\rVert_2}, \\quad
        g = c_4 \\circ \\mathrm{ReLU} \\circ c_3 \\circ \\mathrm{ReLU} \\circ c_2 \\circ
            \\mathrm{ReLU} \\circ c_1, \\qquad
        s(p_L, p_R) = \\langle f(P_L), f(P_R) \\rangle,

    with :math:`c_i` a 3x3 convolution to 64 maps (Žbontar & LeCun 2016, Sec. 3.2).

    Parameters
    ----------
    features, layers, kernel : int, keyword-only

    Examples
    --------
    >>> net = MatchingNet()
    >>> sum(p.numel() for p in net.parameters())
    111424
    >>> tuple(net(torch.zeros(1, 1, 9, 9)).shape)
    (1, 64, 1, 1)
    """

    def __init__(self, *, features: int = FEATURES, layers: int = LAYERS, kernel: int = KERNEL):
        super().__init__()
        modules: list[nn.Module] = []
        for i in range(int(layers)):
            modules.append(nn.Conv2d(1 if i == 0 else features, features, kernel))
            if i < layers - 1:
                modules.append(nn.ReLU())
        self.body = nn.Sequential(*modules)
        self.features = int(features)
        self.layers = int(layers)
        self.kernel = int(kernel)

    def config(self) -> dict:
        """The constructor's keyword arguments: ``MatchingNet(**net.config())`` builds the
        same architecture.

        Examples
        --------
        >>> MatchingNet(features=8, layers=2).config()
        {'features': 8, 'layers': 2, 'kernel': 3}
        """
        return {"features": self.features, "layers": self.layers, "kernel": self.kernel}

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Unit features of a batch of grey images (B, 1, H, W) -> (B, F, H - 8, W - 8)."""
        return F.normalize(self.body(x), dim=1)


@torch.no_grad()
def dense_features(net: MatchingNet, image) -> torch.Tensor:
    """Features of every pixel of one grey image, computed once.

    Parameters
    ----------
    net : MatchingNet
    image : numpy.ndarray, shape (H, W)
        A network input (:func:`stereovar.probe.inputs.network_input`).

    Returns
    -------
    torch.Tensor, shape (F, H - 2b, W - 2b)
        With :math:`b` = :func:`border`; on the network's device.
    """
    x = torch.as_tensor(np.ascontiguousarray(image, dtype=np.float32))[None, None]
    x = x.to(next(net.parameters()).device)
    return net.eval()(x)[0]


@torch.no_grad()
def score_volume(feat_left, feat_right, *, sign: int, max_disparity: int) -> torch.Tensor:
    """The learned matching score of every left pixel and disparity.

    .. math::

        S(x, y, d) = \\langle f_L(x, y), f_R(x + s d, y) \\rangle, \\qquad
        d = 0, \\dots, D,

    and :math:`-\\infty` where :math:`x + s d` leaves the feature map.

    Parameters
    ----------
    feat_left, feat_right : torch.Tensor, shape (F, h, w)
    sign : {1, -1}, keyword-only
        :math:`s`, the ground truth's ``disparity_sign`` (right pixel at :math:`x + s d`).
    max_disparity : int, keyword-only

    Returns
    -------
    torch.Tensor, shape (D + 1, h, w)
        On the features' device.

    Examples
    --------
    >>> f = torch.nn.functional.normalize(torch.randn(8, 3, 10), dim=0)
    >>> s = score_volume(f[:, :, :-2], f[:, :, 2:], sign=-1, max_disparity=3)
    >>> bool((s.argmax(0)[:, 2:] == 2).all())
    True
    """
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    if feat_left.shape != feat_right.shape:
        raise ValueError(
            f"left and right features differ: {tuple(feat_left.shape)} vs "
            f"{tuple(feat_right.shape)}"
        )
    _, h, w = feat_left.shape
    out = torch.full((int(max_disparity) + 1, h, w), -torch.inf, device=feat_left.device)
    for d in range(int(max_disparity) + 1):
        if d >= w:
            break
        if sign > 0:
            out[d, :, : w - d] = (feat_left[:, :, : w - d] * feat_right[:, :, d:]).sum(0)
        else:
            out[d, :, d:] = (feat_left[:, :, d:] * feat_right[:, :, : w - d]).sum(0)
    return out


def wta_disparity(
    net: MatchingNet, left, right, *, sign: int, max_disparity: int
) -> np.ndarray:
    """Winner-take-all disparity of a grey pair: dense features once per view, one dot product
    per disparity, the best score per pixel; no aggregation, no SGM.

    .. math::

        \\hat d(x, y) = \\arg\\max_{0 \\le d \\le D} S(x, y, d)

    Parameters
    ----------
    net : MatchingNet
    left, right : numpy.ndarray, shape (H, W)
        Network inputs of the two views.
    sign : {1, -1}, keyword-only
    max_disparity : int, keyword-only

    Returns
    -------
    numpy.ndarray, float64, shape (H, W)
        :math:`\\hat d`; NaN in the :func:`border` the features do not reach.
    """
    if np.shape(left) != np.shape(right) or np.ndim(left) != 2:
        raise ValueError(
            f"left and right must be grey images of one shape, got {np.shape(left)} and "
            f"{np.shape(right)}"
        )
    fl, fr = dense_features(net, left), dense_features(net, right)
    return wta_from_features(
        fl, fr, sign=sign, max_disparity=max_disparity, border_px=border(net.layers, net.kernel)
    )


def wta_from_features(
    feat_left, feat_right, *, sign: int, max_disparity: int, border_px: int = border()
) -> np.ndarray:
    """:func:`wta_disparity` from features already computed (a view shared by several test
    inputs is computed once).

    Parameters
    ----------
    feat_left, feat_right : torch.Tensor, shape (F, H - 2b, W - 2b)
        :func:`dense_features` of the two views.
    sign : {1, -1}, keyword-only
    max_disparity : int, keyword-only
    border_px : int, keyword-only
        :math:`b`, the network's :func:`border`.

    Returns
    -------
    numpy.ndarray, float64, shape (H, W)
        :math:`\\hat d`, NaN in the border.
    """
    _, h, w = feat_left.shape
    b = int(border_px)
    volume = score_volume(feat_left, feat_right, sign=sign, max_disparity=max_disparity)
    out = np.full((h + 2 * b, w + 2 * b), np.nan)
    out[b : b + h, b : b + w] = volume.argmax(0).cpu().numpy().astype(np.float64)
    return out


CHUNK_PIXELS = {"cpu": 65_536, "cuda": 8_000_000}
"""Image pixels per pass of :func:`predict_matcher` by device type (at least one image a
pass). On the CPU one image at a time is fastest (a batch's activations leave the cache:
4 images of 320x180 took twice as long per image on one thread); a GPU wants large batches,
about ``CHUNK_PIXELS * features * 4`` bytes per activation (2 GB at 64 maps)."""


def _chunk_pixels(device: torch.device, chunk_pixels) -> int:
    if chunk_pixels is not None:
        return max(1, int(chunk_pixels))
    return CHUNK_PIXELS.get(device.type, CHUNK_PIXELS["cuda"])


@torch.no_grad()
def batch_features(net: MatchingNet, images, *, chunk_pixels: int | None = None) -> torch.Tensor:
    """Features of a stack of grey images of one shape, in forward passes of at most
    ``chunk_pixels`` image pixels (at least one image each; default :data:`CHUNK_PIXELS` of
    the network's device), in channels-last layout (1.6x faster on one CPU thread).

    Parameters
    ----------
    net : MatchingNet
    images : sequence of numpy.ndarray, shape (H, W)
    chunk_pixels : int, optional, keyword-only

    Returns
    -------
    torch.Tensor, shape (B, F, H - 2b, W - 2b)
        On the network's device.
    """
    device = next(net.parameters()).device
    stack = torch.from_numpy(np.ascontiguousarray(np.stack(images), dtype=np.float32))[:, None]
    pixels = max(1, stack.shape[2] * stack.shape[3])
    per = max(1, _chunk_pixels(device, chunk_pixels) // pixels)
    net = net.eval()
    layout = torch.channels_last
    return torch.cat(
        [
            net(stack[i : i + per].to(device).contiguous(memory_format=layout)).contiguous()
            for i in range(0, len(stack), per)
        ]
    )


@torch.no_grad()
def _wta_batch(feat_left, feat_right, *, sign: int, max_disparity: int) -> torch.Tensor:
    """Winner-take-all disparity index (B, h, w) of batched features (B, F, h, w): the first
    :math:`d` of the highest score, as :func:`score_volume` then ``argmax`` gives it."""
    _, _, h, w = feat_left.shape
    best = (feat_left * feat_right).sum(1)
    arg = torch.zeros(best.shape, dtype=torch.int64, device=best.device)
    for d in range(1, min(int(max_disparity), w - 1) + 1):
        score = torch.full_like(best, -torch.inf)
        if sign > 0:
            score[..., : w - d] = (feat_left[..., : w - d] * feat_right[..., d:]).sum(1)
        else:
            score[..., d:] = (feat_left[..., d:] * feat_right[..., : w - d]).sum(1)
        better = score > best  # strict: ties keep the smaller d, as argmax does
        best = torch.where(better, score, best)
        arg = torch.where(better, torch.full_like(arg, d), arg)
    return arg


def predict_matcher(
    net: MatchingNet, pairs, *, sign: int, max_disparity: int, chunk_pixels: int | None = None
) -> list[np.ndarray]:
    """:func:`wta_disparity` of many pairs at once: the features of every distinct image of
    the pairs in batched forward passes, then the winner-take-all scan of all pairs together.

    .. math::

        \\hat d_k(x, y) = \\arg\\max_{0 \\le d \\le D}
            \\langle f(L_k)(x, y),\\, f(R_k)(x + s d, y) \\rangle

    An image passed in several pairs (the same array object, e.g. a left render shared by
    several counterfactual inputs) goes through the network once.

    Parameters
    ----------
    net : MatchingNet
    pairs : sequence of (left, right)
        Network inputs (H, W) float32 (:func:`stereovar.probe.inputs.network_input`); pairs of
        one shape are batched together.
    sign : {1, -1}, keyword-only
        :math:`s` (right pixel at :math:`x + s d`).
    max_disparity : int, keyword-only
        :math:`D`.
    chunk_pixels : int, optional, keyword-only
        Image pixels per forward pass and per scan (default :data:`CHUNK_PIXELS` of the
        network's device).

    Returns
    -------
    list of numpy.ndarray, float64, shape (H, W)
        :math:`\\hat d` of each pair, NaN in the :func:`border`; on the CPU.

    Examples
    --------
    >>> net = MatchingNet(features=4, layers=1)
    >>> x = np.random.default_rng(0).standard_normal((6, 12)).astype(np.float32)
    >>> out = predict_matcher(net, [(x, x), (x, x)], sign=1, max_disparity=2)
    >>> len(out), out[0].shape, bool((out[0][1:-1, 1:-1] == 0).all())
    (2, (6, 12), True)
    """
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    pairs = [(np.asarray(a), np.asarray(b)) for a, b in pairs]
    for a, b in pairs:
        if a.shape != b.shape or a.ndim != 2:
            raise ValueError(
                f"left and right must be grey images of one shape, got {a.shape} and {b.shape}"
            )
    b_px = border(net.layers, net.kernel)
    out: list = [None] * len(pairs)
    for shape in dict.fromkeys(a.shape for a, _ in pairs):
        members = [k for k, (a, _) in enumerate(pairs) if a.shape == shape]
        slot: dict = {}  # id of an image -> its row in the feature stack
        images = []
        for k in members:
            for image in pairs[k]:
                if id(image) not in slot:
                    slot[id(image)] = len(images)
                    images.append(image)
        feats = batch_features(net, images, chunk_pixels=chunk_pixels)
        per = max(1, _chunk_pixels(feats.device, chunk_pixels) // max(1, shape[0] * shape[1]))
        for i in range(0, len(members), per):
            chunk = members[i : i + per]
            rows_l = torch.tensor([slot[id(pairs[k][0])] for k in chunk], device=feats.device)
            rows_r = torch.tensor([slot[id(pairs[k][1])] for k in chunk], device=feats.device)
            arg = _wta_batch(
                feats[rows_l], feats[rows_r], sign=sign, max_disparity=max_disparity
            ).cpu().numpy()
            for k, a in zip(chunk, arg, strict=True):
                d_hat = np.full(shape, np.nan)
                d_hat[b_px : shape[0] - b_px, b_px : shape[1] - b_px] = a
                out[k] = d_hat
    return out
