"""Eq. 1 on subsets of the seeds: split halves and disjoint subsets (paper Sec. 2.1).

The reported :math:`\\rho` is measured on finite-:math:`N` estimates of the variance fields,
so part of it is set by the estimator and not by the scene. Two families of sub-estimates
expose that:

* the **split halves**: Eq. 1 over the even-indexed and over the odd-indexed seeds, whose
  agreement is the reliability of an :math:`N/2` estimate
  (:mod:`stereovar.statistics.reliability`);
* **disjoint subsets** of :math:`N' = 2, 4, 8, \\ldots < N` consecutive seeds, which give
  :math:`\\rho` as a function of :math:`N'`.

:class:`~stereovar.estimators.seeds.StreamingVariance` keeps the halves' sums apart as it
accumulates Eq. 1; :class:`SeedSubsets` builds the disjoint subsets in the same pass over the
renders.
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


def channel_variance(m2, n: int) -> np.ndarray:
    """Eq. 1 from the pooled sums of squared deviations of ``n`` renders, float32 (H, W).

    .. math:: \\sigma^2 = \\frac13 \\sum_c \\frac{M_c}{n}
    """
    total = m2[..., 0].copy()
    for c in range(1, m2.shape[-1]):
        total += m2[..., c]
    total *= np.float32(1.0 / (m2.shape[-1] * n))
    return np.maximum(total, np.float32(0.0), out=total)


class SeedSubsets:
    """Disjoint-subset variance fields of one view, fed one render at a time.

    The disjoint subsets of size :math:`N' = 2^j` are the runs of :math:`N'` consecutive seeds
    :math:`\\{iN', \\ldots, (i+1)N' - 1\\}`, built by pairwise pooling
    (:func:`pooled_moments`) like a binary counter, so at most one pending subset per size is
    held in memory. The moments are float32 (the stored fields' precision) and pooled in
    place: Chan's update has no cancellation, and a render costs a handful of passes over
    preallocated buffers.

    Non-finite values propagate into the fields of the subsets they fall in; downstream
    statistics drop non-finite pixels.
    """

    def __init__(self):
        self.n = 0
        self._pending: dict[int, list] = {}
        self._free: list = []
        self._tmp = None
        self.subsets: list[tuple[int, int, np.ndarray]] = []

    def _buffers(self, shape) -> list:
        if self._free:
            return self._free.pop()
        return [np.empty(shape, np.float32), np.empty(shape, np.float32)]

    def _pool_into(self, into: list, n1: int, mean2, m2, n2: int) -> None:
        """``into`` (mean, m2) over ``n1`` renders absorbs ``(mean2, m2)`` over ``n2``
        (:func:`pooled_moments`, in place)."""
        mean1, spread = into
        n = n1 + n2
        delta, scratch = self._tmp
        np.subtract(mean2, mean1, out=delta)
        if m2 is not None:
            spread += m2
        np.multiply(delta, delta, out=scratch)
        scratch *= np.float32(n1 * n2 / n)
        spread += scratch
        delta *= np.float32(n2 / n)
        mean1 += delta

    def _start(self, image) -> list:
        buf = self._buffers(image.shape)
        np.copyto(buf[0], image)
        buf[1].fill(0.0)
        return buf

    def update(self, image) -> SeedSubsets:
        """Add one whole render (H, W, C)."""
        x = np.asarray(image, dtype=np.float32)
        if self._tmp is None:
            self._tmp = (np.empty(x.shape, np.float32), np.empty(x.shape, np.float32))
        self.n += 1
        carry, size = None, 1  # None: the render itself
        while size in self._pending:
            pending = self._pending.pop(size)
            if carry is None:
                self._pool_into(pending, size, x, None, 1)
            else:
                self._pool_into(pending, size, carry[0], carry[1], size)
                self._free.append(carry)
            carry = pending
            size *= 2
            self.subsets.append((size, self.n // size - 1, channel_variance(carry[1], size)))
        self._pending[size] = self._start(x) if carry is None else carry
        return self

    def subset_fields(self) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """``(sizes, indices, fields)`` of every complete subset smaller than :math:`N`,
        sizes ascending; None when there is none."""
        done = sorted(((s, i, f) for s, i, f in self.subsets if s < self.n), key=lambda t: t[:2])
        if not done:
            return None
        sizes, indices, fields = zip(*done, strict=True)
        return np.array(sizes), np.array(indices), np.stack(fields)


def subset_dataset(subsets: SeedSubsets, halves=None):
    """The optional sub-estimate variables of the variance contract for one view.

    Parameters
    ----------
    subsets : SeedSubsets
    halves : numpy.ndarray (2, H, W), optional
        Eq. 1 over the even and the odd seeds
        (:attr:`~stereovar.estimators.seeds.StreamingVariance.half_variance`).

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
    if halves is not None:
        out["half_variance"] = xr.DataArray(
            np.asarray(halves, dtype=np.float32),
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
