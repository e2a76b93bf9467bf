"""Synthetic frames with a known answer, made from a run's own frames (no rendering).

The calibration (``DESIGN.md``, Calibration) passes data whose answer is known through the
same transforms, statistics and verdict rules as the renders. Everything here is drawn around
one scene's seed means :math:`\\bar I_V` (the "clean" images), its ground-truth disparity and
its :math:`N`:

``camera``
    a matched null: independent Gaussian noise per view whose variance follows a camera law
    :math:`a\\mu + b` fitted to the renders' own variance (:func:`camera_law`), so it has the
    renders' noise level and no Monte Carlo structure;
``misaligned``
    a matched null: each view's noise drawn with the renders' own variance field, the right
    field moved by a random offset (:func:`misaligned_variance`), so the structure is the
    renders' but the views are not aligned;
``planted``
    a cue of known strength :math:`s`: the camera law times :math:`\\exp(s z_V - s^2/2)` with
    :math:`z` a smooth unit-variance pattern of the left view carried into the right view by
    the ground-truth disparity (:func:`planted_pattern`), so that it lines up across the views
    exactly as a Monte Carlo pattern tied to the scene would.
"""

from __future__ import annotations

import numpy as np

KINDS = ("camera", "misaligned", "planted")
"""The synthetic data: two matched nulls and the planted cue."""

NULL_KINDS = ("camera", "misaligned")
"""The kinds with no cue."""

PATTERN_SCALE = 2.0
"""Standard deviation, in pixels, of the Gaussian kernel that smooths the planted pattern:
its correlation length is well inside a 16-pixel bootstrap tile."""

MIN_OFFSET_FRACTION = 0.25
"""The misaligned null moves the right field by at least this fraction of the image in x or
y, far beyond any disparity of the scene."""


def camera_law(variance, intensity, mask=None, *, bins: int = 32) -> tuple[float, float]:
    """A camera law :math:`\\sigma^2 = a\\mu + b` matched to a variance field.

    .. math::

        (\\hat a, \\hat b) = \\arg\\min_{a \\ge 0,\\, b > 0} \\sum_k
            \\bigl(\\tilde\\sigma^2_k - a\\tilde\\mu_k - b\\bigr)^2

    over the medians :math:`(\\tilde\\mu_k, \\tilde\\sigma^2_k)` of ``bins`` quantile bins of
    :math:`\\mu`: medians, so that a few fireflies do not set the law. Not in the paper: the
    shot-noise law of Sec. 2.4 at the renders' own noise level.

    Parameters
    ----------
    variance, intensity : array_like (H, W)
        :math:`\\sigma^2` (Eq. 1) and :math:`\\mu` (the RGB mean of the seed mean).
    mask : array_like of bool (H, W), optional
        Pixels to fit on (finite values only are used).
    bins : int, keyword-only

    Returns
    -------
    a, b : float
        ``b`` is at least :math:`10^{-6}` of the median variance, so the law is never 0.

    Examples
    --------
    >>> import numpy as np
    >>> mu = np.linspace(0.1, 2.0, 400).reshape(20, 20)
    >>> a, b = camera_law(0.02 * mu + 0.001, mu)
    >>> round(a, 6), round(b, 6)
    (0.02, 0.001)
    """
    v = np.asarray(variance, dtype=np.float64).ravel()
    m = np.asarray(intensity, dtype=np.float64).ravel()
    ok = np.isfinite(v) & np.isfinite(m)
    if mask is not None:
        ok &= np.asarray(mask, dtype=bool).ravel()
    v, m = v[ok], m[ok]
    if v.size < 2:
        raise ValueError("camera_law needs at least 2 finite pixels")
    order = np.argsort(m, kind="stable")
    groups = np.array_split(order, min(bins, v.size))
    mu_k = np.array([np.median(m[g]) for g in groups])
    var_k = np.array([np.median(v[g]) for g in groups])
    floor = 1e-6 * max(float(np.median(v)), np.finfo(np.float64).tiny)
    design = np.column_stack([mu_k, np.ones_like(mu_k)])
    (a, b), *_ = np.linalg.lstsq(design, var_k, rcond=None)
    if a < 0:  # no slope: the best constant
        a, b = 0.0, float(var_k.mean())
    if b < floor:  # through the floor: the best slope with b at it
        b = floor
        a = max(float(np.dot(mu_k, var_k - b) / max(np.dot(mu_k, mu_k), 1e-300)), 0.0)
    return float(a), float(b)


