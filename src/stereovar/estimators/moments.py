"""Per-pixel Monte Carlo variance from one render's sample moments (the ``moments`` estimator).

The paper's Eq. 1 (Sec. 2.1) estimates the variance of a pixel rendered at :math:`s` samples
per pixel from :math:`N` independent renders. Under the independent sampler and a box
reconstruction filter, a pixel value is the mean of :math:`s` independent, identically
distributed path samples :math:`f_k` that all land in that pixel with weight 1, so

.. math::

    \\operatorname{Var}\\bigl[I(x, y)\\bigr] = \\frac{\\operatorname{Var}[f]}{s},

and one render's per-pixel sums :math:`\\sum f` and :math:`\\sum f^2` estimate it as well
(:func:`pixel_variance`). The ``moments`` estimator renders each view once per SPP, as two
independent half renders with their own seeds (:mod:`stereovar.io.moments`): their pooled
moments give the field, and the two halves give the split-half reliability that the
attenuation correction needs (:mod:`stereovar.statistics.reliability`).

Importing this module pulls in numpy and xarray only.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..io.renders import IMAGE_DIMS
from ..rig import VIEWS
from .base import VarianceEstimator

ESTIMATOR = (
    "unbiased per-sample variance of one render's samples divided by the SPP, averaged over "
    "RGB channels, from two independent half renders"
)

MIN_SAMPLES = 2
"""Fewest finite samples per half render for a defined pixel."""


def sample_variance(mean, mean_sq, count) -> np.ndarray:
    """Unbiased per-sample variance of each pixel and channel from its sample moments.

    With :math:`n` finite samples, :math:`m_1 = \\frac1n \\sum_k f_k` and
    :math:`m_2 = \\frac1n \\sum_k f_k^2`,

    .. math::

        S^2 = \\frac{n}{n - 1}\\bigl(m_2 - m_1^2\\bigr), \\qquad
        \\mathrm E[S^2] = \\operatorname{Var}[f],

    computed in float64 and floored at 0 (float32 rounding of :math:`m_2` and :math:`m_1^2`
    can leave a tiny negative where the samples barely vary, such as an emitter seen
    directly). NaN where :math:`n < 2`.

    Parameters
    ----------
    mean, mean_sq : array_like, shape (..., C)
        :math:`m_1`, :math:`m_2`.
    count : array_like of int, shape (...)
        :math:`n`.

    Returns
    -------
    numpy.ndarray, float64, shape (..., C)
    """
    m1 = np.asarray(mean, dtype=np.float64)
    m2 = np.asarray(mean_sq, dtype=np.float64)
    n = np.asarray(count, dtype=np.float64)[..., None]
    if m1.shape != m2.shape or n.shape[:-1] != m1.shape[:-1]:
        raise ValueError(
            f"moments of shapes {m1.shape}, {m2.shape} and counts of shape {n.shape[:-1]}"
        )
    with np.errstate(divide="ignore", invalid="ignore"):
        s2 = (m2 - m1 * m1) * (n / (n - 1.0))
    return np.where(n >= MIN_SAMPLES, np.maximum(s2, 0.0), np.nan)


def pooled_sample_moments(mean, mean_sq, count, *, dim: int = 0):
    """Pool the moments of independent renders of the same pixels (sums add).

    .. math::

        n = \\sum_h n_h, \\qquad m_1 = \\frac1n \\sum_h n_h m_{1,h}, \\qquad
        m_2 = \\frac1n \\sum_h n_h m_{2,h}

    Parameters
    ----------
    mean, mean_sq : array_like, shape (..., C) with the renders along ``dim``
    count : array_like of int, the same shape without C
    dim : int
        The renders' axis.

    Returns
    -------
    mean, mean_sq : numpy.ndarray, float64
    count : numpy.ndarray, int64
    """
    n = np.asarray(count, dtype=np.int64)
    w = n.astype(np.float64)[..., None]
    total = n.sum(axis=dim)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(total > 0, 1.0 / np.maximum(total, 1), 0.0)[..., None]
    m1 = (np.asarray(mean, np.float64) * w).sum(axis=dim) * scale
    m2 = (np.asarray(mean_sq, np.float64) * w).sum(axis=dim) * scale
    return m1, m2, total


def pixel_variance(mean, mean_sq, count, spp: int) -> np.ndarray:
    """The Eq. 1 field of a pixel rendered at ``spp`` samples, from sample moments.

    .. math::

        \\hat\\sigma^2(x, y) = \\frac13 \\sum_{c \\in \\{R,G,B\\}} \\frac{S_c^2(x, y)}{s},
        \\qquad
        \\mathrm E\\bigl[\\hat\\sigma^2\\bigr] = \\frac13 \\sum_c
            \\frac{\\operatorname{Var}[f_c]}{s}
            = \\frac13 \\sum_c \\operatorname{Var}\\bigl[I_c^{(s)}(x, y)\\bigr],

    with :math:`S_c^2` the unbiased per-sample variance (:func:`sample_variance`). The
    right-hand side is what Eq. 1 (paper Sec. 2.1) estimates from :math:`N` renders at
    :math:`s` samples: Eq. 1 divides by :math:`N` and so has expectation
    :math:`\\frac{N-1}{N}` times this, a constant factor that every correlation ignores.
    ``spp`` need not be the SPP rendered: the moments give the field of any SPP.

    Parameters
    ----------
    mean, mean_sq, count
        As in :func:`sample_variance` (channels last).
    spp : int
        :math:`s`.

    Returns
    -------
    numpy.ndarray, float64, shape of ``count``
        NaN where fewer than :data:`MIN_SAMPLES` samples are finite.
    """
    if int(spp) < 1:
        raise ValueError(f"spp must be a positive integer, got {spp}")
    return sample_variance(mean, mean_sq, count).mean(axis=-1) / int(spp)


def view_fields(moments: xr.Dataset, *, spp: int | None = None) -> xr.Dataset:
    """The variance contract of one view from its moment store (:mod:`stereovar.io.moments`).

    The pooled moments of the half renders give ``mean`` and ``variance``
    (:func:`pixel_variance` at ``spp``, the stored SPP by default); each half alone gives
    ``half_variance`` (the same field's estimate from half the samples), also stored as the
    two disjoint one-render ``subset_variance`` fields. A pixel is defined (``finite``) when
    every half has at least :data:`MIN_SAMPLES` finite samples; ``n_nonfinite`` counts the
    samples with a NaN or Inf, which every moment excludes.

    Returns
    -------
    xarray.Dataset
        ``mean`` (y, x, channel) float32, ``variance`` (y, x) float64, ``finite``,
        ``n_nonfinite``, ``half_variance`` (half, y, x) and ``subset_variance``
        (subset, y, x) float32; attrs ``n_seeds`` (half renders), ``n_draws`` (samples per
        pixel) and ``estimator``.
    """
    spp = int(moments.attrs["spp"] if spp is None else spp)
    order = ("half", *IMAGE_DIMS)
    m1 = moments["sample_mean"].transpose(*order).values
    m2 = moments["sample_mean_sq"].transpose(*order).values
    n = moments["n_samples"].transpose("half", "y", "x").values
    n_halves = m1.shape[0]
    rendered = int(moments["half_spp"].values.sum())
    finite = (n >= MIN_SAMPLES).all(axis=0)
    mean, mean_sq, total = pooled_sample_moments(m1, m2, n)
    variance = np.where(finite, pixel_variance(mean, mean_sq, total, spp), 0.0)
    halves = np.stack(
        [np.where(finite, pixel_variance(m1[h], m2[h], n[h], spp), 0.0) for h in range(n_halves)]
    ).astype(np.float32)
    yx = ("y", "x")
    return xr.Dataset(
        {
            "mean": (
                IMAGE_DIMS,
                np.where(finite[..., None], mean, 0.0).astype(np.float32),
                {"long_name": "mean of the finite samples of both half renders"},
            ),
            "variance": (yx, variance, {"long_name": ESTIMATOR}),
            "finite": (
                yx,
                finite,
                {"long_name": f"at least {MIN_SAMPLES} finite samples per half"},
            ),
            "n_nonfinite": (
                yx,
                (rendered - total).astype(np.int32),
                {"long_name": "samples with a NaN or Inf, excluded from every moment"},
            ),
            "half_variance": (
                ("half", *yx),
                halves,
                {"long_name": "the field from one half render's samples"},
            ),
            "subset_variance": (
                ("subset", *yx),
                halves,
                {"long_name": "the field from one half render's samples"},
            ),
        },
        coords={
            "y": moments["y"].values,
            "x": moments["x"].values,
            "channel": moments["channel"].values,
            "half": ["even", "odd"][:n_halves] if n_halves == 2 else np.arange(n_halves),
            "subset": np.arange(n_halves),
            "subset_size": ("subset", np.ones(n_halves, dtype=np.int64)),
            "subset_index": ("subset", np.arange(n_halves)),
        },
        attrs={"n_seeds": n_halves, "n_draws": rendered, "estimator": ESTIMATOR},
    )


def moment_variance_dataset(left_paths, right_paths, *, spp: int | None = None) -> xr.Dataset:
    """Variance fields of both views from their moment stores: the variance contract.

    .. math::

        \\hat\\sigma_V^2(x, y) = \\frac13 \\sum_c \\frac{S_{V,c}^2(x, y)}{s},
        \\quad V \\in \\{L, R\\}

    (:func:`view_fields` of each view; paper Sec. 2.1's Eq. 1 in expectation).

    Parameters
    ----------
    left_paths, right_paths : sequence of path-like
        The moment store of each view (one each).
    spp : int, optional
        SPP of the field (the stored SPP by default).

    Raises
    ------
    ValueError
        Not exactly one store per view.
    StoreError
        A store is damaged, or the views differ in shape.
    """
    from ..io.moments import load_moments
    from ..io.store import store_error

    left_paths, right_paths = list(left_paths), list(right_paths)
    if len(left_paths) != 1 or len(right_paths) != 1:
        raise ValueError(
            f"the moments estimator reads one moment store per view, got {len(left_paths)} "
            f"and {len(right_paths)}"
        )
    views = [view_fields(load_moments(p[0]), spp=spp) for p in (left_paths, right_paths)]
    shapes = [tuple(v["mean"].shape) for v in views]
    if shapes[0] != shapes[1]:
        raise store_error(
            right_paths[0], f"shape {shapes[1]} differs from {shapes[0]} of {left_paths[0]}"
        )
    ds = xr.concat(views, dim="view", join="exact", combine_attrs="override")
    return ds.assign_coords(view=list(VIEWS))


class MomentEstimator(VarianceEstimator):
    """``render.estimator: moments``: one render per view and SPP, as two half renders.

    .. math::

        \\hat\\sigma_V^2(x, y) = \\frac13 \\sum_c \\frac{1}{s}\\,\\frac{n}{n-1}
            \\Bigl(\\frac1n \\sum_k f_{k,c}^2 - \\Bigl(\\frac1n \\sum_k f_{k,c}\\Bigr)^2\\Bigr)

    over the :math:`n` finite samples of the pixel (:func:`pixel_variance`), whose expectation
    is the variance of the pixel at :math:`s` samples that Eq. 1 estimates over seeds
    (paper Sec. 2.1).
    """

    name = "moments"
    description = ESTIMATOR
    reads = "moments"
    takes_transforms = False  # a store transform maps single renders, not sample moments

    def estimate(self, left, right) -> xr.Dataset:
        """:func:`moment_variance_dataset` of the two views' moment stores."""
        return moment_variance_dataset(left, right)
