"""Block-shuffle decorrelation of the right view's Monte Carlo residuals (paper Sec. 3.4).

The intervention of the causal experiment splits every right render into the across-seed mean
and a residual, :math:`I_R^{(n)} = \\bar I_R + \\epsilon_R^{(n)}`, and moves the residual's
``block`` x ``block`` tiles by one fixed permutation :math:`\\Pi`,
:math:`\\tilde I_R^{(n)} = \\bar I_R + \\Pi(\\epsilon_R^{(n)})`. The clean image is kept; only the
spatial alignment between :math:`\\sigma_L^2` and :math:`\\sigma_R^2` is destroyed.

:func:`block_permutation` draws :math:`\\Pi` as a tile index array and
:func:`apply_block_permutation` moves the tiles of one field; the intervention
(:mod:`stereovar.intervention.metrics`) applies it to each seed's residual as it streams.
"""

from __future__ import annotations

import operator

import numpy as np
import xarray as xr

IMAGE_DIMS = ("y", "x")
"""Spatial dims of a field; any other dim (e.g. ``channel``) is carried along."""


def _check_block(height: int, width: int, block) -> int:
    """``block`` as an int in ``[1, min(height, width)]``; one-line ValueError otherwise."""
    try:
        b = operator.index(block)
    except TypeError:
        raise ValueError(f"block must be an integer, got {block!r}") from None
    if b < 1 or b > min(height, width):
        raise ValueError(
            f"block must be between 1 and min(height, width) = {min(height, width)} "
            f"for a {height}x{width} image, got block={b}"
        )
    return b


def _tile_grid(height: int, width: int, block: int) -> tuple[int, int]:
    """Number of full tiles along y and x."""
    return height // block, width // block


def block_permutation(height: int, width: int, *, block: int = 16, seed: int = 0) -> np.ndarray:
    """Fixed random permutation :math:`\\Pi` of the full ``block`` x ``block`` tiles of an image.

    The image is cut into :math:`T_y = \\lfloor H / b \\rfloor` by :math:`T_x = \\lfloor W / b
    \\rfloor` full tiles, numbered row-major, :math:`k = i\\,T_x + j` for the tile covering
    rows :math:`[i b, (i+1) b)` and columns :math:`[j b, (j+1) b)`. The returned array
    :math:`\\pi` is a permutation of :math:`0, \\dots, T_y T_x - 1` drawn with
    ``numpy.random.default_rng(seed)``; as a gather (paper Sec. 3.4)

    .. math::

        \\Pi(f)\\bigl|_{\\text{tile } k} = f\\bigl|_{\\text{tile } \\pi_k},

    and the strips at the right and bottom edge that do not hold a full tile are not part of
    :math:`\\Pi` (they stay where they are).

    Parameters
    ----------
    height, width : int
        Image size :math:`H \\times W`.
    block : int, keyword-only
        Tile side :math:`b` in pixels, ``1 <= block <= min(height, width)``.
    seed : int, keyword-only
        Seed of ``numpy.random.default_rng``; the same seed gives the same :math:`\\Pi`.

    Returns
    -------
    perm : numpy.ndarray of int64, shape (T_y * T_x,)
        Source tile of each destination tile, for :func:`apply_block_permutation`.

    Raises
    ------
    ValueError
        If ``block`` is not an integer in ``[1, min(height, width)]``.
    """
    height, width = operator.index(height), operator.index(width)
    if height < 1 or width < 1:
        raise ValueError(f"image size must be positive, got {height}x{width}")
    b = _check_block(height, width, block)
    ny, nx = _tile_grid(height, width, b)
    return np.random.default_rng(seed).permutation(ny * nx).astype(np.int64)


def _apply_numpy(arr: np.ndarray, perm: np.ndarray, block: int) -> np.ndarray:
    """Gather the full tiles of ``arr`` (y, x first, any trailing dims) by ``perm``."""
    height, width = arr.shape[:2]
    b = _check_block(height, width, block)
    ny, nx = _tile_grid(height, width, b)
    perm = np.asarray(perm)
    if perm.shape != (ny * nx,) or not np.array_equal(np.sort(perm), np.arange(ny * nx)):
        raise ValueError(
            f"perm must be a permutation of the {ny * nx} full {b}x{b} tiles of a "
            f"{height}x{width} image, got shape {perm.shape}"
        )
    rest = arr.shape[2:]
    core = arr[: ny * b, : nx * b]
    tiles = core.reshape(ny, b, nx, b, *rest).swapaxes(1, 2).reshape(ny * nx, b, b, *rest)
    moved = tiles[perm].reshape(ny, nx, b, b, *rest).swapaxes(1, 2).reshape(core.shape)
    out = arr.copy()
    out[: ny * b, : nx * b] = moved
    return out


def apply_block_permutation(field, perm, *, block: int = 16):
    """Move the full tiles of a field by :math:`\\Pi` (paper Sec. 3.4).

    .. math::

        \\Pi(f)(i b + u,\\, j b + v) = f\\bigl(i' b + u,\\, j' b + v\\bigr), \\qquad
        \\pi_{i T_x + j} = i' T_x + j', \\quad 0 \\le u, v < b,

    for every full tile :math:`(i, j)`; pixels outside the full tiles (the right and bottom
    strips narrower than ``block``) are copied unchanged. Values are moved, not resampled, so
    the dtype is kept.

    Parameters
    ----------
    field : numpy.ndarray, shape (H, W) or (H, W, C), or xarray.DataArray
        The field; a DataArray needs dims ``y`` and ``x`` (any order) and may have one more
        dim (e.g. ``channel``).
    perm : numpy.ndarray of int
        Tile permutation from :func:`block_permutation` for this image size and ``block``.
    block : int, keyword-only
        Tile side in pixels, the one ``perm`` was drawn with.

    Returns
    -------
    moved : same type, shape and dims as ``field``

    Raises
    ------
    ValueError
        If ``field`` has the wrong shape or dims, ``block`` is out of range, or ``perm`` does
        not permute this image's full tiles.
    """
    if isinstance(field, xr.DataArray):
        missing = [d for d in IMAGE_DIMS if d not in field.dims]
        if missing or field.ndim not in (2, 3):
            raise ValueError(f"field must have dims (y, x[, channel]), got {field.dims}")
        extra = [d for d in field.dims if d not in IMAGE_DIMS]
        f = field.transpose(*IMAGE_DIMS, *extra)
        return f.copy(data=_apply_numpy(f.values, perm, block)).transpose(*field.dims)
    arr = np.asarray(field)
    if arr.ndim not in (2, 3):
        raise ValueError(f"field must have shape (H, W) or (H, W, C), got {arr.shape}")
    return _apply_numpy(arr, perm, block)
