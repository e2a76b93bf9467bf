"""The moments estimator: sample moments, their variance field, the integrator, the job."""

import numpy as np
import pytest

from stereovar.estimators.moments import (
    moment_variance_dataset,
    pixel_variance,
    pooled_sample_moments,
    sample_variance,
    view_fields,
)
from stereovar.estimators.seeds import variance_field
from stereovar.io.moments import moments_dataset
from stereovar.io.store import open_dataset, write_dataset
from stereovar.renderers.base import SampleMoments
from stereovar.rig import VIEWS

from .test_ground_truth import REPO

RIG = {"width": 48, "height": 27, "baseline_m": 0.026, "convention": "paper"}


def moments_of(samples):
    """Brute-force moments of samples (n, H, W, C): mean, mean of squares, count."""
    s = np.asarray(samples, dtype=np.float64)
    return s.mean(axis=0), (s * s).mean(axis=0), np.full(s.shape[1:3], s.shape[0])


def test_sample_variance_is_the_unbiased_variance_of_the_samples():
    rng = np.random.default_rng(1)
    samples = rng.lognormal(0.0, 1.5, size=(37, 5, 6, 3))
    m1, m2, n = moments_of(samples)
    np.testing.assert_allclose(
        sample_variance(m1, m2, n), samples.var(axis=0, ddof=1), rtol=1e-10, atol=1e-12
    )
    np.testing.assert_allclose(
        pixel_variance(m1, m2, n, 37), samples.var(axis=0, ddof=1).mean(axis=-1) / 37, rtol=1e-10
    )


def test_sample_variance_is_nan_below_two_samples_and_never_negative():
    m1 = np.array([[[2.0, 1.0, 0.5]], [[3.0, 3.0, 3.0]]])
    m2 = m1 * m1 * (1 - 1e-7)  # float32 rounding can put m2 just below m1^2
    out = sample_variance(m1, m2, np.array([[1], [8]]))
    assert np.isnan(out[0]).all()
    assert (out[1] == 0.0).all()


def test_pooled_moments_equal_the_moments_of_the_union():
    rng = np.random.default_rng(2)
    a = rng.gamma(0.5, 2.0, size=(5, 4, 3, 3))
    b = rng.gamma(0.5, 2.0, size=(9, 4, 3, 3))
    halves = [moments_of(a), moments_of(b)]
    m1, m2, n = pooled_sample_moments(
        np.stack([h[0] for h in halves]),
        np.stack([h[1] for h in halves]),
        np.stack([h[2] for h in halves]),
    )
    union = moments_of(np.concatenate([a, b]))
    np.testing.assert_allclose(m1, union[0], rtol=1e-12)
    np.testing.assert_allclose(m2, union[1], rtol=1e-12)
    assert (n == 14).all()


def test_moment_field_and_eq1_estimate_the_pixel_variance_in_expectation():
    """Samples of known variance: the moment field of one render at s samples averages
    Var/s; Eq. 1 over N renders of s samples averages (N-1)/N Var/s."""
    rng = np.random.default_rng(3)
    s, n, pixels = 16, 6, (40, 50)
    scale = rng.uniform(0.5, 2.0, size=(*pixels, 1))  # exponential: Var = scale^2
    truth = (scale[..., 0] ** 2) / s
    one = rng.exponential(scale, size=(s, *pixels, 3))
    field = pixel_variance(*moments_of(one), s)
    renders = rng.exponential(scale, size=(n, s, *pixels, 3)).mean(axis=1)
    _, eq1 = variance_field(renders)
    ratio_m = field.sum() / truth.sum()
    ratio_s = eq1.sum() / (truth.sum() * (n - 1) / n)
    # relative standard errors: about sqrt(Kurt / s / pixels) and sqrt(2 / N / pixels)
    assert abs(ratio_m - 1) < 4 * np.sqrt(9 / s / (3 * field.size))
    assert abs(ratio_s - 1) < 4 * np.sqrt(3 / n / (3 * field.size))


