"""What the learned matcher sees: one render per view, and the counterfactual test inputs.

A data set ships one render per view, tone-mapped for display. The matcher's input is that
render as an 8-bit-free display image: the grey (RGB-mean) radiance clipped to [0, 1],
sRGB-encoded, then standardised to zero mean and unit variance over the image's finite pixels
(MC-CNN's normalisation). Non-finite pixels become 0.

The counterfactual inputs split each render of a view into a reference mean and its residual,
:math:`I_V^{(n)} = \\bar I_V + \\epsilon_V^{(n)}` (paper Sec. 3.4), and change the residual
only. :math:`\\bar I_V` is the mean of the other renders of the view
(:func:`reference_mean`), so that the test frame's own noise is not inside it. With
:math:`\\Pi_S` the stratified shuffle (:func:`stratified_shuffle`: the residual pixels
permuted at random within quantile strata of :math:`\\bar I_R`, in linear space) and
:math:`\\eta_V` camera noise of the law :math:`a\\mu + b` fitted to the renders
(:func:`camera_residual`):

``normal``
    :math:`(I_L^{(n)}, I_R^{(n)})`;
``shuffled``
    :math:`(I_L^{(n)}, \\bar I_R + \\Pi_S(\\epsilon_R^{(n)}))`: the right residual keeps its
    values in every intensity stratum (the noise law by intensity) and the linear mean, and
    loses its alignment with the left view;
``camera``
    :math:`(\\bar I_L + \\eta_L, \\bar I_R + \\eta_R)`: the residual of a camera, which has
    no Monte Carlo structure;
``camera_shuffled``
    :math:`(\\bar I_L + \\eta_L, \\bar I_R + \\Pi_S(\\eta_R))`: the same shuffle applied to
    camera noise, the matched control of ``shuffled`` (what the shuffle changes where there is
    no cue to break);
``clean``
    :math:`(\\bar I_L, \\bar I_R)`;
``conflict``
    :math:`(I_L^{(n)}, \\bar I_R + \\epsilon_R^{(n)}(x - s k, y))`: the right residual moved
    by :math:`k` pixels, so its variance structure lines up with the left at
    :math:`d_{GT} + k` while the clean image still lines up at :math:`d_{GT}`.

Importing this module pulls in only numpy.
"""

from __future__ import annotations

import numpy as np

from ..io.transfer import linear_to_srgb

__all__ = [
    "LEFT_KEPT",
    "MIN_DISTANCE",
    "STRATA",
    "TEST_INPUTS",
    "camera_residual",
    "counterfactual_pair",
    "grey",
    "network_input",
    "noise_scale",
    "reference_mean",
    "shift_columns",
    "stratified_shuffle",
]

TEST_INPUTS = ("normal", "shuffled", "camera", "camera_shuffled", "clean", "conflict")
"""The test inputs, in table order."""

STRATA = 64
"""Intensity strata of the stratified shuffle. Equal-count strata that straddle a jump in
intensity mix noise levels: on a render-like image of 128 x 128 pixels (dark and bright
objects) 16 strata raised the darkest pixels' noise SD by 14 % and moved a decile's SD by up
to 10 %; 64 strata keep both within 1 % and still hold hundreds of pixels each."""

MIN_DISTANCE = 8
"""The least move of a residual under the stratified shuffle, in pixels: beyond the
correlation length of a Monte Carlo variance pattern at the probe's resolution."""

LEFT_KEPT = ("normal", "shuffled", "conflict")
"""The test inputs whose left view is the render itself (only the right residual changes)."""


def grey(render) -> np.ndarray:
    """The RGB mean of a render (H, W, 3) as float64; a (H, W) array is returned as is."""
    a = np.asarray(render, dtype=np.float64)
    if a.ndim == 3:
        return a.mean(axis=2)
    if a.ndim != 2:
        raise ValueError(f"a render must have shape (H, W) or (H, W, 3), got {a.shape}")
    return a


def network_input(render) -> np.ndarray:
    """The matcher's input of one render: display-encoded grey, standardised.

    .. math::

        u = \\mathrm{sRGB}\\bigl(\\min(\\max(\\bar c, 0), 1)\\bigr), \\qquad
        x = \\frac{u - \\operatorname{mean}(u)}{\\operatorname{std}(u)},

    with :math:`\\bar c` the RGB mean of the linear radiance and the mean and standard
    deviation over the image's finite pixels (non-finite pixels become 0).

    Parameters
    ----------
    render : array_like, shape (H, W, 3) or (H, W)
        Linear radiance.

    Returns
    -------
    numpy.ndarray, float32, shape (H, W)

    Examples
    --------
    >>> x = network_input(np.array([[0.0, 1.0], [2.0, np.nan]]))
    >>> np.round(x.astype(float), 3).tolist()
    [[-1.414, 0.707], [0.707, 0.0]]
    """
    g = grey(render)
    finite = np.isfinite(g)
    u = linear_to_srgb(np.clip(np.where(finite, g, 0.0), 0.0, 1.0))
    values = u[finite]
    if values.size == 0:
        raise ValueError("the render has no finite pixel")
    std = values.std()
    x = (u - values.mean()) / (std if std > 0 else 1.0)
    return np.where(finite, x, 0.0).astype(np.float32)


