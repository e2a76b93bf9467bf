"""Mitigation transforms (stereovar.transforms) against analytic laws and pyoidn itself."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from stereovar.errors import ConfigError
from stereovar.transforms import TRANSFORMS, TransformInputs, check_reads, get_transform
from stereovar.transforms.denoise import denoise_image

GAIN, READ = 1000.0, 2.0
A, B = 1.0 / GAIN, (READ / GAIN) ** 2
U32 = 2.0**-24  # float32 unit roundoff


def seed_stats(stack):
    """Per-channel mean and unbiased variance over seeds, by explicit sums."""
    stack = np.asarray(stack, dtype=np.float64)
    n = stack.shape[0]
    mean = stack.sum(axis=0) / n
    var = ((stack - mean) ** 2).sum(axis=0) / (n - 1)
    return mean, var


def inputs_for(stack, k, *, rng_seed=0, **extra):
    mean, var = seed_stats(stack)
    return TransformInputs(
        render=stack[k].astype(np.float32),
        view="left",
        seed_index=k,
        rng_seed=rng_seed,
        seed_mean=mean,
        seed_var=var,
        n_seeds=stack.shape[0],
        **extra,
    )


def mc_renders(n, shape=(48, 40), seed=0):
    """Renders with a known per-pixel residual variance (Gaussian, MC-like: large and
    spatially structured, unrelated to a*mu + b)."""
    rng = np.random.default_rng(seed)
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w]
    mu = np.stack([0.2 + 0.8 * (xx / w), 0.5 + 0.3 * np.sin(yy / 3.0), 0.05 + 0.0 * xx], -1)
    sigma = 0.05 + 0.3 * ((xx // 8 + yy // 8) % 2)[..., None] * mu
    return (mu + sigma * rng.standard_normal((n, h, w, 3))).astype(np.float32), mu, sigma


# --- registry ----------------------------------------------------------------------------


def test_registry_names_and_reads():
    assert set(TRANSFORMS.names()) == {"denoise", "denoise_sensor", "equalise", "sensor_only",
                                       "png8_filmic", "png16_filmic", "png8_agx"}
    assert get_transform("png16_filmic").encoding["bits"] == 16
    assert get_transform("denoise").encoding is None
    equalise = get_transform("equalise")
    assert equalise.reads == ("seed_mean", "seed_var")
    assert equalise.missing({"seed_mean"}) == ["seed_var"]
    assert equalise.missing({"seed_mean", "seed_var"}) == []
    assert get_transform("denoise").reads == ()
    assert get_transform("denoise").optional_reads == ("albedo", "normal")
    assert get_transform("sensor_only").random and not get_transform("equalise").random


def test_unknown_transform_names_config_key():
    with pytest.raises(ConfigError, match="mitigations.names.*'blur'.*equalise"):
        get_transform("blur")


def test_check_reads_is_one_line_with_fix():
    with pytest.raises(ConfigError) as err:
        check_reads(get_transform("equalise"), {"albedo"}, source="audit 'team_a'")
    message = str(err.value)
    assert "\n" not in message
    assert "transform 'equalise' needs seed_mean, seed_var" in message
    assert "audit 'team_a'" in message and "gives: albedo" in message
    assert "at least 2 seeds" in message and "remove 'equalise'" in message
    check_reads(get_transform("denoise"), set(), source="audit 'team_a'")  # optional reads


def test_missing_reads_refused_before_apply():
    stack, _, _ = mc_renders(3, shape=(8, 8))
    bare = TransformInputs(render=stack[0], view="right", seed_index=0, rng_seed=1)
    for name in ("equalise", "sensor_only"):
        with pytest.raises(ConfigError, match=f"transform '{name}' needs seed_mean"):
            get_transform(name)(bare)


def test_inputs_validate_shapes():
    render = np.zeros((4, 5, 3), np.float32)
    with pytest.raises(ValueError, match="seed_mean has shape"):
        TransformInputs(render, "left", 0, 0, seed_mean=np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="view must be"):
        TransformInputs(render, "centre", 0, 0)


def test_importing_transforms_pulls_in_no_pyoidn():
    code = (
        "import sys; import stereovar.transforms as t; t.get_transform('equalise'); "
        "t.get_transform('denoise'); assert 'pyoidn' not in sys.modules, 'pyoidn imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


# --- equalise ----------------------------------------------------------------------------


def test_equalise_variance_is_camera_law_exactly_over_its_seeds():
    """Over the N renders the statistics came from, Eq. 1's variance of the output is
    a*mu + b up to float32 rounding of the output (bounded per pixel below)."""
    n = 6
    stack, _, _ = mc_renders(n)
    mean, _ = seed_stats(stack)
    out = np.stack([get_transform("equalise")(inputs_for(stack, k)) for k in range(n)])
    assert out.dtype == np.float32
    target = A * np.maximum(mean, 0.0) + B
    _, var_out = seed_stats(out)
    eps = out.astype(np.float64) - mean
    rounding = U32 * np.abs(out.astype(np.float64))
    bound = (2 * (np.abs(eps) * rounding).sum(0) + (rounding**2).sum(0)) / (n - 1)
    assert np.all(np.abs(var_out - target) <= 2 * bound + 1e-15)
    # the residual keeps its shape: one positive factor sqrt(target / s^2) per pixel and
    # channel, the same for every seed, up to the output's float32 rounding
    _, var_in = seed_stats(stack)
    factor = np.sqrt(target / var_in)
    expected = mean + factor * (stack.astype(np.float64) - mean)
    assert np.all(np.abs(out - expected) <= U32 * np.abs(expected) * 1.001 + 1e-15)


@pytest.mark.parametrize("n", [4, 10])
def test_equalise_one_render_has_camera_variance_within_estimator_noise(n):
    """One equalised render, over pixels: q = eps'^2 / (a mu + b) = eps^2 / s^2, and for
    Gaussian residuals eps_n^2 / sum_m eps_m^2 = (N-1)/N * Beta(1/2, (N-2)/2), so
    E[q] = (N-1)/N and Var[q] = ((N-1)^2/N)^2 Var[Beta]."""
    stack, mu, _ = mc_renders(n, shape=(96, 80), seed=n)
    mean, _ = seed_stats(stack)
    target = A * np.maximum(mean, 0.0) + B
    alpha, beta = 0.5, (n - 2) / 2
    var_beta = alpha * beta / ((alpha + beta) ** 2 * (alpha + beta + 1))
    expected = (n - 1) / n
    sd_q = ((n - 1) ** 2 / n) * np.sqrt(var_beta)
    for k in (0, n - 1):
        out = get_transform("equalise")(inputs_for(stack, k)).astype(np.float64)
        q = (out - mean) ** 2 / target
        se = sd_q / np.sqrt(q.size)
        assert abs(q.mean() - expected) < 4 * se, (q.mean(), expected, se)


def test_equalise_zero_and_nonfinite_variance():
    stack, _, _ = mc_renders(4, shape=(6, 6))
    stack[:, 1, 2, :] = 0.25  # every seed equal: s^2 = 0
    stack[2, 3, 3, 1] = np.nan  # a non-finite render entry
    mean, var = seed_stats(stack)
    out = get_transform("equalise")(inputs_for(stack, 2))
    assert_array_equal(out[1, 2], np.float32(0.25))
    assert np.isnan(out[3, 3, 1]) and np.isfinite(out[3, 3, [0, 2]]).all()
    assert np.isfinite(np.delete(out.reshape(-1), 3 * 6 * 3 + 3 * 3 + 1)).all()


# --- sensor_only -------------------------------------------------------------------------

LEVELS = (0.0, 0.01, 0.1, 0.5, 1.0, 2.0)


def test_sensor_only_mean_and_variance_within_estimator_noise():
    """M frames (one rng_seed each) per pixel: the sample variance S^2 of M draws of a
    Poisson-Gaussian in electrons has Var[S^2] = (m4 - s^4 (M-3)/(M-1)) / M with
    m4 = lam + 3 lam^2 + 6 lam r^2 + 3 r^4 (Poisson plus independent Gaussian)."""
    band, width, m = 4, 16, 40
    mu = np.repeat(np.asarray(LEVELS), band)[:, None, None] * np.ones((1, width, 3))
    inputs = [
        TransformInputs(
            render=np.zeros(mu.shape, np.float32),
            view="right",
            seed_index=0,
            rng_seed=s,
            seed_mean=mu,
            seed_var=np.ones(mu.shape),
            n_seeds=m,
        )
        for s in range(m)
    ]
    frames = np.stack([get_transform("sensor_only")(x, gain=GAIN, read_noise=READ) for x in inputs])
    mean, var = seed_stats(frames)
    for i, level in enumerate(LEVELS):
        rows = slice(i * band, (i + 1) * band)
        lam, r2 = GAIN * level, READ**2
        s2 = lam + r2
        m4 = lam + 3 * lam**2 + 6 * lam * r2 + 3 * r2**2
        var_s2 = (m4 - s2**2 * (m - 3) / (m - 1)) / m
        k = var[rows].size
        ratio = var[rows].mean() / (A * level + B)
        assert abs(ratio - 1) < 4 * np.sqrt(var_s2 / k) / s2, (level, ratio)
        se_mean = np.sqrt((A * level + B) / (m * k))
        assert abs(mean[rows].mean() - level) < 4 * se_mean, level


def test_sensor_only_is_reproducible_and_nan_where_mean_is_not_finite():
    mu = np.full((5, 5, 3), 0.4)
    mu[2, 2, 0] = np.nan
    x = TransformInputs(np.zeros((5, 5, 3), np.float32), "left", 3, 17, seed_mean=mu)
    one, two = get_transform("sensor_only")(x), get_transform("sensor_only")(x)
    assert_array_equal(one, two)
    assert np.isnan(one[2, 2, 0]) and np.isfinite(one).sum() == one.size - 1
    other = TransformInputs(np.zeros((5, 5, 3), np.float32), "left", 3, 18, seed_mean=mu)
    assert not np.array_equal(
        np.nan_to_num(one), np.nan_to_num(get_transform("sensor_only")(other))
    )


# --- denoise -----------------------------------------------------------------------------


def structured_scene(seed=0, shape=(96, 128), noise=0.15):
    rng = np.random.default_rng(seed)
    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w]
    clean = np.stack(
        [
            0.5 + 0.4 * np.sin(xx / 9.0),
            0.3 + 0.5 * ((xx // 16 + yy // 16) % 2),
            0.2 + 0.1 * np.cos(yy / 6.0),
        ],
        -1,
    ).astype(np.float32)
    albedo = np.clip(clean, 0, 1).astype(np.float32)
    normal = np.zeros_like(clean)
    normal[..., 2] = 1.0
    noisy = np.maximum(clean + noise * rng.standard_normal(clean.shape), 0).astype(np.float32)
    return clean, noisy, albedo, normal


@pytest.mark.parametrize("aux", [False, True])
def test_denoise_equals_pyoidn_called_directly(aux):
    pyoidn = pytest.importorskip("pyoidn")
    _, noisy, albedo, normal = structured_scene()
    extra = {"albedo": albedo, "normal": normal} if aux else {}
    x = TransformInputs(noisy, "left", 0, 0, **extra)
    ours = get_transform("denoise")(x)
    direct = pyoidn.denoise(noisy, extra.get("albedo"), extra.get("normal"), hdr=True)
    assert ours.dtype == np.float32
    assert_array_equal(ours, direct)  # same network, same inputs: bit-identical
    assert_array_equal(get_transform("denoise")(x, threads=4), ours)


def test_denoise_reduces_error_against_clean_image():
    pytest.importorskip("pyoidn")
    clean, noisy, albedo, normal = structured_scene(seed=3)
    before = np.mean((noisy - clean) ** 2)
    for extra in ({}, {"albedo": albedo, "normal": normal}):
        out = get_transform("denoise")(TransformInputs(noisy, "left", 0, 0, **extra))
        assert np.mean((out - clean) ** 2) < 0.25 * before


def test_denoise_nonfinite_pixels_replaced_and_kept_nan():
    pytest.importorskip("pyoidn")
    _, noisy, _, _ = structured_scene()
    broken = noisy.copy()
    broken[10, 20, 1] = np.inf
    broken[30, 40, :] = np.nan
    out, n_bad = denoise_image(broken)
    assert n_bad == 4 and np.isfinite(out).all()
    zeroed = noisy.copy()
    zeroed[10, 20, 1] = 0
    zeroed[30, 40, :] = 0
    assert_array_equal(out, denoise_image(zeroed)[0])
    via_transform = get_transform("denoise")(TransformInputs(broken, "left", 0, 0))
    assert np.isnan(via_transform[10, 20, 1]) and np.isnan(via_transform[30, 40]).all()
    assert np.isfinite(via_transform).sum() == via_transform.size - 4


def test_a_repeated_denoise_is_the_first_ones_image_without_running_oidn(monkeypatch):
    pyoidn = pytest.importorskip("pyoidn")
    from stereovar.transforms import denoise

    _, noisy, albedo, normal = structured_scene(shape=(24, 40))
    monkeypatch.setattr(denoise, "_MEMO", type(denoise._MEMO)())
    first, _ = denoise_image(noisy, albedo=albedo, normal=normal)

    def no_oidn(*args, **kwargs):
        raise AssertionError("OIDN ran again for a call it has answered")

    with monkeypatch.context() as m:
        m.setattr(denoise, "_filter", no_oidn)
        again, _ = denoise_image(noisy.copy(), albedo=albedo, normal=normal)
        again[0, 0, 0] = -1.0  # the caller's copy, not the kept one
        assert_array_equal(denoise_image(noisy, albedo=albedo, normal=normal)[0], first)
    assert_array_equal(first, pyoidn.denoise(noisy, albedo, normal, hdr=True))
    changed = noisy.copy()
    changed[3, 5, 1] += 0.5
    other, _ = denoise_image(changed, albedo=albedo, normal=normal)  # a new image: OIDN runs
    assert_array_equal(other, pyoidn.denoise(changed, albedo, normal, hdr=True))
    colour_only, _ = denoise_image(noisy)  # other inputs, another network
    assert_array_equal(colour_only, pyoidn.denoise(noisy, hdr=True))
    assert len(denoise._MEMO) == 3
    monkeypatch.setattr(denoise, "MEMO_BYTES", 2 * first.nbytes)
    denoise_image(noisy, quality="balanced")
    assert sum(v.nbytes for v in denoise._MEMO.values()) <= 2 * first.nbytes


def test_denoise_normal_needs_albedo():
    pytest.importorskip("pyoidn")
    _, noisy, _, normal = structured_scene(shape=(16, 16))
    with pytest.raises(ValueError, match="normal pass only together with an albedo"):
        denoise_image(noisy, normal=normal)


def test_denoise_sensor_adds_camera_noise_to_denoised():
    pytest.importorskip("pyoidn")
    _, noisy, albedo, normal = structured_scene()
    x = TransformInputs(noisy, "left", 0, 5, albedo=albedo, normal=normal)
    denoised = get_transform("denoise")(x).astype(np.float64)
    frames = np.stack(
        [
            get_transform("denoise_sensor")(
                TransformInputs(noisy, "left", 0, s, albedo=albedo, normal=normal)
            )
            for s in range(8)
        ]
    ).astype(np.float64)
    target = A * np.maximum(denoised, 0) + B
    # standardized draws around the denoised image: E[z] = 0, E[z^2] = 1, and
    # Var[z^2] = m4 / s^4 - 1 with the Poisson-Gaussian m4 in electrons
    z = (frames - denoised) / np.sqrt(target)
    assert abs(z.mean()) < 4 / np.sqrt(z.size)
    lam, r2 = GAIN * np.maximum(denoised, 0), READ**2
    m4 = lam + 3 * lam**2 + 6 * lam * r2 + 3 * r2**2
    var_z2 = np.broadcast_to(m4 / (lam + r2) ** 2 - 1, z.shape)
    assert abs((z**2).mean() - 1) < 4 * np.sqrt(var_z2.mean() / z.size)
