"""The cost-volume probe network: size, shapes, soft-argmin, the sign mirror, training and
its file."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from stereovar.probe.costvolume import (  # noqa: E402
    CostVolumeNet,
    CostVolumeSettings,
    cost_volume,
    draw_crops,
    parameter_count,
    predict_costvolume,
    soft_argmin,
    train_costvolume,
)
from stereovar.probe.training import TrainingFrame, load_matcher, save_matcher  # noqa: E402


@pytest.fixture(autouse=True)
def _one_thread():
    """One Torch thread, as the probe's jobs run (more threads spin on a busy machine)."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


FAST = CostVolumeSettings(crops=2, crop_rows=24, crop_cols=48, learning_rate=3e-3)


def _texture(rng, rows, cols):
    """Standardised random texture, blurred a little (a 3-tap box in x)."""
    t = rng.standard_normal((rows, cols + 2))
    t = (t[:, :-2] + t[:, 1:-1] + t[:, 2:]) / 3
    return ((t - t.mean()) / t.std()).astype(np.float32)


def _pair(rng, *, d, sign, rows=32, cols=64, noise=0.0):
    """A random-texture frame of constant disparity ``d`` (int): the right pixel at
    ``x + sign * d`` shows the left pixel ``x``; NaN where that pixel leaves the image."""
    t = _texture(rng, rows, cols + d)
    if sign < 0:
        left, right = t[:, :cols], t[:, d : d + cols]
    else:
        left, right = t[:, d : d + cols], t[:, :cols]
    left = left + noise * rng.standard_normal(left.shape).astype(np.float32)
    right = right + noise * rng.standard_normal(right.shape).astype(np.float32)
    disparity = np.full((rows, cols), float(d))
    x_right = np.arange(cols) + sign * d
    disparity[:, (x_right < 0) | (x_right >= cols)] = np.nan
    return TrainingFrame(left, right, disparity, sign)


def _epe(net, frames, max_disparity):
    errors = []
    for f in frames:
        (d_hat,) = predict_costvolume(
            net, [(f.left, f.right)], sign=f.sign, max_disparity=max_disparity
        )
        ok = np.isfinite(f.disparity)
        errors.append(np.abs(d_hat[ok] - f.disparity[ok]))
    return float(np.mean(np.concatenate(errors)))


def test_parameters_within_budget_and_config_rebuilds():
    net = CostVolumeNet()
    assert 0 < parameter_count(net) <= 500_000
    twin = CostVolumeNet(**net.config())
    assert twin.config() == net.config()
    assert parameter_count(twin) == parameter_count(net)
    assert parameter_count(CostVolumeNet(features=32, volume_channels=16)) <= 500_000