def shift_columns(field, shift: int) -> np.ndarray:
    """Move a field by ``shift`` columns: ``out[:, x] = field[:, x - shift]``; the columns
    that have no source repeat the nearest edge column.

    Examples
    --------
    >>> shift_columns(np.arange(4.0)[None], 1).tolist()
    [[0.0, 0.0, 1.0, 2.0]]
    """
    a = np.asarray(field)
    width = a.shape[1]
    src = np.clip(np.arange(width) - int(shift), 0, width - 1)
    return a[:, src]


def _distant_permutation(pixels, width: int, min_distance: int, rng, rounds: int = 32):
    """A random permutation of ``pixels`` (flat indices) whose every move is at least
    ``min_distance`` pixels (Chebyshev), as far as ``rounds`` redraws reach.

    A uniform permutation, then ``rounds`` times: the pixels whose source lies nearer than
    ``min_distance``, and as many other pixels drawn at random, exchange their sources at
    random. Each round is a permutation of the stratum, so the result is one.
    """
    src = pixels[rng.permutation(pixels.size)]
    if min_distance <= 0 or pixels.size < 2:
        return src
    y, x = np.divmod(pixels, width)
    for _ in range(rounds):
        sy, sx = np.divmod(src, width)
        near = np.flatnonzero(np.maximum(abs(sy - y), abs(sx - x)) < min_distance)
        if near.size == 0:
            break
        others = rng.choice(pixels.size, size=min(near.size, pixels.size), replace=False)
        moved = np.union1d(near, others)
        src[moved] = src[moved[rng.permutation(moved.size)]]
    return src


def stratified_shuffle(
    residual, mean, *, rng, strata: int = STRATA, min_distance: int = MIN_DISTANCE
) -> np.ndarray:
    """The residual's pixels permuted at random within intensity strata, in linear space.

    .. math::

        \\Pi_S(\\epsilon)(p) = \\epsilon\\bigl(\\pi_k(p)\\bigr), \\quad p \\in S_k,
        \\qquad S_k = \\{p : q_{k-1} \\le \\operatorname{rank} \\bar c(p) < q_k\\},

    with :math:`\\bar c` the grey (RGB mean) of ``mean``, :math:`S_1, \\dots, S_K` its
    ``strata`` equal-count quantile bins (ties split by position), and :math:`\\pi_k` a
    random permutation of :math:`S_k` that moves every pixel at least ``min_distance``
    pixels (Chebyshev) where the stratum allows it (:func:`_distant_permutation`): a stratum
    of a smooth image is a band along an isophote, and a uniform permutation would leave a
    share of the residuals next to where they were. A pixel's channels move together. Each
    stratum keeps its multiset of residual vectors, so the noise law by intensity and the
    image's linear mean :math:`\\bar I + \\Pi_S(\\epsilon)` are kept exactly, while the
    residual's alignment with the other view is broken (paper Sec. 3.4's shuffle, with
    strata instead of blocks, so no residual moves to a pixel of another intensity and no
    seams appear). Pixels whose mean is not finite form one more stratum.

    Parameters
    ----------
    residual : array_like, shape (H, W) or (H, W, C)
        :math:`\\epsilon`, linear.
    mean : array_like, shape (H, W) or (H, W, C)
        The mean image :math:`\\bar I` that sets the strata.
    rng : numpy.random.Generator or int, keyword-only
        The permutations' generator (or its seed).
    strata : int, keyword-only
        :math:`K`.
    min_distance : int, keyword-only
        The least move of a residual, in pixels (0: a uniform permutation).

    Returns
    -------
    numpy.ndarray, float64, the shape of ``residual``

    Examples
    --------
    >>> mean = np.repeat([[0.0, 1.0]], 4, axis=0).reshape(2, 4)
    >>> eps = np.arange(8.0).reshape(2, 4)
    >>> out = stratified_shuffle(eps, mean, rng=0, strata=2)
    >>> sorted(out[mean == 0].tolist()) == sorted(eps[mean == 0].tolist())
    True
    """
    eps = np.asarray(residual, dtype=np.float64)
    g = grey(mean)
    if eps.shape[:2] != g.shape:
        raise ValueError(f"residual {eps.shape} and mean {g.shape} differ in image shape")
    strata = int(strata)
    if strata < 1:
        raise ValueError(f"strata must be at least 1, got {strata}")
    rng = np.random.default_rng(rng)
    flat = g.ravel()
    finite = np.flatnonzero(np.isfinite(flat))
    order = finite[np.argsort(flat[finite], kind="stable")]
    groups = [grp for grp in np.array_split(order, min(strata, max(order.size, 1))) if grp.size]
    rest = np.flatnonzero(~np.isfinite(flat))
    if rest.size:
        groups.append(rest)
    width = g.shape[1]
    source = np.arange(flat.size)
    for grp in groups:
        source[grp] = _distant_permutation(grp, width, int(min_distance), rng)
    pixels = eps.reshape(flat.size, -1)[source]
    return pixels.reshape(eps.shape)


