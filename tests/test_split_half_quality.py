"""Image quality without a converged render: the split-half grading against data whose error
is known, for the renders, a per-seed transform and the two transforms that read the seed
mean; and the mitigation scene job grading `sensor_only` on the stub plane."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import uniform_filter

from stereovar.jobs.transform import seed_moments
from stereovar.rig import VIEWS
from stereovar.statistics.utility import image_quality, split_half_quality
from stereovar.transforms.sensor import camera_coefficients, camera_noise, equalise_residual

from .test_architecture import plane_run, stubs  # noqa: F401 (fixtures)

N, SHAPE_K = 8, 20.0  # seeds; gamma shape of the renders' noise (variance mu^2 / 20)
A_CAM, B_CAM = camera_coefficients()  # the transforms' default camera: variance a mu + b


def blur(image):
    return uniform_filter(image, size=(3, 3, 1), mode="nearest")


def renders(size: int, seed: int):
    """Clean image mu in [0.2, 0.8] and N renders mu * Gamma(20, 1/20): right-skewed,
    non-negative, variance mu^2 / 20. At N = 8 the Monte Carlo variance left in the seed
    mean, sigma^2 / N (1.8e-3 on average), is 3.5 times the camera's a mu + b (5e-4)."""
    mu = np.random.default_rng(0).uniform(0.2, 0.8, (size, size, 3))
    rng = np.random.default_rng(seed)
    return mu, mu * rng.gamma(SHAPE_K, 1 / SHAPE_K, (N, size, size, 3))


def images_of(kind, raw, seeds):
    """The images of ``kind`` made from the renders ``raw`` of seed indices ``seeds``."""
    if kind == "none":
        return raw
    if kind == "blur":  # a transform of each render alone
        return np.stack([blur(r) for r in raw])
    mean, var = seed_moments(raw)
    if kind == "sensor_only":
        return np.stack([camera_noise(mean, rng_seed=int(s)) for s in seeds])
    return np.stack([equalise_residual(r, mean, var)[0] for r in raw])


def true_mse(kind, mu):
    """Mean over seeds, pixels and channels of E(Y - mu)^2 for the shipped images."""
    var = mu**2 / SHAPE_K
    camera = A_CAM * mu + B_CAM
    return {
        "none": var,
        "blur": (blur(mu) - mu) ** 2 + blur(var) / 9,  # bias^2 + sum of squared weights x var
        "sensor_only": var / N + camera,  # the seed mean's noise, then the camera's
        "equalise": var / N + (N - 1) / N * camera,  # N-seed variance exactly the camera's
    }[kind].mean()


