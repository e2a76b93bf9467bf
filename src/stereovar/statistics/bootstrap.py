"""Spatial block bootstrap of a correlation over a pixel set.

Fisher-z intervals (:func:`stereovar.statistics.correlation.fisher_interval`) treat the
:math:`n` pixels of a region as independent. Neighbouring pixels of a variance field are not:
they share geometry, texture and light paths, so the effective sample size is far below
:math:`n`. The block bootstrap resamples whole square tiles of the image instead
(Künsch 1989; Lahiri 2003), which keeps the dependence inside a tile.

A replicate draws :math:`K` of the region's :math:`K` non-empty tiles with replacement.
Pearson's :math:`\\rho` of a replicate needs only the per-tile sums
:math:`(n_t, \\sum a, \\sum b, \\sum a^2, \\sum b^2, \\sum ab)`, so with the draw counts
:math:`c_{rt}` of replicate :math:`r`,

.. math::

    S_r = \\sum_t c_{rt}\\, s_t, \\qquad
    \\rho_r = \\frac{S_{ab} - S_a S_b / S_n}
        {\\sqrt{(S_{aa} - S_a^2/S_n)(S_{bb} - S_b^2/S_n)}},

and 1000 replicates of a 1280x720 region cost one matrix product.

The paper's intervals (Sec. 3.1) are Fisher-z intervals; this bootstrap is the interval the
correlation rows report beside them (``boot_low``, ``boot_high``), computed by
:func:`stereovar.statistics.registry.evaluate` with the functions below. Step by step,
:func:`tile_labels`, :func:`tile_sums`, :func:`draw_counts`, :func:`bootstrap_replicates`
and :func:`percentile_interval` (see its example).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LEVEL = 0.95
"""Coverage of the percentile intervals."""

FEWER_THAN_2_TILES = "fewer than 2 bootstrap tiles in the region"


@dataclass(frozen=True)
class BootstrapSettings:
    """``analysis.bootstrap``: tile side in pixels, replicates and the recorded seed."""

    tile: int = 16
    reps: int = 1000
    seed: int = 0


def tile_labels(shape: tuple[int, int], tile: int) -> np.ndarray:
    """Index of the ``tile`` x ``tile`` block that holds each pixel, row-major.

    Parameters
    ----------
    shape : tuple of int (H, W)
    tile : int
        Tile side; the last row and column of tiles may be smaller.

    Returns
    -------
    numpy.ndarray of int64, shape (H, W)

    Examples
    --------
    >>> tile_labels((3, 5), 2).tolist()
    [[0, 0, 1, 1, 2], [0, 0, 1, 1, 2], [3, 3, 4, 4, 5]]
    """
    height, width = shape
    tile = int(tile)
    if tile < 1 or tile > min(height, width):
        raise ValueError(
            f"bootstrap tile {tile} does not fit a {width}x{height} image; set "
            f"analysis.bootstrap.tile between 1 and {min(height, width)}"
        )
    n_x = -(-width // tile)
    ys = np.arange(height) // tile
    xs = np.arange(width) // tile
    return ys[:, None] * n_x + xs[None, :]


def standardized_pair(a, b) -> tuple[np.ndarray, np.ndarray]:
    """Centre two value arrays on their means and scale each by its largest deviation.

    .. math:: \\tilde a_i = \\frac{a_i - \\bar a}{\\max_j |a_j - \\bar a|}

    Pearson's :math:`\\rho` is invariant to both, and the scaled values keep the tile sums
    from overflowing or cancelling. A constant array becomes all zeros.
    """
    return _standardized(a), _standardized(b)


def _standardized(values) -> np.ndarray:
    values = np.asarray(values, dtype=np.float64)
    if not values.size:
        return values.copy()
    mean = float(np.mean(values))
    deviation = max(float(values.max()) - mean, mean - float(values.min()))
    out = np.subtract(values, mean)
    out *= 1.0 / max(deviation, np.finfo(float).tiny)
    return out


def product_sums(labels, da, db, products=None) -> np.ndarray:
    """Per-tile sums of standardized pairs (:func:`standardized_pair`) over non-empty tiles.

    Parameters
    ----------
    labels : numpy.ndarray of int, shape (n,)
        Tile index of each pair (non-negative).
    da, db : numpy.ndarray, shape (n,)
    products : tuple of numpy.ndarray, optional
        :math:`(\\tilde a^2, \\tilde b^2, \\tilde a \\tilde b)` when already computed.

    Returns
    -------
    numpy.ndarray, shape (K, 6)
        As :func:`tile_sums`.
    """
    labels = np.asarray(labels)
    if products is None:
        products = (da * da, db * db, da * db)
    if labels.size and np.all(labels[1:] >= labels[:-1]):
        # sorted by tile: one sequential pass per column
        starts = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
        counts = np.diff(starts, append=labels.size).astype(np.float64)
        columns = [counts] + [np.add.reduceat(c, starts) for c in (da, db, *products)]
        return np.stack(columns, axis=1)
    size = int(labels.max()) + 1 if labels.size else 0
    counts = np.bincount(labels, minlength=size)
    used = counts > 0
    columns = [counts[used].astype(np.float64)]
    for c in (da, db, *products):
        columns.append(np.bincount(labels, weights=c, minlength=size)[used])
    return np.stack(columns, axis=1)


def tile_sums(a, b, labels) -> np.ndarray:
    """Per-tile sufficient statistics of Pearson's :math:`\\rho`, over the non-empty tiles.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (n,)
        The paired values (finite).
    labels : numpy.ndarray of int, shape (n,)
        Tile index of each pair (:func:`tile_labels` at the pixels).

    Returns
    -------
    numpy.ndarray, shape (K, 6)
        Columns :math:`n_t, \\sum a, \\sum b, \\sum a^2, \\sum b^2, \\sum ab` of the
        :math:`K` tiles holding at least one pair, in tile order. The values are centred on
        their overall means and scaled by their largest deviation first
        (:func:`standardized_pair`), so the sums neither overflow nor cancel.

    Examples
    --------
    The four pairs of :func:`~stereovar.statistics.correlation.pearson_over_mask`'s example
    (:math:`\\rho = 0.8`) in two tiles of two pixels: the sums over all tiles give
    :math:`\\rho` back (:func:`pearson_from_sums`).

    >>> import numpy as np
    >>> a, b = np.array([1.0, 2.0, 3.0, 4.0]), np.array([1.0, 3.0, 2.0, 4.0])
    >>> sums = tile_sums(a, b, np.array([0, 0, 1, 1]))
    >>> sums.shape, sums[:, 0].tolist()
    ((2, 6), [2.0, 2.0])
    >>> round(float(pearson_from_sums(sums.sum(axis=0))), 12)
    0.8
    """
    da, db = standardized_pair(a, b)
    return product_sums(labels, da, db)


def draw_counts(n_tiles: int, reps: int, seed) -> np.ndarray:
    """How often each of ``n_tiles`` tiles is drawn in each of ``reps`` replicates.

    Each replicate draws ``n_tiles`` tiles uniformly with replacement.

    Returns
    -------
    numpy.ndarray of float64, shape (reps, n_tiles); every row sums to ``n_tiles``.

    Examples
    --------
    >>> counts = draw_counts(5, 3, seed=0)
    >>> counts.shape, counts.sum(axis=1).tolist()
    ((3, 5), [5.0, 5.0, 5.0])
    """
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, n_tiles, size=(reps, n_tiles))
    flat = draws + (np.arange(reps) * n_tiles)[:, None]
    return (
        np.bincount(flat.ravel(), minlength=reps * n_tiles)
        .reshape(reps, n_tiles)
        .astype(np.float64)
    )


def pearson_from_sums(sums) -> np.ndarray:
    """Pearson's :math:`\\rho` from summed sufficient statistics (rows of :func:`tile_sums`).

    NaN where a resampled field is constant.
    """
    s = np.asarray(sums, dtype=np.float64)
    n, sa, sb, saa, sbb, sab = np.moveaxis(s, -1, 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        vaa = saa - sa * sa / n
        vbb = sbb - sb * sb / n
        cov = sab - sa * sb / n
        rho = cov / np.sqrt(vaa * vbb)
    rho = np.where((vaa > 0) & (vbb > 0), rho, np.nan)
    return np.clip(rho, -1.0, 1.0)


def bootstrap_replicates(sums, counts) -> np.ndarray:
    """Replicates of :math:`\\rho`, one per row :math:`r` of the draw counts.

    .. math::

        \\rho_r = \\rho\\Bigl(\\sum_t c_{rt}\\, s_t\\Bigr)

    with :math:`s_t` the sums of tile :math:`t` (:func:`tile_sums`) and :math:`\\rho(\\cdot)`
    :func:`pearson_from_sums`: Eq. 3 (paper Sec. 2.3) over the pixels of the drawn tiles,
    each counted as often as its tile is drawn.

    Examples
    --------
    The two tiles of :func:`tile_sums`' example: drawing each once gives the full sample's
    :math:`\\rho = 0.8`; drawing one tile twice gives the :math:`\\rho` of its two pixels, 1.

    >>> import numpy as np
    >>> a, b = np.array([1.0, 2.0, 3.0, 4.0]), np.array([1.0, 3.0, 2.0, 4.0])
    >>> sums = tile_sums(a, b, np.array([0, 0, 1, 1]))
    >>> reps = bootstrap_replicates(sums, np.array([[1, 1], [2, 0], [0, 2]]))
    >>> np.round(reps, 12).tolist()
    [0.8, 1.0, 1.0]
    """
    return pearson_from_sums(np.asarray(counts) @ np.asarray(sums))


def percentile_interval(replicates, level: float = LEVEL) -> tuple[float, float]:
    """The percentile interval of the finite bootstrap replicates of :math:`\\rho`.

    .. math::

        \\bigl[q_{\\alpha/2},\\ q_{1-\\alpha/2}\\bigr], \\qquad \\alpha = 1 - \\text{level},

    with :math:`q_p` the :math:`p` quantile of the replicates (``numpy.quantile``, linear
    interpolation); NaN, NaN when fewer than 2 are finite. Not in the paper: its intervals
    (Sec. 3.1) are Fisher-z intervals, which treat neighbouring pixels as independent.

    Examples
    --------
    The 5% and 95% quantiles of 0, 0.01, ..., 1 are 0.05 and 0.95:

    >>> import numpy as np
    >>> low, high = percentile_interval(np.arange(101) / 100, level=0.9)
    >>> round(low, 12), round(high, 12)
    (0.05, 0.95)
    >>> percentile_interval([0.5, np.nan])
    (nan, nan)

    The whole block bootstrap of one region: 8 x 8 fields in four 4 x 4 tiles, 200
    replicates. Where ``b`` is an exact linear function of ``a`` every replicate has
    :math:`\\rho = 1` (or :math:`-1`), so the interval shrinks to that point:

    >>> rng = np.random.default_rng(0)
    >>> a = rng.random((8, 8))
    >>> labels = tile_labels(a.shape, 4).ravel()
    >>> counts = draw_counts(4, 200, seed=0)
    >>> for b in (2 * a + 1, 5 - a):
    ...     reps = bootstrap_replicates(tile_sums(a.ravel(), b.ravel(), labels), counts)
    ...     print([round(x, 9) for x in percentile_interval(reps)])
    [1.0, 1.0]
    [-1.0, -1.0]
    """
    r = np.asarray(replicates, dtype=np.float64)
    r = r[np.isfinite(r)]
    if r.size < 2:
        return float("nan"), float("nan")
    alpha = 1.0 - level
    low, high = np.quantile(r, [alpha / 2, 1 - alpha / 2])
    return float(low), float(high)
