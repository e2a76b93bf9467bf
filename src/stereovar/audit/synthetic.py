"""Synthetic stereo renders with a known cross-view variance correlation, written as files.

The audit's test data and the files of ``stereovar init --example``: a textured slanted
plane whose disparity is an integer per row (so the warp of Eq. 2 is exact and nothing is
occluded), per-pixel variance
fields of the two views whose Pearson correlation after the warp is known, and N noisy
"renders" per view, each the clean image plus zero-mean Gaussian noise scaled by the view's
variance field.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io.writers import write_field, write_image
from ..rig import VIEWS


def _blocks(rng, height, width, block):
    """A field constant on ``block`` x ``block`` tiles, standard normal per tile."""
    tiles = rng.standard_normal((-(-height // block), -(-width // block)))
    return np.kron(tiles, np.ones((block, block)))[:height, :width]


def shift_rows(field, shift):
    """``out[y, x] = field[y, x - shift[y]]`` (integer shift per row; 0 where it leaves the
    image): the right view of a left field when :math:`x_R = x_L + \\text{shift}`."""
    out = np.zeros_like(field)
    width = field.shape[1]
    for y, s in enumerate(np.asarray(shift, dtype=np.int64)):
        if s >= 0:
            out[y, s:] = field[y, : width - s]
        else:
            out[y, : width + s] = field[y, -s:]
    return out


@dataclass
class SyntheticFrame:
    """One frame: clean images, variance fields, renders (view to (N, H, W, 3)) and the
    left disparity; ``rho`` is the Pearson correlation of the left variance field and the
    right one warped into the left, over the valid pixels."""

    clean: dict
    variance: dict
    renders: dict
    disparity: np.ndarray
    valid: np.ndarray
    rho: float


def synthetic_frame(
    *,
    width: int = 160,
    height: int = 96,
    n_seeds: int = 16,
    coupling: float = 0.7,
    spread: float = 0.6,
    level: float = 0.004,
    sign: int = -1,
    block: int = 8,
    seed: int = 0,
) -> SyntheticFrame:
    r"""A stereo frame whose variance fields correlate by a known amount after the warp.

    With :math:`Z_1, Z_2` independent block-constant standard normal fields,

    .. math::

        \sigma_L^2 = \ell\, e^{a Z_1}, \qquad
        \hat\sigma_{R\to L}^2 = \ell\, e^{a (c Z_1 + \sqrt{1 - c^2} Z_2)}, \qquad
        I_v^{(k)} = T_v + \sigma_v\, \varepsilon_v^{(k)},

    with :math:`a` = ``spread``, :math:`c` = ``coupling``, :math:`\ell` = ``level``,
    :math:`T` a textured clean image, the right-view fields the left-coordinate ones moved
    by the per-row integer disparity :math:`d(y)` (:math:`x_R = x_L + s\,d`) and
    :math:`\varepsilon` independent standard normal per seed, pixel and channel. ``rho`` is
    the Pearson correlation of :math:`\sigma_L^2` and :math:`\hat\sigma_{R\to L}^2` over the
    pixels whose match lies inside the right image.
    """
    rng = np.random.default_rng(seed)
    y = np.arange(height)
    disparity_rows = 3 + (6 * y) // height  # 3..8 px, integer: the warp is exact
    disparity = np.repeat(disparity_rows[:, None], width, axis=1).astype(np.float32)
    x_right = np.arange(width)[None, :] + sign * disparity
    valid = (x_right >= 0) & (x_right <= width - 1)
    texture = 0.25 + 0.6 * (0.5 + 0.5 * np.tanh(_blocks(rng, height, width, 4)))
    tint = np.array([1.0, 0.85, 0.7])
    z1, z2 = _blocks(rng, height, width, block), _blocks(rng, height, width, block)
    var_left = level * np.exp(spread * z1)
    var_right_in_left = level * np.exp(spread * (coupling * z1 + np.sqrt(1 - coupling**2) * z2))
    shift = sign * disparity_rows
    clean = {"left": texture[..., None] * tint}
    clean["right"] = np.stack([shift_rows(clean["left"][..., c], shift) for c in range(3)], -1)
    # the right image's columns that nothing in the left sees keep texture
    fill = _blocks(rng, height, width, 4)
    holes = shift_rows(np.ones((height, width)), shift) == 0
    clean["right"][holes] = (0.25 + 0.6 * (0.5 + 0.5 * np.tanh(fill[holes])))[:, None] * tint
    variance = {"left": var_left, "right": shift_rows(var_right_in_left, shift)}
    variance["right"][holes] = level
    renders = {
        v: (
            clean[v][None]
            + np.sqrt(variance[v])[None, ..., None]
            * rng.standard_normal((n_seeds, height, width, 3))
        ).astype(np.float32)
        for v in VIEWS
    }
    rho = float(np.corrcoef(var_left[valid], var_right_in_left[valid])[0, 1])
    return SyntheticFrame(clean, variance, renders, disparity, valid, rho)


def write_synthetic_audit(
    root,
    *,
    name: str = "synthetic",
    n_frames: int = 2,
    render_format: str = "exr",
    disparity_format: str = "pfm",
    convention: str = "conventional",
    **options,
) -> tuple[dict, list[SyntheticFrame]]:
    """Write :func:`synthetic_frame` frames as files under ``root`` and return the
    ``audit:`` settings that read them, and the frames.

    Layout: ``{root}/renders/{frame}/{L,R}/seed_{seed}.{render_format}`` and
    ``{root}/disparity/{frame}.{disparity_format}`` (the left view's; PNG in KITTI's
    encoding, value / 256).
    """
    root = Path(root)
    sign = 1 if convention == "paper" else -1
    frames = []
    for k in range(n_frames):
        frame = synthetic_frame(sign=sign, seed=k, **options)
        frames.append(frame)
        for view, letter in zip(VIEWS, "LR", strict=True):
            folder = root / "renders" / f"f{k:02d}" / letter
            folder.mkdir(parents=True, exist_ok=True)
            for s, image in enumerate(frame.renders[view]):
                write_image(folder / f"seed_{s:03d}.{render_format}", image)
        (root / "disparity").mkdir(parents=True, exist_ok=True)
        write_field(root / "disparity" / f"f{k:02d}.{disparity_format}", frame.disparity)
    settings = {
        "name": name,
        "renders": f"{root}/renders/{{frame}}/{{view}}/seed_{{seed}}.{render_format}",
        "views": {"left": "L", "right": "R"},
        "disparity": f"{root}/disparity/{{frame}}.{disparity_format}",
        "convention": convention,
    }
    return settings, frames


def slanted_texture_means(
    seed: int,
    *,
    noise: float = 0.02,
    fmax: float = 0.25,
    width: int = 96,
    height: int = 64,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Seed means of a smooth texture seen by both views through a slanted plane, with a
    fractional disparity known exactly (the offset check's test and calibration frames,
    :mod:`stereovar.audit.offset`).

    The texture is a sum of 12 sinusoids (up to ``fmax`` cycles/px along x), evaluated
    exactly at each view's pixel: the left pixel :math:`x` sees :math:`T(x, y)` and the right
    pixel :math:`u` the texture point of the left pixel with

    .. math::

        u = x - d(x, y), \qquad d(x, y) = a + b\,y + c\,x,

    :math:`a` in 4-8 px, :math:`b\,H` in 2-4 px, :math:`|c| \le 0.02` (the conventional rig).
    Gaussian noise of standard deviation ``noise`` is added to each view's mean.

    Returns
    -------
    left, right : numpy.ndarray (H, W, 3)
        The views' seed means (grey).
    disparity : numpy.ndarray (H, W)
        The left view's disparity, px.

    Examples
    --------
    >>> left, right, d = slanted_texture_means(0, noise=0.0, width=32, height=8)
    >>> left.shape, right.shape, bool((d > 3.9).all() and (d < 13).all())
    ((8, 32, 3), (8, 32, 3), True)
    """
    rng = np.random.default_rng(seed)
    freq_x, freq_y = rng.uniform(0.02, fmax, 12), rng.uniform(-0.1, 0.1, 12)
    phase, amp = rng.uniform(0, 2 * np.pi, 12), rng.uniform(0.5, 1.0, 12)
    amp *= 0.3 / amp.sum()

    def texture(x, y):
        waves = amp * np.sin(2 * np.pi * (freq_x * x[..., None] + freq_y * y[..., None]) + phase)
        return 0.5 + waves.sum(axis=-1)

    a, b, c = rng.uniform(4, 8), rng.uniform(2, 4) / height, rng.uniform(-0.02, 0.02)
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    left = texture(x, y) + noise * rng.standard_normal((height, width))
    # u = x - d(x)  <=>  x = (u + a + b y) / (1 - c)
    right = texture((x + a + b * y) / (1 - c), y) + noise * rng.standard_normal((height, width))
    return left[..., None].repeat(3, -1), right[..., None].repeat(3, -1), a + b * y + c * x

