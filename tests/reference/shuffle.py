"""In-memory residual split and decorrelation: the reference for the streamed intervention.

Holds every seed at once; :func:`stereovar.intervention.metrics.intervention_metrics` streams
the same operation. Used only by the tests.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from stereovar.intervention.shuffle import IMAGE_DIMS, _apply_numpy, block_permutation


def split_residuals(images, *, dim: str = "seed"):
    """Split renders into the across-seed mean and per-seed residuals (paper Sec. 3.4).

    .. math::

        I^{(n)} = \\bar I + \\epsilon^{(n)}, \\qquad
        \\bar I = \\frac1N \\sum_{n=1}^{N} I^{(n)}, \\qquad \\epsilon^{(n)} = I^{(n)} - \\bar I,

    in float64, so :math:`\\sum_n \\epsilon^{(n)} = 0` up to rounding.

    Parameters
    ----------
    images : numpy.ndarray, shape (N, ...), or xarray.DataArray
        Renders stacked over seeds (seeds first for numpy); a DataArray needs the dim ``dim``.
    dim : str, keyword-only
        Name of the seed dim of a DataArray.

    Returns
    -------
    clean : numpy.ndarray (...) or xarray.DataArray (without ``dim``), float64
        Seed mean :math:`\\bar I`.
    residuals : numpy.ndarray (N, ...) or xarray.DataArray (dims of ``images``), float64
        :math:`\\epsilon^{(n)}`.
    """
    if isinstance(images, xr.DataArray):
        if dim not in images.dims:
            raise ValueError(f"images must have the seed dim {dim!r}, got {images.dims}")
        if images.sizes[dim] == 0:
            raise ValueError(f"images must hold at least one render along {dim!r}")
        stack = images.astype(np.float64)
        clean = stack.mean(dim)
        residuals = (stack - clean).transpose(*images.dims)
        return clean, residuals
    stack = np.asarray(images, dtype=np.float64)
    if stack.ndim < 1 or stack.shape[0] == 0:
        raise ValueError(f"images must have shape (N, ...) with N >= 1, got {stack.shape}")
    clean = stack.mean(axis=0)
    return clean, stack - clean


def decorrelate_right(images_right, *, block: int = 16, seed: int = 0, dim: str = "seed"):
    """Decorrelation operator of the causal experiment (paper Sec. 3.4).

    .. math::

        I_R^{(n)} = \\bar I_R + \\epsilon_R^{(n)}, \\qquad
        \\tilde I_R^{(n)} = \\bar I_R + \\Pi\\bigl(\\epsilon_R^{(n)}\\bigr),

    with one tile permutation :math:`\\Pi` (:func:`block_permutation` with ``seed``) applied to
    every seed :math:`n`. Since :math:`\\Pi` is linear and the same for all :math:`n`, the seed
    mean of :math:`\\tilde I_R` is :math:`\\bar I_R` and the per-pixel variance moves with the
    tiles, :math:`\\tilde\\sigma_R^2 = \\Pi(\\sigma_R^2)`.

    Parameters
    ----------
    images_right : numpy.ndarray, shape (N, H, W) or (N, H, W, C), or xarray.DataArray
        Right renders stacked over seeds (seeds first for numpy); a DataArray needs dims
        ``dim``, ``y``, ``x`` and optionally ``channel``, in any order.
    block : int, keyword-only
        Tile side in pixels (16 in the paper).
    seed : int, keyword-only
        Seed of :math:`\\Pi`.
    dim : str, keyword-only
        Name of the seed dim of a DataArray.

    Returns
    -------
    decorrelated : same type, shape and dims as ``images_right``, float64
        :math:`\\tilde I_R^{(n)}`.
    """
    if isinstance(images_right, xr.DataArray):
        if dim not in images_right.dims or any(d not in images_right.dims for d in IMAGE_DIMS):
            raise ValueError(
                f"images_right must have dims ({dim}, y, x[, channel]), got {images_right.dims}"
            )
        if images_right.ndim not in (3, 4):
            raise ValueError(
                f"images_right must have dims ({dim}, y, x[, channel]), got {images_right.dims}"
            )
        extra = [d for d in images_right.dims if d not in (dim, *IMAGE_DIMS)]
        stack = images_right.transpose(dim, *IMAGE_DIMS, *extra)
        out = decorrelate_right(stack.values, block=block, seed=seed)
        return stack.copy(data=out).transpose(*images_right.dims)
    stack = np.asarray(images_right)
    if stack.ndim not in (3, 4) or stack.shape[0] == 0:
        raise ValueError(
            f"images_right must have shape (N, H, W) or (N, H, W, C) with N >= 1, got {stack.shape}"
        )
    height, width = stack.shape[1:3]
    perm = block_permutation(height, width, block=block, seed=seed)
    clean, residuals = split_residuals(stack)
    # (N, H, W, ...) -> (H, W, ..., N): one gather moves the tiles of every seed at once.
    shuffled = np.moveaxis(_apply_numpy(np.moveaxis(residuals, 0, -1), perm, block), -1, 0)
    return clean[None] + shuffled
