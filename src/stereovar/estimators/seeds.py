"""Per-pixel Monte Carlo variance over independent seeds (paper Sec. 2.1, Eq. 1).

The ``seeds`` estimator (:class:`SeedEstimator`) and the one implementation of Eq. 1 that the
workflow, the intervention and notebooks share.

:func:`variance_field` is the batch estimator on a stack of renders held in memory;
:class:`StreamingVariance` accumulates the same estimate one render at a time (shifted sums
in float64), so peak memory does not grow with the number of seeds; :func:`variance_from_stores`
and :func:`variance_dataset` stream render stores (:mod:`stereovar.io.renders`) from disk into
it and build the variance contract (:mod:`stereovar.io.contracts`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..io.renders import IMAGE_DIMS, iter_renders
from ..io.store import store_error
from ..rig import VIEWS
from .base import VarianceEstimator
from .subsets import MIN_SPLIT_SEEDS, SeedSubsets, subset_dataset

ESTIMATOR = "population variance (1/N) over seeds, averaged over RGB channels (Eq. 1)"


def variance_field(images, *, dim: str = "seed"):
    """Seed mean and RGB-averaged per-pixel Monte Carlo variance of a stack of renders.

    For view :math:`V` and :math:`N` independent renders :math:`I_V^{(n)}` (paper Sec. 2.1),

    .. math::

        \\bar I_V(x, y) = \\frac1N \\sum_{n=1}^{N} I_V^{(n)}(x, y), \\qquad
        \\sigma_V^2(x, y) = \\frac13 \\sum_{c \\in \\{R,G,B\\}} \\frac1N \\sum_{n=1}^{N}
            \\bigl(I_{V,c}^{(n)}(x, y) - \\bar I_{V,c}(x, y)\\bigr)^2

    (Eq. 1, population variance, averaged over the colour channels), accumulated in float64
    with two passes (mean first, then squared deviations). Non-finite values propagate; use
    :class:`StreamingVariance` to flag them instead.

    Parameters
    ----------
    images : numpy.ndarray, shape (N, H, W, C), or xarray.DataArray
        Renders stacked over seeds (seeds first for numpy); a DataArray needs the dims
        ``dim``, ``y``, ``x`` and ``channel`` in any order.
    dim : str, keyword-only
        Name of the seed dim of a DataArray.

    Returns
    -------
    mean : numpy.ndarray (H, W, C) or xarray.DataArray (y, x, channel), float64
        Seed mean per channel.
    variance : numpy.ndarray (H, W) or xarray.DataArray (y, x), float64
        Eq. 1 averaged over channels.

    Examples
    --------
    Two seeds of a 1 x 2 image. Pixel (0, 0) reads 0 in every channel at the first seed and
    (2, 4, 0) at the second, so its per-channel means are (1, 2, 0) and its per-channel
    population variances :math:`\\frac12 \\sum_n (I^{(n)} - \\bar I)^2` are (1, 4, 0), whose
    RGB average is 5/3. Pixel (0, 1) reads 5 at both seeds: variance 0.

    >>> import numpy as np
    >>> renders = np.zeros((2, 1, 2, 3))  # (N seeds, H, W, RGB)
    >>> renders[1, 0, 0] = [2.0, 4.0, 0.0]
    >>> renders[:, 0, 1] = 5.0
    >>> mean, variance = variance_field(renders)
    >>> mean[0, 0].tolist(), mean[0, 1].tolist()
    ([1.0, 2.0, 0.0], [5.0, 5.0, 5.0])
    >>> np.round(variance, 4).tolist()
    [[1.6667, 0.0]]

    A DataArray keeps its coordinates; the seed dim is named by ``dim``:

    >>> import xarray as xr
    >>> stack = xr.DataArray(renders, dims=("seed", "y", "x", "channel"))
    >>> _, var = variance_field(stack)
    >>> var.dims, bool(np.allclose(var, variance))
    (('y', 'x'), True)
    """
    if isinstance(images, xr.DataArray):
        missing = [d for d in (dim, *IMAGE_DIMS) if d not in images.dims]
        if missing or images.ndim != 4:
            raise ValueError(f"images must have dims ({dim}, y, x, channel), got {images.dims}")
        stack = images.transpose(dim, *IMAGE_DIMS)
        mean, variance = variance_field(stack.values)
        first = stack.isel({dim: 0}, drop=True)
        mean_da = xr.DataArray(
            mean,
            dims=IMAGE_DIMS,
            coords=first.coords,
            name="mean",
            attrs={"long_name": "seed mean"},
        )
        var_da = xr.DataArray(
            variance,
            dims=("y", "x"),
            coords=first.isel(channel=0, drop=True).coords,
            name="variance",
            attrs={"long_name": ESTIMATOR},
        )
        return mean_da, var_da
    stack = np.asarray(images, dtype=np.float64)
    if stack.ndim != 4 or stack.shape[0] == 0:
        raise ValueError(f"images must have shape (N, H, W, C) with N >= 1, got {stack.shape}")
    mean = stack.mean(axis=0)
    deviations = stack - mean
    np.square(deviations, out=deviations)  # in place: one stack-sized temporary, not two
    return mean, deviations.mean(axis=0).mean(axis=-1)


def _as_image(image) -> np.ndarray:
    """One render (or a block of its rows) as float32 or float64 (h, W, C), as given."""
    if isinstance(image, xr.DataArray):
        image = image.transpose(*IMAGE_DIMS).values
    block = np.asarray(image)
    if block.dtype not in (np.float32, np.float64):
        block = block.astype(np.float32 if block.dtype.itemsize <= 2 else np.float64)
    if block.ndim != 3:
        raise ValueError(f"an image must have shape (H, W, C), got {block.shape}")
    return block


class StreamingVariance:
    """Streaming accumulator of Eq. 1 fed one render (or one row block of it) at a time.

    Each pixel and channel keeps float64 sums of the deviations from a per-pixel shift
    :math:`K` (the first render's value there; the shifted-data algorithm), so with :math:`N`
    renders added (paper Sec. 2.1, Eq. 1)

    .. math::

        S_1 = \\sum_n \\bigl(I^{(n)} - K\\bigr), \\quad
        S_2 = \\sum_n \\bigl(I^{(n)} - K\\bigr)^2, \\quad
        \\bar I = K + \\frac{S_1}{N}, \\quad
        \\sigma^2 = \\frac13 \\sum_c \\frac{S_{2,c} - S_{1,c}^2 / N}{N}.

    Shifting by a sample of the same pixel keeps the sums small, so large offsets (radiance
    ``1e4`` with small noise) stay accurate; deviations and sums are float64. The sums are
    kept apart for the even- and the odd-indexed renders (their totals give the estimate), so
    the split halves of :attr:`half_variance` cost no extra pass. Memory is five float64
    images whatever :math:`N`, and an update is four passes over the render.

    A pixel with a NaN or Inf in any channel of a render is counted in :attr:`n_nonfinite`;
    that render contributes nothing there (so the accumulator never holds a non-finite
    number and no other pixel is affected), and its :attr:`mean` and :attr:`variance` are
    reported as 0 with :attr:`finite` False.

    Parameters
    ----------
    shape : tuple of int (H, W, C), optional
        Image shape; taken from the first full render when omitted, and required to add row
        blocks before any full render.

    Examples
    --------
    The same estimate as :func:`variance_field`, one render at a time: the values 0, 2 and 4
    at one pixel have mean 2 and population variance :math:`(4 + 0 + 4) / 3 = 8/3`, in every
    channel, even on a large offset.

    >>> import numpy as np
    >>> acc = StreamingVariance()
    >>> for value in (0.0, 2.0, 4.0):
    ...     _ = acc.update(np.full((1, 1, 3), 1e4 + value))
    >>> acc.n, round(float(acc.mean[0, 0, 0]), 6), round(float(acc.variance[0, 0]), 6)
    (3, 10002.0, 2.666667)

    A NaN in a render is counted and that pixel is reported as not finite (0):

    >>> _ = acc.update(np.full((1, 1, 3), np.nan))
    >>> acc.n_nonfinite.tolist(), acc.finite.tolist(), acc.variance.tolist()
    ([[1]], [[False]], [[0.0]])
    """

    def __init__(self, shape: tuple[int, int, int] | None = None):
        self._shift = self._s1 = self._s2 = self._count = self._n_nonfinite = None
        if shape is not None:
            self._allocate(tuple(int(s) for s in shape))

    def _allocate(self, shape) -> None:
        if len(shape) != 3:
            raise ValueError(f"shape must be (H, W, C), got {shape}")
        self._shift = None  # allocated by the first update
        self._s1 = np.zeros((2, *shape), dtype=np.float64)  # even, odd renders
        self._s2 = np.zeros((2, *shape), dtype=np.float64)
        self._count = np.zeros(shape[0], dtype=np.int64)
        self._n_nonfinite = np.zeros(shape[:2], dtype=np.int32)

    @property
    def shape(self) -> tuple[int, int, int] | None:
        """Image shape (H, W, C), or None before the first update."""
        return None if self._s1 is None else self._s1.shape[1:]

    def update(self, image, *, rows: slice | None = None) -> StreamingVariance:
        """Add one render, or the row block ``rows`` of one render.

        Parameters
        ----------
        image : numpy.ndarray (H, W, C) or xarray.DataArray (y, x, channel)
            The render, or its rows ``rows`` only (any float dtype; accumulated in float64).
        rows : slice, keyword-only, optional
            Contiguous rows that ``image`` holds; every row must receive each render once.

        Returns
        -------
        StreamingVariance
            ``self``.
        """
        block = _as_image(image)
        if self._s1 is None:
            if rows is not None:
                raise ValueError("pass shape= to StreamingVariance before adding row blocks")
            self._allocate(block.shape)
        height = self.shape[0]
        start, stop, step = (rows or slice(None)).indices(height)
        if step != 1:
            raise ValueError(f"rows must be a contiguous slice, got {rows}")
        expected = (max(stop - start, 0), *self.shape[1:])
        if block.shape != expected:
            raise ValueError(f"image block has shape {block.shape}, expected {expected}")
        sl = slice(start, stop)
        if self._shift is None:
            self._shift = np.zeros(self.shape, dtype=np.float64)
        first = self._count[sl] == 0
        bad = None
        if not np.isfinite(block.sum()):  # one cheap pass; any NaN or Inf makes it non-finite
            bad = ~np.isfinite(block).all(axis=-1)
            self._n_nonfinite[sl] += bad
        if first.any():
            # The first render of these rows is the shift; a non-finite value shifts by 0.
            init = (
                np.where(bad[first][..., None], 0.0, block[first])
                if bad is not None
                else (block[first])
            )
            self._shift[sl][first] = init
        d = np.subtract(block, self._shift[sl], dtype=np.float64)
        if bad is not None:
            d[bad] = 0.0
        parity = int(self._count[start]) % 2 if stop > start else 0
        self._s1[parity, sl] += d
        np.multiply(d, d, out=d)
        self._s2[parity, sl] += d
        self._count[sl] += 1
        return self

    @property
    def n(self) -> int:
        """Number of renders added (0 before the first)."""
        if self._count is None or not self._count.size:
            return 0
        if self._count.min() != self._count.max():
            raise ValueError(
                f"rows received between {self._count.min()} and {self._count.max()} renders; "
                "add every row of each render"
            )
        return int(self._count[0])

    def _require(self) -> int:
        n = self.n
        if n == 0:
            raise ValueError("no render added yet")
        return n

    @property
    def finite(self) -> np.ndarray:
        """bool (H, W): no render had a NaN or Inf at the pixel."""
        self._require()
        return self._n_nonfinite == 0

    @property
    def n_nonfinite(self) -> np.ndarray:
        """int32 (H, W): number of renders with a NaN or Inf at the pixel."""
        self._require()
        return self._n_nonfinite.copy()

    @property
    def mean(self) -> np.ndarray:
        """float64 (H, W, C): seed mean per channel; 0 where not :attr:`finite`."""
        n = self._require()
        return np.where(self.finite[..., None], self._shift + self._s1.sum(axis=0) / n, 0.0)

    @property
    def variance(self) -> np.ndarray:
        """float64 (H, W): Eq. 1 (1/N) averaged over channels; 0 where not :attr:`finite`."""
        n = self._require()
        return self._channel_variance(self._s1.sum(axis=0), self._s2.sum(axis=0), n)

    @property
    def half_variance(self) -> np.ndarray | None:
        """float64 (2, H, W): Eq. 1 over the even- and over the odd-indexed renders (0-based,
        in the order added), 0 where not :attr:`finite`; None below
        :data:`~stereovar.estimators.subsets.MIN_SPLIT_SEEDS` renders."""
        n = self._require()
        if n < MIN_SPLIT_SEEDS:
            return None
        counts = ((n + 1) // 2, n // 2)
        return np.stack(
            [self._channel_variance(self._s1[h], self._s2[h], counts[h]) for h in range(2)]
        )

    def _channel_variance(self, s1, s2, n) -> np.ndarray:
        per_channel = np.maximum((s2 - s1 * s1 / n) / n, 0.0)
        return np.where(self.finite, per_channel.mean(axis=-1), 0.0)


def _blocks(paths, chunk_rows):
    """Yield ``(store, rows, block)`` for each row block of each render of each store in turn.

    The next block is read in a background thread while the caller processes the current one
    (zarr decompression and numpy both release the GIL), so reading and accumulating overlap;
    at most two blocks are in memory.
    """
    from concurrent.futures import ThreadPoolExecutor

    def tasks():
        for store, seed in iter_renders(paths):
            height = store.shape[0]
            step = int(chunk_rows or height) or 1
            for start in range(0, height, step):
                yield store, seed, slice(start, min(start + step, height))

    def read(task):
        store, seed, rows = task
        return store, rows, store.rows(rows, seed)

    with ThreadPoolExecutor(max_workers=1) as pool:
        pending = None
        for task in tasks():
            future = pool.submit(read, task)
            if pending is not None:
                yield pending.result()
            pending = future
        if pending is not None:
            yield pending.result()


def variance_from_stores(
    paths, *, chunk_rows: int | None = None, subsets: bool = True
) -> xr.Dataset:
    """Stream the render stores of one view into :class:`StreamingVariance` (Eq. 1).

    Stores are opened and read one at a time (``chunk_rows`` rows at a time when given), so
    peak memory is the float64 accumulator plus one block of one render, whatever the number
    of seeds.

    .. math::

        \\sigma^2(x, y) = \\frac13 \\sum_{c} \\frac1N \\sum_{n=1}^{N}
            \\bigl(I_c^{(n)}(x, y) - \\bar I_c(x, y)\\bigr)^2

    (paper Sec. 2.1, Eq. 1).

    Parameters
    ----------
    paths : sequence of path-like
        Render stores of one view (:mod:`stereovar.io.renders`); every render of every store
        is one seed.
    chunk_rows : int, keyword-only, optional
        Rows read per block; whole renders when omitted.
    subsets : bool, keyword-only
        Also accumulate the split halves and disjoint seed subsets
        (:class:`~stereovar.estimators.subsets.SeedSubsets`): ``half_variance`` and
        ``subset_variance``.

    Returns
    -------
    xarray.Dataset
        ``mean`` (y, x, channel) float32, ``variance`` (y, x) float64, ``finite`` (y, x) bool
        and ``n_nonfinite`` (y, x) int32 (see :class:`StreamingVariance`); attrs ``n_seeds``
        and ``estimator``. Coordinates come from the first store.

    Raises
    ------
    StoreError
        A store is missing, unreadable, lacks ``radiance``, misses chunks, or its shape differs
        from the first store's; the one-line message names the store and the rerun command.
    """
    paths = list(paths)
    if not paths:
        raise ValueError("no render stores given")
    if chunk_rows is not None and int(chunk_rows) < 1:
        raise ValueError(f"chunk_rows must be a positive integer, got {chunk_rows}")
    acc = None
    coords = {}
    split, render = (SeedSubsets() if subsets else None), None
    for radiance, rows, block in _blocks(paths, chunk_rows):
        if acc is None:
            acc = StreamingVariance(shape=radiance.shape)
            coords = radiance.coords
        elif radiance.shape != acc.shape:
            raise store_error(
                radiance.path, f"shape {radiance.shape} differs from {acc.shape} of {paths[0]}"
            )
        acc.update(block, rows=rows)
        if split is None:
            continue
        if rows.start == 0 and rows.stop == acc.shape[0]:
            split.update(block)
        else:
            if render is None:
                render = np.empty(acc.shape, dtype=block.dtype)
            render[rows] = block
            if rows.stop == acc.shape[0]:
                split.update(render)
    yx = ("y", "x")
    return xr.Dataset(
        {
            "mean": (IMAGE_DIMS, acc.mean.astype(np.float32), {"long_name": "seed mean"}),
            "variance": (yx, acc.variance, {"long_name": ESTIMATOR}),
            "finite": (yx, acc.finite, {"long_name": "no NaN or Inf in any seed"}),
            "n_nonfinite": (
                yx,
                acc.n_nonfinite.astype(np.int32),
                {"long_name": "number of seeds with a NaN or Inf; mean and variance are 0"},
            ),
        },
        coords=coords,
        attrs={"n_seeds": acc.n, "estimator": ESTIMATOR},
    ).merge(subset_dataset(split, acc.half_variance) if split is not None else xr.Dataset())


def variance_dataset(
    left_paths, right_paths, *, chunk_rows: int | None = None, subsets: bool = True
) -> xr.Dataset:
    """Variance fields of both views: the variance contract (:mod:`stereovar.io.contracts`).

    .. math::

        \\sigma_V^2(x, y) = \\frac13 \\sum_{c} \\frac1N \\sum_{n=1}^{N}
            \\bigl(I_{V,c}^{(n)}(x, y) - \\bar I_{V,c}(x, y)\\bigr)^2, \\quad V \\in \\{L, R\\}

    (paper Sec. 2.1, Eq. 1), each view streamed by :func:`variance_from_stores`.

    Parameters
    ----------
    left_paths, right_paths : sequence of path-like
        Render stores of the left and right view, the same number of seeds each.
    chunk_rows, subsets : keyword-only, optional
        Passed to :func:`variance_from_stores`.

    Returns
    -------
    xarray.Dataset
        ``mean`` (view, y, x, channel) float32, ``variance`` (view, y, x) float64, ``finite``
        (view, y, x) bool and ``n_nonfinite`` (view, y, x) int32, ``view`` in
        ``("left", "right")``; attrs ``n_seeds`` and ``estimator``.

    Raises
    ------
    ValueError
        The views have different numbers of stores.
    StoreError
        A store is damaged (see :func:`variance_from_stores`) or the views differ in shape.
    """
    left_paths, right_paths = list(left_paths), list(right_paths)
    if len(left_paths) != len(right_paths):
        raise ValueError(
            f"left and right need the same number of seeds, got {len(left_paths)} "
            f"and {len(right_paths)}"
        )
    from concurrent.futures import ThreadPoolExecutor

    # The two views are independent streams: accumulate them side by side.
    with ThreadPoolExecutor(max_workers=2) as pool:
        views = list(
            pool.map(
                lambda p: variance_from_stores(p, chunk_rows=chunk_rows, subsets=subsets),
                (left_paths, right_paths),
            )
        )
    left_shape, right_shape = (tuple(v["mean"].shape) for v in views)
    if left_shape != right_shape:
        raise store_error(
            right_paths[0], f"shape {right_shape} differs from {left_shape} of {left_paths[0]}"
        )
    ds = xr.concat(views, dim="view", join="exact", combine_attrs="override")
    ds = ds.assign_coords(view=list(VIEWS))
    ds.attrs = {"n_seeds": views[0].attrs["n_seeds"], "estimator": ESTIMATOR}
    return ds


class SeedEstimator(VarianceEstimator):
    """``render.estimator: seeds``: Eq. 1 over N independent renders per view (paper Sec. 2.1).

    .. math::

        \\sigma_V^2(x, y) = \\frac13 \\sum_{c} \\frac1N \\sum_{n=1}^{N}
            \\bigl(I_{V,c}^{(n)}(x, y) - \\bar I_{V,c}(x, y)\\bigr)^2

    streamed store by store (:func:`variance_dataset`).

    Parameters
    ----------
    chunk_rows : int, optional
        Rows read per block (whole renders when omitted).
    """

    name = "seeds"
    description = ESTIMATOR

    def __init__(self, *, chunk_rows: int | None = None):
        self.chunk_rows = chunk_rows

    def estimate(self, left, right) -> xr.Dataset:
        """:func:`variance_dataset` of the two views' render stores."""
        return variance_dataset(left, right, chunk_rows=self.chunk_rows)
