"""The probe's counterfactual inputs: the stratified shuffle, the leave-one-out mean, camera
noise and the planted views (issue 35, "Clean counterfactuals" and "Positive control")."""

from __future__ import annotations

import numpy as np
import pytest

from stereovar.io.transfer import linear_to_srgb
from stereovar.probe.inputs import (
    TEST_INPUTS,
    camera_residual,
    counterfactual_pair,
    reference_mean,
    stratified_shuffle,
)

SHAPE = (128, 128)


def render_like(seed: int, *, a: float = 0.3, b: float = 0.002):
    """A render-like view: piecewise-constant objects in [0, 1.5] (dark and bright, sharp
    edges) with a smooth shading, and Gaussian noise of variance a*mu + b."""
    rng = np.random.default_rng(seed)
    h, w = SHAPE
    levels = rng.choice([0.01, 0.05, 0.2, 0.6, 1.0, 1.5], size=(h // 32 + 1, w // 24 + 1))
    base = np.kron(levels, np.ones((32, 24)))[:h, :w] * (0.7 + 0.3 * np.linspace(0, 1, w))
    mean = np.repeat(base[..., None], 3, axis=2)
    residual = np.sqrt(a * mean + b) * rng.standard_normal(mean.shape)
    return mean, residual


def display(image) -> np.ndarray:
    """What the network sees before standardising: sRGB of the grey clipped to [0, 1]."""
    return linear_to_srgb(np.clip(np.asarray(image).mean(axis=-1), 0.0, 1.0))


def strata_of(mean, k: int) -> np.ndarray:
    """Equal-count quantile bins of the grey mean (ties by position), as the shuffle forms them."""
    g = mean.mean(axis=-1).ravel()
    labels = np.empty(g.size, dtype=int)
    for i, grp in enumerate(np.array_split(np.argsort(g, kind="stable"), k)):
        labels[grp] = i
    return labels.reshape(mean.shape[:2])


def test_test_inputs_include_the_camera_shuffle():
    assert TEST_INPUTS == ("normal", "shuffled", "camera", "camera_shuffled", "clean", "conflict")


def test_stratified_shuffle_keeps_each_stratum_and_the_linear_mean():
    mean, eps = render_like(0)
    out = stratified_shuffle(eps, mean, rng=1, strata=16)
    labels = strata_of(mean, 16)
    for k in range(16):
        before = eps[labels == k]  # (n, 3) pixel vectors: the channels move together
        after = out[labels == k]
        assert np.array_equal(
            before[np.lexsort(before.T)], after[np.lexsort(after.T)]
        ), f"stratum {k} changed its residual vectors"
    # the linear image mean is the same sum of the same numbers (up to summation order)
    assert (mean + out).mean() == pytest.approx((mean + eps).mean(), abs=1e-12)
    assert np.mean(np.all(out == eps, axis=-1)) < 0.05  # and the pixels did move


def test_stratified_shuffle_moves_non_finite_means_among_themselves():
    mean, eps = render_like(1)
    mean[:3, :5] = np.nan
    out = stratified_shuffle(eps, mean, rng=0)
    bad = np.isnan(mean[..., 0])
    assert sorted(out[bad].ravel()) == sorted(eps[bad].ravel())
    assert np.all(np.isfinite(out))


def test_shuffled_right_view_keeps_display_brightness():
    """After clipping and sRGB encoding the shuffled right view's mean brightness moves by
    less than 1 % of the image's standard deviation (the 16-px block shuffle moved it by
    3-15 % on these images)."""
    for seed in range(5):
        mean, eps = render_like(seed)
        right = mean + eps
        _, shuffled = counterfactual_pair(
            "shuffled", right, right, mean, mean, sign=-1, shuffle_seed=seed
        )
        ref = display(right)
        change = abs(display(shuffled).mean() - ref.mean()) / ref.std()
        assert change < 0.01, f"seed {seed}: brightness moved by {100 * change:.2f} % of SD"


def test_shuffled_right_view_keeps_the_noise_law_by_intensity():
    """The residual's SD in intensity deciles (not the shuffle's 16 strata) is kept within
    sampling error, the darkest decile included."""
    mean, eps = render_like(2)
    right = mean + eps
    _, shuffled = counterfactual_pair("shuffled", right, right, mean, mean, sign=1)
    out = shuffled - mean
    labels = strata_of(mean, 10)
    for k in range(10):
        before, after = eps[labels == k].std(), out[labels == k].std()
        n = eps[labels == k].size
        # SD estimates of n values differ by about sd * sqrt(1/n) (two of relative SE 1/sqrt(2n))
        assert abs(after - before) < 5 * before / np.sqrt(n), (k, before, after)


def test_stratified_shuffle_breaks_cross_view_alignment():
    """Two views share a smooth variance pattern (zero disparity): their standardised
    squared residuals correlate; after the shuffle the correlation is chance."""
    from stereovar.calibration.synthesis import smooth_field

    rng = np.random.default_rng(3)
    mean, _ = render_like(3)
    a, b, s = 0.3, 0.002, 1.0
    law = a * mean + b
    z = smooth_field(SHAPE, rng)[..., None]
    v = law * np.exp(s * z - s * s / 2)
    left = v ** 0.5 * rng.standard_normal(mean.shape)
    right = v ** 0.5 * rng.standard_normal(mean.shape)

    def corr(x, y):
        return np.corrcoef((x**2 / law).ravel(), (y**2 / law).ravel())[0, 1]

    n = left.size
    # (e^{s^2} - 1) / (3 e^{s^2} - 1) = 0.24 for s = 1
    assert corr(left, right) > 0.15
    for seed in range(3):
        shuffled = stratified_shuffle(right, mean, rng=seed)
        assert abs(corr(left, shuffled)) < 4 / np.sqrt(n)


def test_camera_shuffled_shuffles_only_the_right_camera_noise():
    mean, _ = render_like(4)
    eta_l = camera_residual(mean, (0.3, 0.002), 0)
    eta_r = camera_residual(mean, (0.3, 0.002), 1)
    left, right = counterfactual_pair(
        "camera_shuffled", mean, mean, mean, mean, sign=1, camera=(eta_l, eta_r), shuffle_seed=5
    )
    assert np.array_equal(left, mean + eta_l)
    assert np.allclose(right - mean, stratified_shuffle(eta_r, mean, rng=5), atol=1e-12)
    cam_l, cam_r = counterfactual_pair("camera", mean, mean, mean, mean, sign=1,
                                       camera=(eta_l, eta_r))
    assert np.array_equal(cam_r, mean + eta_r)
    with pytest.raises(ValueError, match="camera"):
        counterfactual_pair("camera_shuffled", mean, mean, mean, mean, sign=1)


def test_reference_mean_leaves_the_test_frame_out():
    rng = np.random.default_rng(0)
    stack = rng.random((5, 4, 6, 3))
    for frame in range(5):
        others = [stack[m] for m in range(5) if m != frame]
        brute = sum(others) / len(others)
        assert np.allclose(reference_mean(stack, frame), brute, rtol=0, atol=1e-12)
    with pytest.raises(ValueError):
        reference_mean(stack[:1], 0)


def test_camera_residual_follows_the_law():
    """Sample variance per intensity level matches a*mu + b within 5 standard errors
    (Var of a normal sample variance: 2 sigma^4 / (n - 1))."""
    a, b = 0.05, 0.004
    levels = np.array([0.0, 0.1, 0.5, 1.5])
    mean = np.repeat(levels, 64 * 64 // 4 * 3).reshape(64, 64, 3)
    eta = camera_residual(mean, (a, b), np.random.default_rng(7))
    for mu in levels:
        x = eta[mean == mu]
        var = a * mu + b
        assert abs(x.var(ddof=1) - var) < 5 * var * np.sqrt(2 / (x.size - 1)), mu
        assert abs(x.mean()) < 5 * np.sqrt(var / x.size)
    assert np.all(camera_residual(np.full((2, 2), -1.0), (1.0, 0.0), 0) == 0)


def test_stratified_shuffle_moves_every_residual_away():
    """No residual stays within ``min_distance`` pixels of where it was (a stratum of a
    smooth image is a band, where a uniform permutation leaves some residuals nearby)."""
    h, w = 64, 96
    mean = np.broadcast_to(np.linspace(0, 1, w), (h, w))  # strata: vertical bands
    index = np.arange(h * w, dtype=np.float64).reshape(h, w)
    out = stratified_shuffle(index, mean, rng=0, strata=16, min_distance=8)
    sy, sx = np.divmod(out.astype(int), w)
    yy, xx = np.indices((h, w))
    assert np.maximum(abs(sy - yy), abs(sx - xx)).min() >= 8
    assert sorted(out.ravel()) == sorted(index.ravel())


def test_tile_sums_count_predictions_at_zero():
    from stereovar.probe.scoring import SUMS, tile_sums

    rng = np.random.default_rng(0)
    d_gt = rng.integers(0, 6, (20, 30)).astype(float)
    d_hat = rng.choice([0.0, 0.3, -0.4, 0.5, 1.0, 2.0, np.nan], size=(20, 30))
    mask = rng.random((20, 30)) < 0.8
    labels = np.arange(20 * 30).reshape(20, 30) // 100
    sums = tile_sums(d_hat, d_gt, mask, labels, conflict_shift=3)
    assert "zero" in SUMS
    for i, tile in enumerate(sums["tile"]):
        sel = (labels == tile) & mask & np.isfinite(d_hat)
        brute = sum(abs(v) < 0.5 for v in d_hat[sel])
        assert sums["zero"][i] == brute


def _flat_scene(h=96, w=128, d=4):
    truth = {"disparity": np.full((h, w), float(d)), "valid": np.ones((h, w), bool)}
    return np.full((h, w, 3), 0.5), truth


@pytest.mark.parametrize("sign", [1, -1])
def test_planted_views_carry_the_pattern_into_the_right_view(sign):
    """With a constant disparity d the right pixel of left pixel x is x + sign*d. The
    views' ln(sample variance) fields, aligned so, correlate as
    s^2 / (s^2 + psi'(k/2)) with k = N - 1 (ln of a chi^2_k / k has variance psi'(k/2); the
    channels share one draw per pixel, as a path tracer's do), and do not correlate at s = 0,
    nor unaligned."""
    from scipy.special import polygamma

    from stereovar.estimators.seeds import variance_field
    from stereovar.probe.planted import planted_views

    mean, truth = _flat_scene()
    n, d = 8, 4
    xs = np.arange(8, mean.shape[1] - 8)
    for s in (0.0, 0.5, 1.0):
        left, right = planted_views(mean, mean, truth, truth, sign=sign, law=(0.02, 0.001),
                                    strength=s, n=n, rng=np.random.default_rng(int(10 * s)))
        assert left.shape == right.shape == (n, *mean.shape)
        lv = np.log(variance_field(left)[1])[:, xs].ravel()
        rv = np.log(variance_field(right)[1])
        rho = np.corrcoef(lv, rv[:, xs + sign * d].ravel())[0, 1]
        wrong = np.corrcoef(lv, rv[:, xs - sign * d].ravel())[0, 1]  # the other direction
        noise = left - mean
        assert np.array_equal(noise[..., 0], noise[..., 2])  # one draw shared by the channels
        expected = s * s / (s * s + polygamma(1, (n - 1) / 2))
        # the correlation's standard error, widened 3x for the pattern's ~2-px smoothness
        se = 3 * (1 - expected**2) / np.sqrt(lv.size)
        assert abs(rho - expected) < 5 * se, (s, rho, expected)
        assert abs(wrong) < 0.1 * expected + 5 / np.sqrt(lv.size)


def test_planted_views_at_strength_zero_follow_the_camera_law():
    from stereovar.probe.planted import planted_views

    h, w = 64, 64
    levels = np.repeat([0.0, 0.2, 0.8, 1.4], h * w // 4).reshape(h, w)
    mean = np.repeat(levels[..., None], 3, axis=2)
    truth = {"disparity": np.full((h, w), 3.0), "valid": np.ones((h, w), bool)}
    a, b = 0.03, 0.002
    left, right = planted_views(mean, mean, truth, truth, sign=1, law=(a, b), strength=0.0,
                                n=6, rng=np.random.default_rng(0))
    for frames in (left, right):
        for mu in (0.0, 0.2, 0.8, 1.4):
            x = (frames - mean)[:, levels == mu]
            var = a * mu + b
            assert abs(x.var() - var) < 5 * var * np.sqrt(2 / x.size), mu


def test_renders_strength_recovers_the_planted_strength():
    """The calibration's measure of the renders' strength, on frames planted with a known
    strength: it gives it back where the channels' noise is independent, as its camera null
    draws it; where the channels share their noise (a path tracer's, and the probe's planted
    frames) it reads sqrt(s^2 + psi'((N - 1)/2) - psi'(3(N - 1)/2)), the estimation noise its
    null does not subtract, the same on the renders and on the planted cue."""
    from scipy.special import polygamma

    from stereovar.calibration.synthesis import (
        draw_frames,
        planted_pattern,
        variance_fields,
    )
    from stereovar.probe.planted import planted_views, renders_law, renders_strength

    h, w, n = 96, 128, 8
    base = np.linspace(0.05, 1.2, w)[None, :] * np.linspace(0.6, 1.0, h)[:, None]
    mean = np.repeat(base[..., None], 3, axis=2)
    truth = {"disparity": np.full((h, w), 4.0), "valid": np.ones((h, w), bool)}
    offset = polygamma(1, (n - 1) / 2) - polygamma(1, 3 * (n - 1) / 2)
    for s, tol in ((0.0, 0.1), (0.6, 0.08)):
        rng = np.random.default_rng(1)
        pattern = planted_pattern(truth["disparity"], truth["valid"], sign=1, rng=rng)
        v = variance_fields("planted", s, mean={"left": mean, "right": mean},
                            law=(0.02, 0.001), render_variance={}, pattern=pattern, rng=rng)
        independent = draw_frames(mean, v["left"], n, rng)  # the calibration's null's way
        est = renders_strength(independent, truth, rng=np.random.default_rng(2))
        assert abs(est - s) < tol, (s, est)
        left, _ = planted_views(mean, mean, truth, truth, sign=1, law=(0.02, 0.001),
                                strength=s, n=n, rng=np.random.default_rng(1))
        est = renders_strength(left, truth, rng=np.random.default_rng(2))
        assert abs(est - np.sqrt(s * s + offset)) < tol, (s, est, np.sqrt(s * s + offset))
    a, b = renders_law(left, truth)
    assert a > 0 and b >= 0