def reference_mean(stack, frame: int) -> np.ndarray:
    """The leave-one-out mean of a view's renders: the mean that excludes the test frame.

    .. math:: \\bar I_V^{(-n)} = \\frac{1}{N - 1} \\sum_{m \\ne n} I_V^{(m)}

    so that none of the test frame's residual :math:`I_V^{(n)} - \\bar I_V^{(-n)}` stays
    inside the mean (with the full mean, :math:`1/N` of it would).

    Parameters
    ----------
    stack : array_like, shape (N, H, W, C) or (N, H, W)
        The view's renders, seed index first; :math:`N \\ge 2`.
    frame : int
        :math:`n`, the test frame.

    Returns
    -------
    numpy.ndarray, float64, shape ``stack.shape[1:]``

    Examples
    --------
    >>> reference_mean(np.array([1.0, 2.0, 6.0])[:, None], 2).tolist()
    [1.5]
    """
    a = np.asarray(stack, dtype=np.float64)
    n = a.shape[0]
    if n < 2:
        raise ValueError(f"a leave-one-out mean needs at least 2 renders, got {n}")
    frame = int(frame)
    if not -n <= frame < n:
        raise IndexError(f"frame {frame} is outside the {n} renders")
    return (a.sum(axis=0) - a[frame]) / (n - 1)


def camera_residual(mean, law, rng, *, channel_correlation: float = 1.0) -> np.ndarray:
    """Camera noise of a mean image: Gaussian with the camera law's variance per pixel and
    channel, and the renders' correlation between the channels of a pixel.

    .. math:: \\eta_c(p) = \\sqrt{\\max\\bigl(a\\,\\bar I_c(p) + b,\\ 0\\bigr)}\\;
        \\bigl(\\sqrt\\rho\\, z(p) + \\sqrt{1 - \\rho}\\, z_c(p)\\bigr),
        \\qquad z, z_c \\sim \\mathcal N(0, 1)\\ \\text{i.i.d.}

    with :math:`(a, b)` the law fitted to the renders' variance
    (:func:`stereovar.calibration.synthesis.camera_law`, the shot-noise law of Sec. 2.4) and
    :math:`\\rho` their channels' correlation
    (:func:`stereovar.probe.experiment.channel_correlation`): a path tracer's channels share
    their paths (:math:`\\rho` about 0.9 on the default scenes), and the noise of the grey
    image the networks see follows :math:`\\rho` (independent channels would give it a third
    of one channel's). Non-finite means give non-finite noise.

    Parameters
    ----------
    mean : array_like, shape (H, W, C) or (H, W)
        :math:`\\bar I`, linear.
    law : (float, float)
        :math:`(a, b)`.
    rng : numpy.random.Generator or int
    channel_correlation : float, keyword-only
        :math:`\\rho \\in [0, 1]`.

    Returns
    -------
    numpy.ndarray, float64, the shape of ``mean``

    Examples
    --------
    >>> eta = camera_residual(np.full((200, 200, 3), 2.0), (0.5, 0.0), 0)
    >>> round(float(eta.var()), 1), bool(np.array_equal(eta[..., 0], eta[..., 2]))
    (1.0, True)
    >>> eta = camera_residual(np.full((200, 200, 3), 2.0), (0.5, 0.0), 0, channel_correlation=0)
    >>> abs(float(np.corrcoef(eta[..., 0].ravel(), eta[..., 1].ravel())[0, 1])) < 0.02
    True
    """
    a, b = (float(v) for v in law)
    m = np.asarray(mean, dtype=np.float64)
    sd = np.sqrt(np.maximum(a * m + b, 0.0))
    generator = np.random.default_rng(rng)
    if m.ndim != 3:
        return sd * generator.standard_normal(m.shape)
    rho = float(np.clip(channel_correlation, 0.0, 1.0))
    z = np.sqrt(rho) * generator.standard_normal((*m.shape[:2], 1))
    if rho < 1:
        z = z + np.sqrt(1.0 - rho) * generator.standard_normal(m.shape)
    return sd * z