def smooth_field(shape, rng: np.random.Generator, *, scale: float = PATTERN_SCALE) -> np.ndarray:
    """A smooth Gaussian random field with mean 0 and variance 1.

    .. math:: z = \\frac{G_s * w}{\\sqrt{\\sum_k G_s(k)^2}},
        \\qquad w \\sim \\mathcal N(0, 1)\\ \\text{i.i.d. per pixel}

    with :math:`G_s` a Gaussian kernel of standard deviation ``scale`` pixels: unit variance
    in expectation, not rescaled to the draw's own mean and spread, so that the pattern's
    strength over an image varies from draw to draw as a random field's does (what the
    block bootstrap's interval is about; a pattern rescaled per draw varies less, and the
    bootstrap covered it 100% of the time).

    Examples
    --------
    >>> import numpy as np
    >>> z = smooth_field((400, 400), np.random.default_rng(0))
    >>> bool(abs(z.std() - 1.0) < 0.05), bool(abs(z.mean()) < 0.05)
    (True, True)
    """
    from scipy.ndimage import gaussian_filter

    impulse = np.zeros((int(8 * scale) + 1,) * 2)
    impulse[impulse.shape[0] // 2, impulse.shape[1] // 2] = 1.0
    norm = float(np.sqrt(np.sum(gaussian_filter(impulse, scale, mode="constant") ** 2)))
    return gaussian_filter(rng.standard_normal(shape), scale, mode="reflect") / norm


def planted_pattern(
    disparity_right, valid_right, *, sign: int, rng: np.random.Generator, scale=PATTERN_SCALE
) -> tuple[np.ndarray, np.ndarray]:
    """A pattern :math:`z_L` of the left view and the same pattern seen by the right view.

    .. math:: z_R(x, y) = z_L\\bigl(x - s\\,d_R(x, y),\\, y\\bigr)

    where the right pixel is valid (bilinear), with :math:`x_R = x_L + s\\,d` the ground
    truth's relation (Eq. 2, Sec. 2.2); an independent pattern elsewhere (occluded or outside
    the left image), so nothing lines up there. Warping :math:`z_R` into the left view by
    Eq. 2 gives back :math:`z_L` up to the interpolation.

    Parameters
    ----------
    disparity_right, valid_right : array_like (H, W)
        The right view's ground-truth disparity magnitude and validity.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    rng : numpy.random.Generator, keyword-only
    scale : float, keyword-only
        :func:`smooth_field`'s kernel.

    Returns
    -------
    z_left, z_right : numpy.ndarray (H, W), float64
    """
    from scipy.ndimage import map_coordinates

    d = np.asarray(disparity_right, dtype=np.float64)
    valid = np.asarray(valid_right, dtype=bool) & np.isfinite(d)
    shape = d.shape
    z_left = smooth_field(shape, rng, scale=scale)
    other = smooth_field(shape, rng, scale=scale)
    yy, xx = np.indices(shape, dtype=np.float64)
    x_left = xx - sign * np.where(valid, d, 0.0)
    inside = valid & (x_left >= 0) & (x_left <= shape[1] - 1)
    seen = map_coordinates(z_left, [yy, np.clip(x_left, 0, shape[1] - 1)], order=1)
    return z_left, np.where(inside, seen, other)


def misaligned_variance(variance_right, rng: np.random.Generator) -> np.ndarray:
    """The right variance field moved by a random circular offset.

    .. math:: \\tilde\\sigma_R^2(x, y) = \\sigma_R^2\\bigl((x + \\Delta x) \\bmod W,\\,
        (y + \\Delta y) \\bmod H\\bigr)

    with :math:`(\\Delta x, \\Delta y)` uniform over the offsets with
    :math:`|\\Delta x| \\ge W/4` or :math:`|\\Delta y| \\ge H/4`
    (:data:`MIN_OFFSET_FRACTION`): the field keeps its values and spatial structure but no
    longer lines up with the left view.
    """
    v = np.asarray(variance_right, dtype=np.float64)
    h, w = v.shape
    while True:
        dy, dx = int(rng.integers(0, h)), int(rng.integers(0, w))
        far_x = min(dx, w - dx) >= MIN_OFFSET_FRACTION * w
        far_y = min(dy, h - dy) >= MIN_OFFSET_FRACTION * h
        if far_x or far_y:
            return np.roll(v, (dy, dx), axis=(0, 1))


def filled(field, fallback=None) -> np.ndarray:
    """``field`` with non-finite or negative entries replaced by its finite median (or
    ``fallback``)."""
    f = np.asarray(field, dtype=np.float64)
    ok = np.isfinite(f) & (f >= 0)
    fill = float(np.median(f[ok])) if ok.any() else (fallback or 0.0)
    return np.where(ok, f, fill)


def channel_correlation(left, valid=None) -> float:
    """The correlation :math:`\\rho` between the channels of a pixel's noise over a scene's
    renders, from the grey image's share of the channels' variance.

    .. math::

        \\rho = \\frac{3 r - 1}{2}, \\qquad
        r = \\frac{\\sum_p \\operatorname{Var}_n \\bar g_p}{\\sum_p \\frac13 \\sum_c
            \\operatorname{Var}_n I_{c,p}},

    with :math:`g` the RGB mean (for channels of equal variance, the grey variance is
    :math:`\\sigma^2 (1 + 2\\rho)/3`), clipped to [0, 1].

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> z = rng.standard_normal((6, 50, 50, 1))
    >>> stack = 0.5 + 0.1 * np.repeat(z, 3, axis=3)
    >>> round(channel_correlation(stack), 2)
    1.0
    >>> round(channel_correlation(0.5 + 0.1 * rng.standard_normal((6, 50, 50, 3))), 1)
    0.0
    """
    stack = np.asarray(left, dtype=np.float64)
    ok = np.ones(stack.shape[1:3], bool) if valid is None else np.asarray(valid, dtype=bool)
    per_channel = stack.var(axis=0).mean(axis=-1)[ok]
    grey = stack.mean(axis=-1).var(axis=0)[ok]
    total = float(per_channel.sum())
    if not total > 0:
        return 1.0
    return float(np.clip((3 * float(grey.sum()) / total - 1) / 2, 0.0, 1.0))


def draw_frames(
    mean, variance, n: int, rng: np.random.Generator, *, channel_correlation: float = 0.0
) -> np.ndarray:
    """:math:`N` frames :math:`I^{(n)} = \\bar I + \\sqrt{v}\\,\\varepsilon^{(n)}`,
    :math:`\\varepsilon` standard normal per pixel, channel and frame, with correlation
    :math:`\\rho` between the channels of a pixel
    (:math:`\\varepsilon_c = \\sqrt\\rho\\, z + \\sqrt{1 - \\rho}\\, z_c`; a path tracer's
    channels share their paths, so its :math:`\\rho` is near 1).

    Parameters
    ----------
    mean : array_like (H, W, C)
        The clean image.
    variance : array_like (H, W) or (H, W, C)
        Per-pixel (all channels) or per-channel noise variance.
    n : int
    rng : numpy.random.Generator
    channel_correlation : float, keyword-only
        :math:`\\rho \\in [0, 1]`; 0: independent channels.

    Returns
    -------
    numpy.ndarray (N, H, W, C), float32
    """
    mean = np.asarray(mean, dtype=np.float64)
    v = np.asarray(variance, dtype=np.float64)
    sd = np.sqrt(np.maximum(v, 0.0))
    if sd.ndim == 2:
        sd = sd[..., None]
    noise = rng.standard_normal((int(n), *mean.shape), dtype=np.float32)
    rho = float(np.clip(channel_correlation, 0.0, 1.0))
    if rho > 0:
        shared = rng.standard_normal((int(n), *mean.shape[:2], 1), dtype=np.float32)
        noise *= np.float32(np.sqrt(1.0 - rho))
        noise += np.float32(np.sqrt(rho)) * shared
    noise *= sd.astype(np.float32)
    noise += mean.astype(np.float32)
    return noise


def variance_fields(
    kind: str,
    strength: float,
    *,
    mean: dict,
    law: tuple[float, float],
    render_variance: dict,
    pattern=None,
    rng: np.random.Generator,
) -> dict:
    """Each view's per-channel noise variance for one kind of synthetic data.

    .. math::

        v_V^{\\text{camera}} = a\\mu_V + b, \\qquad
        v_V^{\\text{planted}} = (a\\mu_V + b)\\,e^{s z_V - s^2/2}, \\qquad
        v_L^{\\text{misaligned}} = \\sigma_L^2,\\ v_R^{\\text{misaligned}} = \\tilde\\sigma_R^2

    with :math:`\\mu_V` the seed mean per channel floored at 0 and :math:`s` the
    ``strength``: the standard deviation of the planted :math:`\\ln v` (the factor
    :math:`e^{-s^2/2}` keeps the mean variance at the camera law's).

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`.
    strength : float
        The planted :math:`s` (ignored by the nulls).
    mean : dict
        View to the seed mean (H, W, C).
    law : (a, b)
        :func:`camera_law`.
    render_variance : dict
        View to the renders' Eq. 1 field (H, W), used by ``misaligned``.
    pattern : (z_left, z_right), optional
        :func:`planted_pattern`'s output; needed by ``planted``.
    rng : numpy.random.Generator

    Returns
    -------
    dict
        View to the variance, (H, W, C) or (H, W).
    """
    a, b = law
    if kind == "misaligned":
        return {
            "left": filled(render_variance["left"]),
            "right": misaligned_variance(filled(render_variance["right"]), rng),
        }
    base = {v: a * np.maximum(np.asarray(mean[v], dtype=np.float64), 0.0) + b for v in mean}
    if kind == "camera":
        return base
    if kind != "planted":
        raise ValueError(f"unknown kind {kind!r}; use one of {', '.join(KINDS)}")
    if pattern is None:
        raise ValueError("a planted cue needs its pattern (planted_pattern)")
    s = float(strength)
    return {
        v: base[v] * np.exp(s * z - s * s / 2.0)[..., None]
        for v, z in zip(("left", "right"), pattern, strict=True)
    }