# size: the Monte Carlo sd of one estimate over 20 datasets is 0.75% of the truth for
# sensor_only and equalise at 256 x 256, 0.34% for none and 0.20% for blur at 128 x 128, so
# 5% is at least 6.5 sd
@pytest.mark.parametrize(
    ("kind", "size"), [("none", 128), ("blur", 128), ("sensor_only", 256), ("equalise", 256)]
)
def test_split_half_mse_is_within_5_percent_of_the_truth(kind, size):
    mu, raw = renders(size, seed=1)
    seeds = np.arange(N)
    first, second = seeds[: N // 2], seeds[N // 2 :]
    shipped = images_of(kind, raw, seeds)
    made = tuple(images_of(kind, raw[h], h) for h in (first, second))
    got = split_half_quality(shipped, made, (raw[first], raw[second]))
    truth = true_mse(kind, mu)
    assert got["mse"] == pytest.approx(truth, rel=0.05)
    assert got["psnr"] == pytest.approx(-10 * math.log10(got["mse"]), rel=1e-12)
    assert got["reason"] == "" and got["n_pixels"] == size * size and got["n_images"] == N
    if kind in ("sensor_only", "equalise"):
        # the shipped images read all N renders: graded against the other half's mean they
        # share its noise; sensor_only reads 2 sigma^2 / N low (as against the mean of the
        # other seeds), equalise 2 (1 - s) sigma^2 / N with s its rescaling factor
        naive = image_quality(
            shipped[first], raw[second].mean(0), reference_var=raw.var(0, ddof=1) / (N // 2)
        )
        if kind == "sensor_only":
            bias = 2 * (mu**2 / SHAPE_K).mean() / N
            assert naive["mse"] == pytest.approx(truth - bias, rel=0.1)
        assert naive["mse"] < 0.5 * truth


def test_split_half_pieces_against_a_loop():
    """Each term of the estimate by explicit loops over one pixel's seeds, halves 3 and 4."""
    rng = np.random.default_rng(2)
    images, raw = rng.normal(1.0, 0.2, (2, 7, 2, 3, 3))
    made = (rng.normal(1.0, 0.2, (3, 2, 3, 3)), rng.normal(1.0, 0.2, (4, 2, 3, 3)))
    got = split_half_quality(images, made, (raw[:3], raw[3:]))
    total, noise = 0.0, 0.0
    for y in range(2):
        for x in range(3):
            for c in range(3):
                ys = [float(v) for v in images[:, y, x, c]]
                rs = [float(v) for v in raw[:, y, x, c]]
                ya = sum(float(v) for v in made[0][:, y, x, c]) / 3
                yb = sum(float(v) for v in made[1][:, y, x, c]) / 4
                ra, rb = sum(rs[:3]) / 3, sum(rs[3:]) / 4
                ybar, rbar = sum(ys) / 7, sum(rs) / 7
                var = sum((r - rbar) ** 2 for r in rs) / 6
                within = sum((v - ybar) ** 2 for v in ys) / 7
                kappa = 0.5 - (1 / 7) / (1 / 3 + 1 / 4)
                d = 0.5 * ((ya - rb) ** 2 - var / 4 + (yb - ra) ** 2 - var / 3)
                total += within + d - kappa * (ya - yb) ** 2
                noise += 0.5 * var * (1 / 3 + 1 / 4)
    assert got["mse"] == pytest.approx(total / 18, rel=1e-10)
    assert got["reference_noise"] == pytest.approx(noise / 18, rel=1e-10)
    assert got["mse_raw"] == pytest.approx(got["mse"] + got["reference_noise"], rel=1e-10)
    assert got["bias"] == pytest.approx(float((images.mean(0) - raw.mean(0)).mean()), rel=1e-10)


def test_the_scene_job_grades_sensor_only_by_split_half(plane_run, tmp_path):  # noqa: F811
    """`sensor_only` on the stub plane (clean value 0.5, Gaussian noise of known sd per pixel,
    N = 6, no moments render): the scene job's MSE, both views pooled, within 10% of the truth
    sigma^2 / N + a mu + b (one estimate's Monte Carlo sd is 1.5% of it, over 40 simulated
    datasets); the mean of the other seeds as the reference read 2 sigma^2 / N (57% of the
    truth) low. The rows hold every quantity of SCENE_QUANTITIES."""
    from stereovar.jobs.mitigation_scene import SCENE_QUANTITIES, mitigation_scene_job
    from stereovar.jobs.transform import transform_job

    from .test_architecture import RIG, PlaneRenderer, amplitude

    gt, stores = plane_run
    out = {v: [] for v in VIEWS}
    for view in VIEWS:
        for batch in ([0, 1, 2], [3, 4, 5]):
            path = tmp_path / f"sensor_{view}_{batch[0]}.zarr"
            transform_job(stores[view], path, transform="sensor_only", batch=batch, view=view)
            out[view].append(path)
    rows = mitigation_scene_job(
        out["left"], out["right"], gt, {v: stores[v] for v in VIEWS}, tmp_path / "rows.csv"
    )
    by = {(r["region"], r["quantity"]): r for r in rows}
    hits = PlaneRenderer().prepare({"name": "x"}, rig=RIG).hits
    sigma2 = [(amplitude(hits(v)) ** 2 / 4).mean() for v in VIEWS]  # stub noise at spp 4
    truth = float(np.mean(sigma2)) / 6 + A_CAM * 0.5 + B_CAM
    assert by[("all", "mse")]["value"] == pytest.approx(truth, rel=0.10)
    assert by[("all", "psnr")]["reason"] == ""
    assert {r["quantity"] for r in rows if r["region"] == "all"} == set(SCENE_QUANTITIES)
    # the plane's disparity is 4 px: its pixels are in the [2, 8) band only
    assert (
        by[("all", "residual_rho_gt_d2-8")]["n_pixels"]
        == by[("all", "residual_rho_gt")]["n_pixels"]
    )
    assert by[("all", "residual_rho_gt_d0-2")]["reason"].startswith("fewer than")
