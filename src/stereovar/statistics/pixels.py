"""One region's pixels and the work its statistics share (paper Sec. 2.3, 3.1).

Every registered statistic of a region (:mod:`stereovar.statistics.registry`) reads the same
fields at the same pixels: :math:`\\sigma_L^2` alone enters Eq. 3, Spearman, the logarithms,
the trimming, the no-warp baseline, the intensity control and each split half's reliability.
:class:`PixelSet` gathers a field's values over the region once, and keeps the region's
tile labels (the block bootstrap) and the medians the firefly count needs, so a scene's
dozens of statistics cost one pass per field and not one per statistic.
"""

from __future__ import annotations

import numpy as np


class PixelSet:
    """The pixels of one region with cached per-field values.

    Parameters
    ----------
    mask : array_like of bool, shape (H, W)
        The region (e.g. :math:`\\Omega \\cap G`).
    labels : array_like of int, shape (H, W), optional
        Bootstrap tile of each pixel (:func:`stereovar.statistics.bootstrap.tile_labels`).
    parent : PixelSet, optional
        A set holding every pixel of this one (e.g. :math:`\\Omega` for
        :math:`\\Omega \\cap G`): a field's values here are taken from the parent's cached
        values, so a field computed pixel by pixel (a warp) is evaluated once for both.

    Notes
    -----
    Values are cached by the identity of the field array, and the set holds a reference to
    each array it has read, so an identity is never reused while the set lives. Fields must
    not be modified in place after they were read.
    """

    def __init__(self, mask, labels=None, *, parent: PixelSet | None = None):
        mask = np.asarray(mask, dtype=bool)
        self.shape = mask.shape
        self.index = np.flatnonzero(mask)
        self.tiles = None
        if labels is not None:
            # tile-major order: each tile's pixels are contiguous, so per-tile sums are one
            # sequential pass (numpy.add.reduceat); no statistic depends on the order
            tiles = np.asarray(labels).ravel()[self.index]
            order = np.argsort(tiles, kind="stable")
            self.index, self.tiles = self.index[order], tiles[order]
        self.parent, self._positions = parent, None
        if parent is not None:
            where = np.full(mask.size, -1, dtype=np.int64)
            where[parent.index] = np.arange(parent.size)
            self._positions = where[self.index]
            if self._positions.size and self._positions.min() < 0:
                raise ValueError("a PixelSet's parent must hold every one of its pixels")
        self._values: dict[int, tuple] = {}
        self._medians: dict[int, tuple] = {}
        self._nonfinite: dict[int, tuple] = {}

    @property
    def size(self) -> int:
        """Number of pixels in the region."""
        return int(self.index.size)

    def values(self, field) -> np.ndarray:
        """float64 (n,): ``field`` (H, W) at the region's pixels, in :attr:`index` order
        (row-major, or tile-major when built with tile labels; cached). A field with an
        ``at(index)`` method (:class:`~stereovar.statistics.warp.WarpedField`) is evaluated
        at those pixels only, or at the parent's."""
        key = id(field)
        hit = self._values.get(key)
        if hit is None:
            if self.parent is not None:
                values = self.parent.values(field)[self._positions]
            elif hasattr(field, "at"):  # computed only where needed (a WarpedField)
                values = np.asarray(field.at(self.index), dtype=np.float64)
            else:
                values = np.asarray(field).reshape(-1)[self.index].astype(np.float64, copy=False)
            hit = (field, values)
            self._values[key] = hit
        return hit[1]

    def forget(self) -> None:
        """Drop every cached value (e.g. between seed subsets, whose fields are read once)."""
        self._values.clear()
        self._medians.clear()
        self._nonfinite.clear()

    def median(self, values) -> float:
        """Median of a value array of this set (cached for the arrays :meth:`values` gave)."""
        key = id(values)
        hit = self._medians.get(key)
        if hit is None:
            hit = (values, float(np.median(values)) if values.size else float("nan"))
            self._medians[key] = hit
        return hit[1]

    def nonfinite(self, values) -> np.ndarray | None:
        """bool (n,) marking the non-finite entries of a value array, or None when it has
        none (cached for the arrays :meth:`values` gave)."""
        key = id(values)
        hit = self._nonfinite.get(key)
        if hit is None:
            bad = None
            if not np.isfinite(np.sum(values)):  # one pass; a huge finite sum is rechecked
                bad = ~np.isfinite(values)
                bad = bad if bad.any() else None
            hit = (values, bad)
            self._nonfinite[key] = hit
        return hit[1]
