"""Scoring one predicted disparity map: per-tile sums of every metric, per region.

A prediction :math:`\\hat d` is scored on the pixels of a region that have a ground-truth
disparity :math:`d` and a prediction (the network's border has none):

.. math::

    \\mathrm{hit} = [\\,|\\hat d - d| < 1\\,], \\qquad
    \\mathrm{EPE} = |\\hat d - d|, \\qquad
    \\mathrm{pulled} = [\\,|\\hat d - (d + k)| < 1\\,], \\qquad
    \\mathrm{zero} = [\\,|\\hat d| < 0.5\\,],

``pulled`` for the cue-conflict input, whose right residual lines up at :math:`d + k`;
``zero`` the predictions at :math:`\\hat d = 0` (disparities are integers or rounded to
within half a pixel). A non-finite prediction (NaN or Inf) is left out, or, given a bound
:math:`e_{\\max} \\ge 1` (``nonfinite_error``), scored as a miss at that end-point error:

.. math::

    \\mathrm{hit} = 0, \\qquad \\mathrm{EPE} = e_{\\max}, \\qquad
    \\mathrm{pulled} = \\mathrm{zero} = 0, \\qquad \\mathrm{nonfinite} = 1,

so that every prediction of a region is scored on the same pixels whatever it returns.
The sums are kept per bootstrap tile
(:func:`stereovar.statistics.bootstrap.tile_labels`), so that intervals can resample tiles
(:mod:`stereovar.probe.metrics`).

Importing this module pulls in only numpy.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SUMS", "tile_sums"]

SUMS = ("n", "hits", "abs_error", "pulled", "zero")
"""The per-tile sums: scored pixels, hits, summed end-point error, pixels pulled to d + k,
pixels predicted at zero disparity."""


def tile_sums(
    d_hat, d_gt, mask, labels, *, conflict_shift: int, nonfinite_error: float | None = None
) -> dict:
    """Per-tile sums of the metrics of one prediction over one region.

    Parameters
    ----------
    d_hat, d_gt : array_like, shape (H, W)
        Predicted and ground-truth disparity magnitudes; NaN where there is none.
    mask : array_like of bool, shape (H, W)
        The region.
    labels : array_like of int, shape (H, W)
        Tile index of each pixel.
    conflict_shift : int, keyword-only
        :math:`k`.
    nonfinite_error : float, keyword-only, optional
        :math:`e_{\\max}`: where given, a pixel of the region with a ground truth and a NaN
        or Inf prediction is scored, as a miss at this end-point error (module docstring),
        and counted in ``nonfinite``; by default it is not scored.

    Returns
    -------
    dict
        ``tile`` (the tiles with a scored pixel) and one int or float array per :data:`SUMS`
        (and ``nonfinite``, the non-finite predictions, with ``nonfinite_error``).

    Examples
    --------
    >>> d = np.array([[2.0, 2.0, 5.0, np.nan]])
    >>> s = tile_sums(np.array([[2.0, 5.0, 5.0, 1.0]]), d, np.ones((1, 4), bool),
    ...               np.array([[0, 0, 1, 1]]), conflict_shift=3)
    >>> s["tile"].tolist(), s["n"].tolist(), s["hits"].tolist(), s["pulled"].tolist()
    ([0, 1], [2, 1], [1, 1], [1, 0])
    >>> s["abs_error"].tolist(), s["zero"].tolist()
    ([3.0, 0.0], [0, 0])

    With a bound, the NaN prediction of pixel 1 is a miss at 4 px:

    >>> s = tile_sums(np.array([[2.0, np.nan, 5.0, 1.0]]), d, np.ones((1, 4), bool),
    ...               np.array([[0, 0, 1, 1]]), conflict_shift=3, nonfinite_error=4.0)
    >>> s["n"].tolist(), s["hits"].tolist(), s["abs_error"].tolist(), s["nonfinite"].tolist()
    ([2, 1], [1, 1], [4.0, 0.0], [1, 0])
    """
    d_hat = np.asarray(d_hat, dtype=np.float64)
    d_gt = np.asarray(d_gt, dtype=np.float64)
    labels = np.asarray(labels)
    mask = np.asarray(mask, dtype=bool)
    if not d_hat.shape == d_gt.shape == mask.shape == labels.shape:
        raise ValueError(
            f"prediction, ground truth, mask and tile labels differ in shape: {d_hat.shape}, "
            f"{d_gt.shape}, {mask.shape}, {labels.shape}"
        )
    bounded = nonfinite_error is not None
    if bounded and not float(nonfinite_error) >= 1:
        raise ValueError(f"nonfinite_error must be at least 1 (a miss), got {nonfinite_error}")
    scored = mask & np.isfinite(d_gt)
    if not bounded:
        scored &= np.isfinite(d_hat)
    tiles = labels[scored]
    truth = d_gt[scored]
    finite = np.isfinite(d_hat[scored])
    pred = np.where(finite, d_hat[scored], 0.0)  # a non-finite one's sums are set by `finite`
    err = np.where(finite, np.abs(pred - truth), float(nonfinite_error) if bounded else 0.0)
    hit = finite & (err < 1)
    pulled = finite & (np.abs(pred - truth - int(conflict_shift)) < 1)
    zero = finite & (np.abs(pred) < 0.5)
    used, inverse = np.unique(tiles, return_inverse=True)
    k = used.size
    out = {
        "tile": used,
        "n": np.bincount(inverse, minlength=k),
        "hits": np.bincount(inverse, weights=hit, minlength=k).astype(np.int64),
        "abs_error": np.bincount(inverse, weights=err, minlength=k),
        "pulled": np.bincount(inverse, weights=pulled, minlength=k).astype(np.int64),
        "zero": np.bincount(inverse, weights=zero, minlength=k).astype(np.int64),
    }
    if bounded:
        out["nonfinite"] = np.bincount(inverse, weights=~finite, minlength=k).astype(np.int64)
    return out
