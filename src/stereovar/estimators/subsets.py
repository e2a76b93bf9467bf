"""Eq. 1 on subsets of the seeds: split halves and disjoint subsets (paper Sec. 2.1).

The reported :math:`\\rho` is measured on finite-:math:`N` estimates of the variance fields,
so part of it is set by the estimator and not by the scene. Two families of sub-estimates
expose that:

* the **split halves**: Eq. 1 over the even-indexed and over the odd-indexed seeds, whose
  agreement is the reliability of an :math:`N/2` estimate
  (:mod:`stereovar.statistics.reliability`);
* **disjoint subsets** of :math:`N' = 2, 4, 8, \\ldots < N` consecutive seeds, which give
  :math:`\\rho` as a function of :math:`N'`.

:class:`SeedSubsets` accumulates both in one pass over the renders, next to
:class:`~stereovar.estimators.seeds.StreamingVariance`.
"""

from __future__ import annotations

import numpy as np

MIN_SPLIT_SEEDS = 4
"""Fewest seeds for a split-half estimate (two halves of at least two seeds)."""


def pooled_moments(first: tuple, second: tuple) -> tuple:
    """Pool the moments of two disjoint sets of renders (Chan et al.'s pairwise update).

    With :math:`(n_k, \\bar I_k, M_k)` the count, mean and sum of squared deviations of set
    :math:`k`, and :math:`\\delta = \\bar I_2 - \\bar I_1`,

    .. math::

        n = n_1 + n_2, \\qquad \\bar I = \\bar I_1 + \\delta\\,\\frac{n_2}{n}, \\qquad
        M = M_1 + M_2 + \\delta^2 \\frac{n_1 n_2}{n},

    so that :math:`M / n` is the population variance of Eq. 1 over the union.

    Parameters
    ----------
    first, second : tuple (n, mean, m2)
        ``n`` an int, ``mean`` and ``m2`` float64 arrays of one shape (``m2`` may be None
        for a single render, meaning zeros).

    Returns
    -------
    tuple (n, mean, m2)
    """
    n1, mean1, m1 = first
    n2, mean2, m2 = second
    n = n1 + n2
    delta = mean2 - mean1
    mean = mean1 + delta * (n2 / n)
    spread = delta * delta * (n1 * n2 / n)
    for part in (m1, m2):
        if part is not None:
            spread += part
    return n, mean, spread


def channel_variance(moments: tuple) -> np.ndarray:
    """Eq. 1 from pooled moments: :math:`\\frac13 \\sum_c M_c / n`, float32 (H, W)."""
    n, _, m2 = moments
    if m2 is None:
        return np.zeros(np.shape(moments[1])[:2], dtype=np.float32)
    return (np.maximum(m2, 0.0).mean(axis=-1) / n).astype(np.float32)


class SeedSubsets:
    """Split-half and disjoint-subset variance fields of one view, fed one render at a time.

    Seed :math:`k` (0-based, in the order added) goes to half :math:`k \\bmod 2`; the
    disjoint subsets of size :math:`N' = 2^j` are the runs of :math:`N'` consecutive seeds
    :math:`\\{iN', \\ldots, (i+1)N' - 1\\}`, built by pairwise pooling
    (:func:`pooled_moments`) like a binary counter, so at most one pending subset per size is
    held in memory.

    Non-finite values propagate into the fields of the subsets they fall in; downstream
    statistics drop non-finite pixels.
    """

    def __init__(self):
        self.n = 0
        self._halves = [None, None]
        self._pending: dict[int, tuple] = {}
        self.subsets: list[tuple[int, int, np.ndarray]] = []

    def update(self, image) -> SeedSubsets:
        """Add one whole render (H, W, C)."""
        item = (1, np.asarray(image, dtype=np.float64), None)
        half = self.n % 2
        self._halves[half] = (
            item if self._halves[half] is None else pooled_moments(self._halves[half], item)
        )
        self.n += 1
        size = 1
        while size in self._pending:
            item = pooled_moments(self._pending.pop(size), item)
            size *= 2
            index = self.n // size - 1
            self.subsets.append((size, index, channel_variance(item)))
        self._pending[size] = item
        return self

    @property
    def halves(self) -> np.ndarray | None:
        """float32 (2, H, W): Eq. 1 over the even and the odd seeds; None below
        :data:`MIN_SPLIT_SEEDS` seeds."""
        if self.n < MIN_SPLIT_SEEDS:
            return None
        return np.stack([channel_variance(h) for h in self._halves])

    def subset_fields(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """``(sizes, indices, fields)`` of every complete subset smaller than :math:`N`,
        sizes ascending; None when there is none."""
        done = sorted(((s, i, f) for s, i, f in self.subsets if s < self.n), key=lambda t: t[:2])
        if not done:
            return None
        sizes, indices, fields = zip(*done, strict=True)
        return np.array(sizes), np.array(indices), np.stack(fields)


def subset_dataset(subsets: SeedSubsets):
    """The optional sub-estimate variables of the variance contract for one view.

    Returns
    -------
    xarray.Dataset
        ``half_variance`` (half, y, x), float32, ``half`` in ``("even", "odd")``, when there
        are at least :data:`MIN_SPLIT_SEEDS` seeds; ``subset_variance`` (subset, y, x) with
        the coordinates ``subset_size`` (:math:`N'`) and ``subset_index`` on ``subset``, when
        a subset smaller than :math:`N` exists. Empty otherwise.
    """
    import xarray as xr

    out = xr.Dataset()
    halves = subsets.halves
    if halves is not None:
        out["half_variance"] = xr.DataArray(
            halves,
            dims=("half", "y", "x"),
            coords={"half": ["even", "odd"]},
            attrs={"long_name": "Eq. 1 over the even- and the odd-indexed seeds"},
        )
    fields = subsets.subset_fields()
    if fields is not None:
        sizes, indices, stack = fields
        out["subset_variance"] = xr.DataArray(
            stack,
            dims=("subset", "y", "x"),
            coords={
                "subset": np.arange(len(sizes)),
                "subset_size": ("subset", sizes),
                "subset_index": ("subset", indices),
            },
            attrs={"long_name": "Eq. 1 over disjoint runs of subset_size consecutive seeds"},
        )
    return out