def noise_scale(reference_renders: int | None, *, residual: bool) -> float:
    """The factor :math:`c` on the noise a counterfactual adds to a reference mean of
    :math:`m` renders, so that the input holds one render's noise variance :math:`\\sigma^2`.

    .. math::

        c_{\\text{residual}} = \\sqrt{\\frac{m - 1}{m + 1}}, \\qquad
        c_{\\text{camera}} = \\sqrt{\\frac{m - 1}{m}},

    from :math:`c^2 \\operatorname{Var}(\\text{noise}) + \\sigma^2/m = \\sigma^2`, with a
    residual against the reference of variance :math:`\\sigma^2 (1 + 1/m)` and camera noise
    of variance :math:`\\sigma^2`. The reference's own noise (:math:`1/m` of the variance)
    keeps its alignment with the other view.

    Examples
    --------
    >>> round(noise_scale(7, residual=True) ** 2, 4), round(noise_scale(7, residual=False) ** 2, 4)
    (0.75, 0.8571)
    >>> noise_scale(None, residual=True)
    1.0
    """
    if reference_renders is None:
        return 1.0
    m = int(reference_renders)
    if m < 1:
        raise ValueError(f"a reference mean averages at least 1 render, got {m}")
    return float(np.sqrt((m - 1) / (m + 1) if residual else (m - 1) / m))


def counterfactual_pair(
    kind: str,
    left,
    right,
    mean_left,
    mean_right,
    *,
    sign: int,
    shuffle_seed: int = 0,
    strata: int = STRATA,
    conflict_shift: int = 3,
    camera=None,
    reference_renders: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """One test pair of linear renders (see the module docstring for each ``kind``).

    Parameters
    ----------
    kind : str
        One of :data:`TEST_INPUTS`.
    left, right : numpy.ndarray, shape (H, W, 3)
        One seed's render of each view.
    mean_left, mean_right : numpy.ndarray, shape (H, W, 3)
        Each view's reference mean :math:`\\bar I_V` (:func:`reference_mean`: without the
        test frame).
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign`` :math:`s`.
    shuffle_seed : int, keyword-only
        Seed of :math:`\\Pi_S` (:func:`stratified_shuffle`).
    strata : int, keyword-only
        Intensity strata of :math:`\\Pi_S`.
    conflict_shift : int, keyword-only
        :math:`k`, in pixels.
    camera : tuple of numpy.ndarray, optional, keyword-only
        ``(eta_left, eta_right)``: the camera's noise of each view
        (:func:`camera_residual`), needed for ``camera`` and ``camera_shuffled``.
    reference_renders : int, optional, keyword-only
        :math:`m`, the renders averaged in the reference means (:math:`N - 1` for
        :func:`reference_mean`). The reference then holds noise of variance
        :math:`\\sigma^2/m`, so the noise a counterfactual adds is scaled by
        :func:`noise_scale` to give every input one render's noise variance :math:`\\sigma^2`
        (the residual against the reference has :math:`\\sigma^2 (1 + 1/m)`). None: no
        scaling (a noiseless reference).

    Returns
    -------
    (left, right) : numpy.ndarray, float64, shape (H, W, 3)

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> m = rng.random((32, 32, 3)); r = m + rng.normal(size=m.shape)
    >>> _, right = counterfactual_pair("conflict", r, r, m, m, sign=1, conflict_shift=2)
    >>> bool(np.allclose(right[:, 5] - m[:, 5], r[:, 3] - m[:, 3]))
    True
    """
    if kind not in TEST_INPUTS:
        raise ValueError(f"unknown test input {kind!r}; use one of {', '.join(TEST_INPUTS)}")
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    mean_left = np.asarray(mean_left, dtype=np.float64)
    mean_right = np.asarray(mean_right, dtype=np.float64)
    shapes = {a.shape for a in (left, right, mean_left, mean_right)}
    if len(shapes) != 1:
        raise ValueError(f"renders and seed means differ in shape: {sorted(shapes)}")
    if kind == "normal":
        return left, right
    if kind == "clean":
        return mean_left, mean_right
    if kind in ("camera", "camera_shuffled"):
        if camera is None:
            raise ValueError(f"the {kind} test input needs camera=(eta_left, eta_right)")
        c = noise_scale(reference_renders, residual=False)
        eta_l, eta_r = (c * np.asarray(e, dtype=np.float64) for e in camera)
        if kind == "camera_shuffled":
            eta_r = stratified_shuffle(eta_r, mean_right, rng=shuffle_seed, strata=strata)
        return mean_left + eta_l, mean_right + eta_r
    residual = noise_scale(reference_renders, residual=True) * (right - mean_right)
    if kind == "shuffled":
        shuffled = stratified_shuffle(residual, mean_right, rng=shuffle_seed, strata=strata)
        return left, mean_right + shuffled
    return left, mean_right + shift_columns(residual, sign * int(conflict_shift))