def store(tmp_path, name, halves, spp):
    ds = moments_dataset(
        [SampleMoments(*h) for h in halves],
        view=name,
        sampler_seeds=[11, 12],
        half_spp=[spp // 2, spp - spp // 2],
        attrs={"spp": spp, "scene": "synthetic"},
    )
    return write_dataset(ds, tmp_path / f"{name}.zarr")


def test_view_fields_pool_halves_and_exclude_pixels_with_too_few_samples(tmp_path):
    rng = np.random.default_rng(4)
    spp = 8
    samples = rng.lognormal(0.0, 1.0, size=(2, spp // 2, 3, 4, 3)).astype(np.float32)
    halves = []
    counts = np.full((2, 3, 4), spp // 2)
    counts[1, 0, 0] = 1  # one half with a single finite sample: the pixel is excluded
    counts[0, 2, 3] = 3  # one non-finite sample: pooled over the finite ones
    for h in range(2):
        m1, m2, _ = moments_of(samples[h])
        halves.append((m1.astype(np.float32), m2.astype(np.float32), counts[h]))
    path = store(tmp_path, "left", halves, spp)
    ds = view_fields(open_dataset(path))
    finite = ds["finite"].values
    assert not finite[0, 0] and finite.sum() == 11
    assert ds["n_nonfinite"].values[0, 0] == 3 and ds["n_nonfinite"].values[2, 3] == 1
    union = moments_of(samples.reshape(spp, 3, 4, 3))
    expected = union[1] - union[0] ** 2
    expected = expected * spp / (spp - 1)
    np.testing.assert_allclose(ds["variance"].values[1, 1], expected[1, 1].mean() / spp, rtol=1e-5)
    halves_v = ds["half_variance"].values
    np.testing.assert_allclose(
        halves_v[0, 1, 1], samples[0][:, 1, 1].var(axis=0, ddof=1).mean() / spp, rtol=1e-5
    )
    assert ds.attrs["n_seeds"] == 2 and ds.attrs["n_draws"] == spp
    assert (ds["variance"].values[~finite] == 0).all()
    # the field at another SPP is the same moments divided by that SPP
    twice = view_fields(open_dataset(path), spp=2 * spp)
    np.testing.assert_allclose(twice["variance"].values, ds["variance"].values / 2, rtol=1e-12)


def test_moment_variance_dataset_is_the_variance_contract(tmp_path):
    rng = np.random.default_rng(5)
    paths = {}
    for view in VIEWS:
        halves = []
        for _ in range(2):
            m1, m2, n = moments_of(rng.lognormal(size=(4, 5, 6, 3)))
            halves.append((m1.astype(np.float32), m2.astype(np.float32), n))
        paths[view] = [store(tmp_path, view, halves, 8)]
    ds = moment_variance_dataset(paths["left"], paths["right"])
    assert ds["variance"].dims == ("view", "y", "x")
    assert ds["mean"].dims == ("view", "y", "x", "channel")
    assert ds["half_variance"].sizes["half"] == 2
    assert list(ds["view"].values) == list(VIEWS)
    with pytest.raises(ValueError, match="one moment store per view"):
        moment_variance_dataset(paths["left"] * 2, paths["right"])


def test_sample_moments_stack_round_trips():
    rng = np.random.default_rng(6)
    m = SampleMoments(
        rng.random((3, 4, 3)).astype(np.float32),
        rng.random((3, 4, 3)).astype(np.float32),
        rng.integers(0, 9, (3, 4)).astype(np.int32),
    )
    back = SampleMoments.from_stack(m.stack())
    for a, b in zip(m, back, strict=True):
        np.testing.assert_array_equal(a, b)


def render_pair(mi, spp, seed):
    """The left view of scene_001 rendered by path and by the moment integrator."""
    from stereovar.renderers.mitsuba.moments import film_moments, moment_integrator_dict, register
    from stereovar.renderers.mitsuba.render import render_view
    from stereovar.renderers.mitsuba.scene import load_scene
    from stereovar.renderers.mitsuba.sensor import integrator_dict
    from stereovar.rig import make_rig
    from stereovar.scenes.spec import load_scene_spec

    scene, cam = load_scene(mi, load_scene_spec(REPO / "scenes/scene_001.yaml"))
    rig = make_rig(cam.to_world, cam.fov_deg, **RIG)
    register(mi)
    path = render_view(mi, scene, rig, "left", spp=spp, seed=seed)
    film = render_view(
        mi,
        scene,
        rig,
        "left",
        spp=spp,
        seed=seed,
        channels=None,
        integrator=moment_integrator_dict(integrator_dict()),
    )
    return path, film, film_moments(film, spp)


def test_moment_integrator_renders_the_path_image_and_its_sample_moments(mi):
    path, film, moments = render_pair(mi, 8, 7)
    # the nested integrator sees the same random numbers: the same image
    np.testing.assert_allclose(film[..., :3], path, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(moments.mean, path, rtol=1e-5, atol=1e-6)
    assert (moments.count == 8).all()
    assert (moments.mean_sq >= moments.mean**2 * (1 - 1e-5) - 1e-7).all()
    assert (sample_variance(moments.mean, moments.mean_sq, moments.count) > 0).any()


def test_one_sample_has_a_second_moment_equal_to_its_square(mi):
    _, _, moments = render_pair(mi, 1, 3)
    np.testing.assert_allclose(moments.mean_sq, moments.mean**2, rtol=1e-5, atol=1e-7)
    assert np.isnan(sample_variance(moments.mean, moments.mean_sq, moments.count)).all()


def test_moments_job_writes_both_halves_with_their_own_seeds(mi, tmp_path):
    from stereovar.jobs.render import moments_job
    from stereovar.seeding import render_seed

    out = tmp_path / "left.zarr"
    moments_job(REPO / "scenes/scene_001.yaml", out, view="left", spp=8, cache=None, **RIG)
    ds = open_dataset(out)
    assert ds["half_spp"].values.tolist() == [4, 4]
    seeds = ds["sampler_seed"].values.tolist()
    assert seeds == [render_seed("scene_001", "left", 8, f"moments{h}") for h in range(2)]
    assert seeds[0] != seeds[1] and render_seed("scene_001", "left", 8, 0) not in seeds
    assert (ds["n_samples"].values == 4).all()
    assert not np.array_equal(ds["sample_mean"].values[0], ds["sample_mean"].values[1])
    assert ds.attrs["estimator"] == "moments" and ds.attrs["spp"] == 8


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"sampler": "stratified"}, "render.sampler.*independent"),
        ({"rfilter": "gaussian"}, "render.rfilter.*box"),
    ],
)
def test_moments_job_refuses_samplers_and_filters_that_break_var_over_s(tmp_path, options, message):
    from stereovar.errors import ConfigError
    from stereovar.jobs.render import moments_job

    with pytest.raises(ConfigError, match=message):
        moments_job(
            REPO / "scenes/scene_001.yaml",
            tmp_path / "x.zarr",
            view="left",
            spp=8,
            **RIG,
            **options,
        )
    assert not (tmp_path / "x.zarr").exists()


def test_half_spp_splits_evenly_and_needs_two_samples_per_half():
    from stereovar.errors import StereovarError
    from stereovar.jobs.render import half_spp

    assert half_spp(8) == [4, 4] and half_spp(9) == [5, 4]
    with pytest.raises(StereovarError, match="spp >= 4"):
        half_spp(3)
