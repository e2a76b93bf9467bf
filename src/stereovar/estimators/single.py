"""Per-pixel noise variance from ONE render per view: the candidates, and why none is used.

Eq. 1 (paper Sec. 2.1) needs :math:`N \\ge 2` independent renders of a view. Most published
stereo data sets ship one render per view, so a single-render estimate of :math:`\\sigma^2`
would let the audit read them. Each candidate below maps one render :math:`I` (H, W, 3) to a
field :math:`\\hat\\sigma^2` (H, W) on the scale of Eq. 1 (RGB-averaged), and to the clean
intensity :math:`\\hat\\mu` the intensity control conditions on:

``oidn``, ``oidn_aux``
    the local variance of the residual after a denoiser, :math:`r = I - D(I)` with
    :math:`D` Intel Open Image Denoise (colour only, or with the albedo and normal passes),
    :func:`residual_variance` (:func:`window_variance` of :math:`r`);
``wavelet_mad``
    the local median absolute deviation of the finest diagonal wavelet subband (Donoho and
    Johnstone 1994, made local in a window), :func:`local_mad_variance`;
``poisson_gaussian``
    a signal-dependent noise law :math:`\\sigma^2 = a\\mu + b` fitted to one render (after
    Foi et al. 2008), :func:`poisson_gaussian_variance`: a function of intensity alone, so
    whatever it shares across views is explained by intensity by construction.

Cycles' own passes carry no such field: the per-pixel variance passes of Blender's former NLM
denoiser ("Denoising Image Variance") were removed with it in Blender 3.0; Blender 5.0's
Cycles adds "Denoising Normal", "Denoising Albedo" and "Denoising Depth" only, plus the debug
"Sample Count" pass, which is constant without adaptive sampling and under it a function of
the stopping rule's relative error, not a variance (``docs/single_render.md``).

The measurement (``bench/single_render.py``, ``docs/single_render.md``) refuses all four.
The denoiser residuals agree with Eq. 1 in rank but find no planted cue in one frame up to
twice the strength the renders show, nor the renders' own cue; the Poisson-Gaussian law
calls a cue on 17% of cue-free frames; the local wavelet MAD agrees best (Spearman 0.77) and
detects the cue when its matched null is drawn on the seed mean, but one render has no seed
mean, and against the null it can build from itself (:func:`one_render_null`) it calls a cue
on 71% of cue-free frames. So the audit refuses one render per view (:func:`refusal`); the
functions stay for the measurement and for anyone who repeats it on other data.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..links import docs_page
from ..rig import VIEWS

WINDOW = 7
"""Side, in pixels, of the square window of the local estimates."""

MAD_TO_SD = 0.6744897501960817
"""Median of :math:`|Z|` for a standard normal :math:`Z`, :math:`\\Phi^{-1}(3/4)`."""

METHODS = ("oidn", "oidn_aux", "wavelet_mad", "poisson_gaussian")
"""The single-render candidates, in the order the measurement reports them."""

DOCS_PAGE = "docs/single_render.md"
"""The page with the measurement behind :func:`refusal`, in the repository. The refusal cites
its address on the documentation site (:func:`stereovar.links.docs_page`), which a user who
installed the wheel can open."""


class SingleField(NamedTuple):
    """One view's single-render estimate.

    Attributes
    ----------
    mean : numpy.ndarray (H, W, 3), float64
        The clean-image estimate :math:`\\hat\\mu_c` (the intensity control's :math:`\\mu`).
    variance : numpy.ndarray (H, W), float64
        :math:`\\hat\\sigma^2`, RGB-averaged as Eq. 1.
    """

    mean: np.ndarray
    variance: np.ndarray


def _image(image) -> np.ndarray:
    block = np.asarray(image, dtype=np.float64)
    if block.ndim == 2:
        block = block[..., None]
    if block.ndim != 3:
        raise ValueError(f"an image must have shape (H, W) or (H, W, C), got {block.shape}")
    return block


def _window(window: int) -> int:
    window = int(window)
    if window < 2:
        raise ValueError(f"window must be at least 2 pixels, got {window}")
    return window


def box_sums(field, *, window: int = WINDOW) -> tuple[np.ndarray, np.ndarray]:
    """Sum of a field over a square window around each pixel, and the window's pixel count.

    .. math:: S(x, y) = \\sum_{|u| \\le h,\\, |v| \\le h} f(x + u, y + v), \\qquad
        n(x, y) = \\#\\{(u, v) : (x + u, y + v) \\text{ inside the image}\\}

    with :math:`h = \\lfloor w/2 \\rfloor` (an even ``window`` reaches :math:`h` on one side
    and :math:`h - 1` on the other); pixels outside the image are left out, not mirrored, so
    a window at the border holds fewer, distinct pixels.

    Parameters
    ----------
    field : array_like (H, W) or (H, W, C)
    window : int, keyword-only

    Returns
    -------
    sums : numpy.ndarray, float64, the shape of ``field``
    counts : numpy.ndarray (H, W), float64

    Examples
    --------
    >>> s, n = box_sums(np.ones((3, 4)), window=3)
    >>> n.tolist()
    [[4.0, 6.0, 6.0, 4.0], [6.0, 9.0, 9.0, 6.0], [4.0, 6.0, 6.0, 4.0]]
    >>> bool(np.allclose(s, n))
    True
    """
    from scipy.ndimage import uniform_filter

    window = _window(window)
    f = np.asarray(field, dtype=np.float64)
    spatial = (window, window) + (1,) * (f.ndim - 2)
    area = float(window * window)
    sums = uniform_filter(f, size=spatial, mode="constant", cval=0.0) * area
    counts = uniform_filter(np.ones(f.shape[:2]), size=window, mode="constant") * area
    return sums, np.rint(counts)


def window_variance(residual, *, window: int = WINDOW) -> np.ndarray:
    """Local sample variance of a residual, corrected for the window's own mean.

    Per channel :math:`c`, over the :math:`n` pixels of the window around :math:`(x, y)`,

    .. math::

        \\hat v_c(x, y) = \\frac{1}{n - 1} \\Bigl(\\sum_{i} r_{c,i}^2
            - \\frac{1}{n}\\bigl(\\sum_i r_{c,i}\\bigr)^2\\Bigr), \\qquad
        \\hat\\sigma^2(x, y) = \\frac13 \\sum_c \\hat v_c(x, y),

    the unbiased sample variance: for residuals with a common mean :math:`m` (any, unknown)
    and variance :math:`\\sigma^2` in the window, :math:`\\mathrm E[\\hat v_c] = \\sigma^2`;
    dividing the raw second moment by :math:`n` instead would add :math:`m^2` and the
    :math:`1/n` would miss the :math:`(n-1)/n` that estimating :math:`m` costs. The
    RGB average matches Eq. 1 (paper Sec. 2.1). The sums are taken about each channel's
    image mean (which leaves the estimate unchanged) and the result is floored at 0.

    Parameters
    ----------
    residual : array_like (H, W) or (H, W, C)
    window : int, keyword-only
        :func:`box_sums`' window; at least 2.

    Returns
    -------
    numpy.ndarray (H, W), float64

    Examples
    --------
    A constant offset is no variance; a checkerboard of :math:`\\pm 1` has, over a
    3 x 3 window of five :math:`+1` and four :math:`-1`, sample variance
    :math:`(9 - 1/9) / 8 = 10/9`:

    >>> window_variance(np.full((5, 5), 3.0), window=3).max()
    0.0
    >>> board = np.where(np.indices((5, 5)).sum(axis=0) % 2 == 0, 1.0, -1.0)
    >>> round(float(window_variance(board, window=3)[2, 2]), 6)
    1.111111
    """
    r = _image(residual)
    r = r - r.mean(axis=(0, 1))  # shifted data: the sums stay small (no cancellation)
    s1, n = box_sums(r, window=window)
    s2, _ = box_sums(r * r, window=window)
    n = n[..., None]
    v = (s2 - s1 * s1 / n) / np.maximum(n - 1.0, 1.0)
    return np.maximum(v, 0.0).mean(axis=-1)


def denoised(image, *, albedo=None, normal=None, quality: str = "high") -> np.ndarray:
    """:math:`D(I)`: OIDN's RT filter on one HDR render, as the ``denoise`` transform runs it
    (:func:`stereovar.transforms.denoise.denoise_image`), with the auxiliary passes when
    given; float64 (H, W, 3)."""
    from ..transforms.denoise import denoise_image

    out, _ = denoise_image(
        np.asarray(image, dtype=np.float32),
        albedo=albedo,
        normal=normal if albedo is not None else None,
        quality=quality,
    )
    return out.astype(np.float64)


def residual_variance(image, clean, *, window: int = WINDOW) -> np.ndarray:
    """Candidate (a): local variance of the residual after a denoiser.

    .. math::

        r = I - D(I), \\qquad \\hat\\sigma^2 = \\operatorname{wvar}_w(r)

    with :func:`window_variance` (mean-corrected, RGB-averaged). For a denoiser that returned
    the clean image :math:`\\mu`, :math:`r` would be the noise and
    :math:`\\mathrm E[\\hat\\sigma^2] = \\sigma^2` where :math:`\\sigma^2` is constant over the
    window. A real :math:`D` keeps part of each pixel's own noise (scaling :math:`\\hat\\sigma^2`
    down by a factor a correlation does not see) and removes detail the noise hid (texture,
    edges): that detail is a function of the scene, which both views share once aligned, so
    it is exactly what the matched null through the same path must subtract.

    Parameters
    ----------
    image, clean : array_like (H, W, C)
        :math:`I` and :math:`D(I)` (:func:`denoised`).
    window : int, keyword-only

    Returns
    -------
    numpy.ndarray (H, W), float64
    """
    return window_variance(_image(image) - _image(clean), window=window)


def diagonal_detail(image) -> np.ndarray:
    """The finest diagonal Haar wavelet subband, undecimated, per channel.

    .. math::

        d(x, y) = \\tfrac12\\bigl(I(x, y) - I(x + 1, y) - I(x, y + 1) + I(x + 1, y + 1)\\bigr)

    It vanishes on any image that is linear in :math:`x` and :math:`y` (a smooth image's
    local trend), and for independent noise of variance :math:`\\sigma_i^2` at the four
    pixels :math:`\\operatorname{Var} d = \\frac14 \\sum_i \\sigma_i^2`: the noise variance
    itself where it is locally constant (the subband of Donoho and Johnstone's estimate,
    with the Haar filter). The last row and column repeat their neighbour's value.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)

    Returns
    -------
    numpy.ndarray (H, W, C), float64

    Examples
    --------
    >>> ramp = np.add.outer(np.arange(4.0), 2 * np.arange(5.0))
    >>> float(np.abs(diagonal_detail(ramp)).max())
    0.0
    """
    f = _image(image)
    d = 0.5 * (f[:-1, :-1] - f[:-1, 1:] - f[1:, :-1] + f[1:, 1:])
    return np.pad(d, ((0, 1), (0, 1), (0, 0)), mode="edge")


def local_mad_variance(image, *, window: int = WINDOW) -> np.ndarray:
    """Candidate (c): Donoho and Johnstone's noise estimate, made local.

    .. math::

        \\hat\\sigma_c(x, y) = \\frac{\\operatorname{median}_{W(x, y)} |d_c|}{0.6745},
        \\qquad \\hat\\sigma^2(x, y) = \\frac13 \\sum_c \\hat\\sigma_c(x, y)^2

    with :math:`d` the finest diagonal subband (:func:`diagonal_detail`) and :math:`W` the
    ``window`` x ``window`` square (``skimage.restoration.estimate_sigma`` takes the median
    over the whole image). The median ignores the few large :math:`d` an edge leaves; for
    Gaussian noise :math:`\\operatorname{median}|d| = 0.6745\\,\\sigma`. It estimates the
    scale of the bulk of the noise, so the heavy tail of Monte Carlo noise (fireflies) that
    Eq. 1 counts is missed.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)
    window : int, keyword-only

    Returns
    -------
    numpy.ndarray (H, W), float64
    """
    from scipy.ndimage import median_filter

    d = np.abs(diagonal_detail(image))
    window = _window(window)
    med = median_filter(d, size=(window, window, 1), mode="reflect")
    return ((med / MAD_TO_SD) ** 2).mean(axis=-1)


def box_mean(image, *, window: int = WINDOW) -> np.ndarray:
    """The window mean of an image per channel (:func:`box_sums` over the counts); the clean
    intensity of the candidates that use no denoiser."""
    s, n = box_sums(_image(image), window=window)
    return s / n[..., None]


def poisson_gaussian_variance(image, intensity, *, window: int = WINDOW, mask=None):
    """Candidate (c'): a Poisson-Gaussian noise law fitted to one render.

    .. math::

        \\hat\\sigma^2(x, y) = \\hat a\\,\\mu(x, y) + \\hat b, \\qquad
        (\\hat a, \\hat b) = \\arg\\min \\sum_k \\bigl(\\tilde s_k - a \\tilde\\mu_k - b\\bigr)^2

    over the medians :math:`(\\tilde\\mu_k, \\tilde s_k)` of quantile bins of :math:`\\mu` of
    the local estimates :func:`local_mad_variance` (the law of Foi et al. 2008, fitted as
    :func:`stereovar.calibration.synthesis.camera_law` fits the camera null; Foi et al. fit
    by maximum likelihood on smooth segments). The field is a function of :math:`\\mu`
    alone, so its intensity-controlled correlation across views is 0 by construction: a
    camera's law has no Monte Carlo cue to find.

    Parameters
    ----------
    image : array_like (H, W, C)
    intensity : array_like (H, W)
        :math:`\\mu` (the RGB mean of the clean estimate).
    window : int, keyword-only
    mask : array_like of bool (H, W), optional
        Pixels to fit on.

    Returns
    -------
    numpy.ndarray (H, W), float64
    """
    from ..calibration.synthesis import camera_law

    mu = np.asarray(intensity, dtype=np.float64)
    a, b = camera_law(local_mad_variance(image, window=window), mu, mask)
    return a * np.maximum(mu, 0.0) + b


def single_render_field(
    image, method: str, *, albedo=None, normal=None, window: int = WINDOW, clean=None
) -> SingleField:
    """One view's :class:`SingleField` by the candidate ``method`` (:data:`METHODS`).

    The clean estimate :math:`\\hat\\mu` is :math:`D(I)` for the denoiser candidates and the
    window mean (:func:`box_mean`) for the others.

    Parameters
    ----------
    image : array_like (H, W, 3)
        One render.
    method : str
    albedo, normal : array_like (H, W, 3), keyword-only, optional
        The auxiliary passes (``oidn_aux`` needs the albedo).
    window : int, keyword-only
    clean : array_like (H, W, 3), keyword-only, optional
        :math:`D(I)` when already computed.
    """
    if method not in METHODS:
        raise ValueError(f"unknown single-render method {method!r}; use one of {METHODS}")
    image = _image(image)
    if method in ("oidn", "oidn_aux"):
        if method == "oidn_aux" and albedo is None:
            raise ValueError("oidn_aux needs the albedo pass (and the normal pass, optional)")
        if clean is None:
            aux = {"albedo": albedo, "normal": normal} if method == "oidn_aux" else {}
            clean = denoised(image, **aux)
        clean = _image(clean)
        return SingleField(clean, residual_variance(image, clean, window=window))
    mean = box_mean(image, window=window)
    if method == "wavelet_mad":
        return SingleField(mean, local_mad_variance(image, window=window))
    return SingleField(
        mean, poisson_gaussian_variance(image, mean.mean(axis=-1), window=window)
    )


def single_render_statistics(
    fields: dict, ground_truth_left, *, sign: int, settings, label: str,
    methods=("partial",),
) -> dict:
    """Eq. 2 and the registered statistics on single-render fields, through the same code as
    the correlation rows and the calibration replicates.

    .. math::

        \\rho_{\\text{partial}} = \\mathrm{corr}\\bigl(e_L, e_{R\\to L}\\bigr)\\big|_{\\Omega},
        \\qquad e_V = \\ln\\hat\\sigma_V^2 - \\hat g_V(\\ln\\hat\\mu_V)

    with :math:`\\hat\\sigma_V^2, \\hat\\mu_V` a :class:`SingleField` per view in place of
    Eq. 1 and the seed mean (paper Sec. 2.2-2.3; the intensity control of
    :mod:`stereovar.controls.intensity`), each statistic evaluated by
    :func:`stereovar.statistics.registry.evaluate` with its spatial block bootstrap over all
    valid pixels.

    Parameters
    ----------
    fields : dict
        ``left`` and ``right`` to a :class:`SingleField`.
    ground_truth_left : mapping
        ``disparity`` and ``valid`` of the left view.
    sign : int
        ``disparity_sign``.
    settings : stereovar.statistics.fields.AnalysisSettings
    label : str
        Seeds the bootstrap draws.
    methods : sequence of str
        Registered statistics.

    Returns
    -------
    dict
        Method name to its result (:data:`~stereovar.statistics.correlation.RESULT_KEYS`).
    """
    from ..seeding import derive_seed
    from ..statistics.bootstrap import tile_labels
    from ..statistics.fields import aligned_fields, seed_mean_controls
    from ..statistics.pixels import PixelSet
    from ..statistics.registry import METHODS as STATISTICS
    from ..statistics.registry import BootstrapDraws, evaluate
    from ..statistics.warp import align_variance

    left, right = (np.asarray(fields[v].variance, dtype=np.float64) for v in VIEWS)
    aligned = align_variance(
        left, right, ground_truth_left, sign=sign,
        finite_left=np.isfinite(left), finite_right=np.isfinite(right),
    )
    aligned_set = aligned_fields(
        left, np.where(np.isfinite(right), right, np.nan), aligned["warped"],
        ground_truth_left=ground_truth_left, sign=sign, settings=settings,
        **seed_mean_controls(fields["left"].mean, fields["right"].mean, ground_truth_left,
                             sign=sign),
    )
    pixels = PixelSet(
        np.asarray(aligned["omega"], dtype=bool),
        tile_labels(left.shape, settings.bootstrap.tile),
    )
    draws = BootstrapDraws(settings.bootstrap, derive_seed(settings.bootstrap.seed, label, "all"))
    return {
        name: evaluate(STATISTICS.get(name), aligned_set, pixels, settings=settings, draws=draws)
        for name in methods
    }


def residual_channel_correlation(image, clean, valid=None) -> float:
    """The correlation of a pixel's noise between its channels, from one render's residual.

    .. math::

        \\rho = \\frac{3 q - 1}{2}, \\qquad
        q = \\frac{\\sum_p \\bar r_p^2}{\\sum_p \\frac13 \\sum_c r_{c,p}^2}, \\qquad r = I - D(I)

    (:func:`stereovar.probe.experiment.channel_correlation` with the residual in place of
    the deviations from the seed mean), clipped to [0, 1]: the grey residual keeps
    :math:`(1 + 2\\rho)/3` of the channels' variance.
    """
    r = _image(image) - _image(clean)
    ok = np.ones(r.shape[:2], bool) if valid is None else np.asarray(valid, dtype=bool)
    ok &= np.isfinite(r).all(axis=-1)
    total = float((r[ok] ** 2).mean(axis=-1).sum())
    if not total > 0:
        return 1.0
    grey = float((r[ok].mean(axis=-1) ** 2).sum())
    return float(np.clip((3 * grey / total - 1) / 2, 0.0, 1.0))


def one_render_null(
    images: dict, clean: dict, ground_truth: dict, *, sign: int, settings, rng,
    method: str = "wavelet_mad", draws: int = 4, label: str = "", aux: dict | None = None,
) -> dict:
    """The matched null of a single-render statistic built from the single render alone.

    With one render per view there is no seed mean to draw the calibration's nulls on
    (:mod:`stereovar.calibration.synthesis`), so the clean estimate :math:`D(I_V)` takes
    its place: a camera law :math:`a\\mu + b` is fitted to the single-render field against
    :math:`D(I)`'s intensity (:func:`~stereovar.calibration.synthesis.camera_law`), and

    .. math::

        I_V^{0,k} = D(I_V) + \\sqrt{a D(I_V) + b}\\;\\varepsilon^{k}, \\qquad
        I_V^{\\text{mis},k} = D(I_V) + \\sqrt{\\tilde v_V}\\;\\varepsilon^{k}

    (:math:`\\varepsilon` standard normal with the residual's channel correlation,
    :func:`residual_channel_correlation`; :math:`\\tilde v` the single-render field, the
    right one moved by a random offset) go through the same estimator and statistic. Their
    :math:`\\rho_{\\text{partial}}` give the null's mean and standard error, and the chance
    spread, for :func:`stereovar.calibration.nulls.difference_interval`.

    Parameters
    ----------
    images, clean : dict
        View to one render :math:`I_V` and to :math:`D(I_V)` (H, W, 3).
    ground_truth : dict
        View to ``disparity`` and ``valid``.
    sign : int
    settings : stereovar.statistics.fields.AnalysisSettings
    rng : numpy.random.Generator
    method : str, keyword-only
        A :data:`METHODS` entry.
    draws : int, keyword-only
        Frames per view of each null.
    label : str, keyword-only
        Seeds the bootstrap draws.
    aux : dict, keyword-only, optional
        View to ``{"albedo", "normal"}`` for the denoiser candidates.

    Returns
    -------
    dict
        ``null_rho``, ``null_se``, ``chance_sd``, ``law`` (a, b) and ``channel_correlation``.
    """
    from ..calibration.synthesis import camera_law, draw_frames, variance_fields

    valid = np.asarray(ground_truth["left"]["valid"], dtype=bool)
    base = {v: np.maximum(_image(clean[v]), 0.0) for v in VIEWS}
    field = {v: single_render_field(images[v], method, clean=clean[v]).variance for v in VIEWS}
    law = camera_law(field["left"], base["left"].mean(axis=-1), valid)
    rho_c = residual_channel_correlation(images["left"], clean["left"], valid)
    values: dict = {"camera": [], "misaligned": []}
    for k in range(int(draws)):
        for kind in values:
            v = variance_fields(kind, 0.0, mean=base, law=law, render_variance=field, rng=rng)
            frames = {
                view: draw_frames(base[view], v[view], 1, rng, channel_correlation=rho_c)[0]
                for view in VIEWS
            }
            fields = {view: single_render_field(frames[view], method,
                                                **dict((aux or {}).get(view) or {}))
                      for view in VIEWS}
            result = single_render_statistics(
                fields, ground_truth["left"], sign=sign, settings=settings,
                label=f"{label}|{kind}|{k}",
            )["partial"]
            values[kind].append(result["rho"])
    camera = np.array([x for x in values["camera"] if math.isfinite(x)])
    chance = np.array([x for x in values["misaligned"] if math.isfinite(x)])
    return {
        "null_rho": float(camera.mean()) if camera.size else math.nan,
        "null_se": float(camera.std(ddof=1) / math.sqrt(camera.size))
        if camera.size > 1 else math.nan,
        "chance_sd": float(chance.std(ddof=1)) if chance.size > 1 else math.nan,
        "law": law,
        "channel_correlation": rho_c,
    }


def refusal(numbers: dict | None = None) -> str:
    """The one line the audit gives for one render per view: why, with the measured numbers.

    Parameters
    ----------
    numbers : dict, optional
        The measurement to quote (default :data:`MEASURED`): ``method`` (the best
        candidate), ``spearman`` (its rank agreement with Eq. 1), ``fpr`` (how often it calls
        a cue on cue-free camera frames against the null one render can build), and
        ``n2_smallest`` and ``n2_fpr`` (Eq. 1 at N = 2: the smallest planted strength it
        detects with 80% power, as a multiple of the renders' own, and its worst
        false-positive rate).

    Returns
    -------
    str

    Examples
    --------
    >>> line = refusal({"method": "m", "spearman": 0.5, "fpr": 0.4, "n2_smallest": 0.3,
    ...                 "n2_fpr": 0.0})
    >>> "calls a cue in 40% of cue-free" in line and "from 0.3x" in line
    True
    >>> line.split("false positives (")[1].split(")")[0].endswith("/single_render.html")
    True
    >>> "docs/single_render.md" not in line and "\\n" not in line
    True
    """
    m = dict(MEASURED if numbers is None else numbers)
    page = docs_page(Path(DOCS_PAGE).stem)
    return (
        "one render per view cannot tell a Monte Carlo cue from none: Eq. 1 needs N >= 2 "
        "independent renders, and a single render's noise estimate needs a matched null "
        "drawn on the clean image it lacks; the best one "
        f"({m['method']}, Spearman {float(m['spearman']):.2f} with Eq. 1) calls a cue in "
        f"{100 * float(m['fpr']):.0f}% of cue-free camera frames against the null one render "
        "can build, where N = 2 renders per view detect a planted cue from "
        f"{float(m['n2_smallest']):.3g}x the renders' strength with at most "
        f"{100 * float(m['n2_fpr']):.0f}% false positives ({page}); render N >= 2 seeds "
        "per view"
    )


MEASURED = {
    "method": "wavelet_mad",
    "spearman": 0.77,
    "fpr": 0.71,
    "n2_smallest": 0.425,
    "n2_fpr": 0.02,
}
"""What ``bench/single_render.py`` measured on the default scenes (``docs/single_render.md``):
the best candidate and its mean Spearman correlation with Eq. 1, its false-positive rate per
frame on the camera null with the null built from one render, and Eq. 1 at N = 2 (smallest
detectable planted strength with 80% power, worst false-positive rate on the matched
nulls)."""