@pytest.mark.parametrize("scale", [2, 4])
def test_shapes_at_any_size(scale):
    net = CostVolumeNet(scale=scale, max_disparity=9).eval()
    x = torch.randn(3, 1, 21, 37)
    with torch.no_grad():
        up, refined = net.stages(x, x)
    assert tuple(up.shape) == tuple(refined.shape) == (3, 21, 37)
    assert net.levels() == -(-9 // scale) + 1
    rng = np.random.default_rng(0)
    pairs = [
        (rng.standard_normal(s).astype(np.float32),) * 2 for s in ((20, 30), (17, 40), (20, 30))
    ]
    out = predict_costvolume(net, pairs, sign=-1, max_disparity=9, batch=1)
    assert [o.shape for o in out] == [(20, 30), (17, 40), (20, 30)]
    assert all(o.dtype == np.float64 and np.isfinite(o).all() and (o >= 0).all() for o in out)


def test_soft_argmin_of_a_known_cost():
    # one level far below the rest: that level exactly
    cost = torch.full((2, 7, 3, 4), 40.0)
    cost[0, 5] = 0.0
    cost[1, 2] = 0.0
    got = soft_argmin(cost)
    assert torch.allclose(got[0], torch.full((3, 4), 5.0), atol=1e-6)
    assert torch.allclose(got[1], torch.full((3, 4), 2.0), atol=1e-6)
    # two equal minima at k and k + 1 (the others far): their midpoint
    cost = torch.full((1, 6, 1, 1), 40.0)
    cost[0, 3] = cost[0, 4] = 1.0
    assert float(soft_argmin(cost)) == pytest.approx(3.5, abs=1e-6)
    # a general cost against the weighted mean written out
    c = np.array([0.3, -1.0, 2.0, 0.5])
    w = np.exp(-c) / np.exp(-c).sum()
    expected = float((w * np.arange(4)).sum())
    got = float(soft_argmin(torch.tensor(c, dtype=torch.float64)[None, :, None, None]))
    assert got == pytest.approx(expected, rel=1e-12)


def test_cost_volume_is_zero_at_the_shift_of_the_views():
    rng = np.random.default_rng(1)
    f = torch.from_numpy(rng.standard_normal((1, 3, 5, 20)))
    k = 4  # right features are the left ones moved k columns left: right(x - k) = left(x)
    right = torch.zeros_like(f)
    right[..., : 20 - k] = f[..., k:]
    vol = cost_volume(f, right, 7)
    norm = vol.abs().sum(dim=(1, 3))[0]  # (levels, w)
    assert float(norm[k, k:].max()) == 0.0
    assert float(norm[np.arange(7) != k][:, 7:].min()) > 0


def test_sign_plus_one_is_the_mirror_of_the_conventional_sign():
    torch.manual_seed(3)
    net = CostVolumeNet(max_disparity=8).eval()
    rng = np.random.default_rng(2)
    left, right = _texture(rng, 20, 40), _texture(rng, 20, 40)
    plus = predict_costvolume(net, [(left, right)], sign=1, max_disparity=8)[0]
    mirrored = predict_costvolume(net, [(left[:, ::-1], right[:, ::-1])], sign=-1, max_disparity=8)[
        0
    ][:, ::-1]
    np.testing.assert_allclose(plus, mirrored, rtol=0, atol=1e-5)
    minus = predict_costvolume(net, [(left, right)], sign=-1, max_disparity=8)[0]
    assert np.abs(plus - minus).max() > 1e-3  # the mirror is not a no-op


def test_crops_of_a_plus_one_frame_are_in_the_conventional_sign():
    rng = np.random.default_rng(4)
    frame = _pair(rng, d=3, sign=1, rows=30, cols=60)
    settings = CostVolumeSettings(crops=3, crop_rows=10, crop_cols=20)
    left, right, d, keep = draw_crops(
        [frame], settings, np.random.default_rng(0), np.random.default_rng(1), max_disparity=6
    )
    assert bool(keep.any())
    assert torch.all(d[keep] == 3)
    cols = torch.arange(20)
    assert not bool(keep[:, :, cols < 3].any())  # x - d leaves the crop: not supervised
    # the right crop at x - d shows the left crop at x
    np.testing.assert_array_equal(right[:, 0, :, :-3].numpy(), left[:, 0, :, 3:].numpy())


def test_a_few_dozen_steps_reduce_the_epe():
    rng = np.random.default_rng(5)
    frames = [_pair(rng, d=d, sign=s, noise=0.05) for d, s in ((3, -1), (6, 1), (4, -1))]
    held = [_pair(rng, d=d, sign=-1, noise=0.05) for d in (3, 6)]
    settings = CostVolumeSettings(**{**FAST.__dict__, "steps": 40, "max_disparity": 8})
    net, history = train_costvolume(frames, settings, seed=0)
    torch.manual_seed(0)
    baseline = _epe(CostVolumeNet(max_disparity=8).eval(), held, 8)
    trained = _epe(net, held, 8)
    assert history["steps"] == 40 and len(history["loss"]) == 40
    assert trained < 0.5 * baseline, (baseline, trained)


def test_plateau_stops_keeps_the_best_and_uses_the_twin_redraw():
    rng = np.random.default_rng(6)
    base = _pair(rng, d=2, sign=-1, rows=24, cols=48)
    draws = []

    def redraw(r):
        draws.append(1)
        return base.right + 0.1 * r.standard_normal(base.right.shape).astype(np.float32)

    twin = TrainingFrame(base.left, base.right, base.disparity, -1, redraw=redraw)
    settings = CostVolumeSettings(
        **{
            **FAST.__dict__,
            "steps": 500,
            "check_every": 2,
            "patience": 2,
            "min_steps": 4,
            "min_delta": 0.5,
            "max_disparity": 4,
        }
    )
    net, history = train_costvolume([twin], settings, seed=1, validation=[base])
    assert 4 <= history["steps"] < 500  # no gain of 0.5 is possible after the first check
    assert history["best_step"] == history["validation"][0][0] == 2
    assert len(draws) == settings.crops * history["steps"]
    assert set(history) >= {
        "loss",
        "triplets",
        "seconds",
        "step_seconds",
        "steps",
        "best_step",
        "validation",
    }


def test_save_load_round_trip(tmp_path):
    torch.manual_seed(7)
    net = CostVolumeNet(features=8, volume_channels=4, refine_channels=4, max_disparity=6)
    with torch.no_grad():
        for p in net.parameters():
            p.add_(0.01)
    path = tmp_path / "cv.pt"
    save_matcher(path, net, settings=FAST, seed=3, meta={"condition": "x"})
    loaded, record = load_matcher(path)
    assert isinstance(loaded, CostVolumeNet)
    assert record["architecture"]["kind"] == "costvolume"
    assert loaded.config() == net.config()
    rng = np.random.default_rng(8)
    pair = (_texture(rng, 16, 30), _texture(rng, 16, 30))
    a = predict_costvolume(net, [pair], sign=1, max_disparity=6)[0]
    b = predict_costvolume(loaded, [pair], sign=1, max_disparity=6)[0]
    np.testing.assert_array_equal(a, b)
