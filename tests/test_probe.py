"""Tests of the learned probe (:mod:`stereovar.probe`): the MC-CNN matcher and its training,
the counterfactual test inputs, per-tile scoring, the two-level bootstrap table and the
experiment helpers.

Every expected value is computed independently of the code under test: brute-force loops over
pixels, disparities, tiles and seeds, analytic cases (zero-width intervals, paired drops) or
synthetic data with a known answer (a right view that is the left view shifted by a known
disparity; variance fields that line up at a known disparity). Training runs are short (tens
of steps on 48x96 images), so the whole file takes well under a minute.
"""

from __future__ import annotations

import re
from dataclasses import asdict

import numpy as np
import pandas as pd
import pytest
import torch  # the probe extra, which the set-up installs
from scipy.ndimage import gaussian_filter
from torch.nn import functional as F

from stereovar.io.transfer import linear_to_srgb

# imported as a module: pytest would collect test_scene and TestSettings by their names
from stereovar.probe import experiment
from stereovar.probe.conditions import CONTROL
from stereovar.probe.experiment import fold_scenes
from stereovar.probe.inputs import (
    TEST_INPUTS,
    counterfactual_pair,
    network_input,
    shift_columns,
)
from stereovar.probe.network import (
    MatchingNet,
    border,
    predict_matcher,
    score_volume,
    wta_disparity,
)
from stereovar.probe.scoring import SUMS, tile_sums
from stereovar.probe.training import (
    TrainingFrame,
    TrainSettings,
    load_matcher,
    save_matcher,
    train_matcher,
)
from stereovar.statistics.correlation import pearson_over_mask
from stereovar.statistics.warp import warp_right_to_left

H, W = 48, 96  # the synthetic pairs of the training tests
B = 4  # the network's border: four unpadded 3x3 convolutions
NOISE = 0.15  # std of the per-pixel Gaussian noise of the noisy pairs (texture std 0.35)


# --------------------------------------------------------------------------------------------
# synthetic data
# --------------------------------------------------------------------------------------------


def texture(rng, height, width):
    """Gaussian-filtered white noise as linear radiance in [0.02, 0.98]."""
    t = gaussian_filter(rng.normal(size=(height, width)), 1.0)
    return np.clip(0.5 + 0.35 * t / t.std(), 0.02, 0.98)


def shifted_pair(rng, d, sign, *, noise=0.0, height=H, width=W, margin=12):
    """A left view and a right view with ``right(x + sign * d) = left(x)``, each plus its own
    Gaussian noise; the disparity is ``d`` where ``x + sign * d`` lies in the image, NaN
    elsewhere."""
    t = texture(rng, height, width + margin)
    x0 = margin if sign > 0 else 0
    left = t[:, x0 : x0 + width]
    right = t[:, x0 - sign * d : x0 - sign * d + width]
    xs = np.arange(width) + sign * d
    inside = (xs >= 0) & (xs <= width - 1)
    # the construction itself: every left column reappears at x + s d in the right view
    np.testing.assert_array_equal(right[:, xs[inside]], left[:, inside])
    disparity = np.where(inside, float(d), np.nan)[None, :].repeat(height, axis=0)
    left = left + noise * rng.normal(size=left.shape)
    right = right + noise * rng.normal(size=right.shape)
    return left, right, disparity


def sad_wta(left, right, *, sign, max_disparity, radius):
    """Brute-force SAD block matching: for every pixel and disparity the sum of
    ``|L - R(x + s d)|`` over a (2r+1)^2 window that lies in both images, the smallest sum
    wins; NaN where no disparity has a window."""
    height, width = left.shape
    r = radius
    out = np.full((height, width), np.nan)
    for y in range(r, height - r):
        for x in range(r, width - r):
            best, best_d = np.inf, np.nan
            for d in range(max_disparity + 1):
                xr = x + sign * d
                if not r <= xr <= width - 1 - r:
                    continue
                cost = np.abs(
                    left[y - r : y + r + 1, x - r : x + r + 1]
                    - right[y - r : y + r + 1, xr - r : xr + r + 1]
                ).sum()
                if cost < best:
                    best, best_d = cost, d
            out[y, x] = best_d
    return out


def reachable(disparity, sign):
    """Left pixels whose own 9x9 patch and whose true right pixel's patch both lie in the
    image: the pixels a matcher with a 4 px border can get right."""
    height, width = disparity.shape
    out = np.zeros((height, width), dtype=bool)
    for y in range(B, height - B):
        for x in range(B, width - B):
            d = disparity[y, x]
            if np.isfinite(d) and B <= x + sign * d <= width - 1 - B:
                out[y, x] = True
    return out


def frames_of(pairs):
    return [
        TrainingFrame(network_input(left), network_input(right), d.astype(np.float32), sign)
        for left, right, d, sign in pairs
    ]


def seeded_net(seed):
    torch.manual_seed(seed)
    return MatchingNet()


SETTINGS_SHORT = dict(steps=80, crops=2, crop_rows=12, crop_cols=40)


@pytest.fixture(scope="module")
def trained():
    """One matcher trained briefly on noisy shifts of both signs (d = 3, 5, 7): the net,
    its history and its settings."""
    rng = np.random.default_rng(0)
    pairs = []
    for sign in (1, -1):
        for d in (3, 5, 7):
            left, right, disp = shifted_pair(rng, d, sign, noise=NOISE)
            pairs.append((left, right, disp, sign))
    settings = TrainSettings(**SETTINGS_SHORT)
    net, history = train_matcher(frames_of(pairs), settings, seed=1)
    return net, history, settings


# --------------------------------------------------------------------------------------------
# 1. the trained matcher on a known shift
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("sign", [1, -1])
def test_trained_matcher_finds_a_known_shift_and_beats_sad(trained, sign):
    net, history, _ = trained
    d = 4  # not a training disparity, on a texture the net never saw
    left, right, disp = shifted_pair(np.random.default_rng(99), d, sign, noise=NOISE)
    xl, xr = network_input(left), network_input(right)
    ok = reachable(disp, sign)
    assert ok.sum() > 0.7 * ok.size

    d_net = wta_disparity(net, xl, xr, sign=sign, max_disparity=10)
    d_untrained = wta_disparity(seeded_net(1), xl, xr, sign=sign, max_disparity=10)
    d_sad = sad_wta(
        xl.astype(np.float64), xr.astype(np.float64), sign=sign, max_disparity=10, radius=2
    )
    acc_net = np.mean(np.abs(d_net[ok] - disp[ok]) < 1)
    acc_untrained = np.mean(np.abs(d_untrained[ok] - disp[ok]) < 1)
    acc_sad = np.mean(np.abs(d_sad[ok] - disp[ok]) < 1)
    assert acc_net > acc_sad + 0.05, (acc_net, acc_sad)
    assert acc_net > acc_untrained + 0.05, (acc_net, acc_untrained)
    assert np.mean(history["loss"][:10]) > np.mean(history["loss"][-10:])
    assert all(t > 0 for t in history["triplets"])

    # an easy noiseless shift: >= 90 % over every scored pixel with a prediction (the few
    # whose right pixel lies in the right view's border cannot be matched)
    left, right, disp = shifted_pair(np.random.default_rng(98), d, sign)
    d_net = wta_disparity(
        net, network_input(left), network_input(right), sign=sign, max_disparity=10
    )
    scored = np.isfinite(disp) & np.isfinite(d_net)
    assert np.mean(np.abs(d_net[scored] - disp[scored]) < 1) >= 0.9
    assert np.mean(d_net[ok] == d) >= 0.98


def test_training_rejects_bad_settings_and_frames():
    with pytest.raises(ValueError, match="optimiser"):
        TrainSettings(optimiser="rmsprop")
    with pytest.raises(ValueError, match="pos < neg_low < neg_high"):
        TrainSettings(pos=2.0, neg_low=1.5)
    with pytest.raises(ValueError, match="steps"):
        TrainSettings(steps=0)
    with pytest.raises(ValueError, match="sign"):
        TrainingFrame(np.zeros((4, 4)), np.zeros((4, 4)), np.zeros((4, 4)), 0)
    with pytest.raises(ValueError, match="three"):
        TrainingFrame(np.zeros((4, 4)), np.zeros((4, 5)), np.zeros((4, 4)), 1)
    with pytest.raises(ValueError, match="no training frame"):
        train_matcher([], TrainSettings(steps=1), seed=0)
    left, right, disp = shifted_pair(np.random.default_rng(0), 3, 1, height=16, width=40)
    with pytest.raises(ValueError, match="too small"):
        train_matcher(frames_of([(left, right, disp, 1)]), TrainSettings(steps=1), seed=0)


# --------------------------------------------------------------------------------------------
# 2. score volume and winner-take-all against loops
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("max_disparity", [4, 13])
def test_score_volume_matches_brute_force(sign, max_disparity):
    gen = torch.Generator().manual_seed(3 + sign)
    fl = F.normalize(torch.randn(8, 5, 11, generator=gen), dim=0)
    fr = F.normalize(torch.randn(8, 5, 11, generator=gen), dim=0)
    a, b = fl.numpy().astype(np.float64), fr.numpy().astype(np.float64)
    _, h, w = a.shape
    expected = np.full((max_disparity + 1, h, w), -np.inf)
    for d in range(max_disparity + 1):
        for y in range(h):
            for x in range(w):
                xr = x + sign * d
                if 0 <= xr <= w - 1:
                    expected[d, y, x] = sum(a[c, y, x] * b[c, y, xr] for c in range(8))
    volume = score_volume(fl, fr, sign=sign, max_disparity=max_disparity)
    assert tuple(volume.shape) == expected.shape
    np.testing.assert_allclose(volume.numpy(), expected, rtol=0, atol=1e-6)
    # unit features: a pixel matched with itself scores 1
    own = score_volume(fl, fl, sign=sign, max_disparity=max_disparity)
    np.testing.assert_allclose(own[0].numpy(), 1.0, atol=1e-6)


def test_score_volume_rejects_bad_arguments():
    f = torch.zeros(4, 3, 6)
    with pytest.raises(ValueError, match="sign"):
        score_volume(f, f, sign=0, max_disparity=2)
    with pytest.raises(ValueError, match="differ"):
        score_volume(f, torch.zeros(4, 3, 5), sign=1, max_disparity=2)


@pytest.mark.parametrize("sign", [1, -1])
def test_wta_disparity_matches_patchwise_brute_force(sign):
    """The features of every pixel from its own 9x9 patch (one forward pass each), then the
    best disparity by explicit loops: checks the feature-to-pixel alignment, the sign and the
    argmax, and the NaN border."""
    rng = np.random.default_rng(5)
    height, width, max_d = 14, 26, 7
    left = rng.normal(size=(height, width)).astype(np.float32)
    right = rng.normal(size=(height, width)).astype(np.float32)
    net = seeded_net(7)
    assert border(net.layers, net.kernel) == B

    def patch_features(image):
        out = {}
        with torch.no_grad():
            for y in range(B, height - B):
                for x in range(B, width - B):
                    patch = torch.from_numpy(image[y - B : y + B + 1, x - B : x + B + 1].copy())
                    f = net(patch[None, None])
                    assert tuple(f.shape) == (1, 64, 1, 1)
                    out[y, x] = f[0, :, 0, 0].numpy().astype(np.float64)
        return out

    fl, fr = patch_features(left), patch_features(right)
    expected = np.full((height, width), np.nan)
    for (y, x), f in fl.items():
        best, best_d = -np.inf, None
        for d in range(max_d + 1):
            xr = x + sign * d
            if (y, xr) in fr:
                score = float(f @ fr[y, xr])
                if score > best:
                    best, best_d = score, d
        expected[y, x] = best_d
    got = wta_disparity(net, left, right, sign=sign, max_disparity=max_d)
    assert got.dtype == np.float64 and got.shape == (height, width)
    np.testing.assert_array_equal(got, expected)
    with pytest.raises(ValueError, match="one shape"):
        wta_disparity(net, left, right[:, :-1], sign=sign, max_disparity=max_d)


# --------------------------------------------------------------------------------------------
# 3. per-tile scoring and the bootstrap table
# --------------------------------------------------------------------------------------------


def test_tile_sums_match_brute_force():
    rng = np.random.default_rng(4)
    shape, k = (20, 30), 3
    d_gt = rng.uniform(1.0, 10.0, shape)
    d_gt[rng.random(shape) < 0.1] = np.nan
    offsets = rng.choice([-2.0, -0.5, 0.0, 0.3, 0.99, 1.0, 2.5, 3.0, 3.7, 6.0], shape)
    d_hat = np.rint(d_gt) + offsets
    d_hat[rng.random(shape) < 0.1] = np.nan
    mask = rng.random(shape) < 0.8
    labels = rng.integers(0, 9, shape)
    labels[labels == 4] = 5  # a tile with no pixel at all

    brute: dict = {}
    for y in range(shape[0]):
        for x in range(shape[1]):
            if not (mask[y, x] and np.isfinite(d_hat[y, x]) and np.isfinite(d_gt[y, x])):
                continue
            s = brute.setdefault(int(labels[y, x]), dict.fromkeys(SUMS, 0))
            err = abs(d_hat[y, x] - d_gt[y, x])
            s["n"] += 1
            s["hits"] += int(err < 1)
            s["abs_error"] += err
            s["pulled"] += int(abs(d_hat[y, x] - (d_gt[y, x] + k)) < 1)
            s["zero"] += int(abs(d_hat[y, x]) < 0.5)

    got = tile_sums(d_hat, d_gt, mask, labels, conflict_shift=k)
    assert got["tile"].tolist() == sorted(brute)
    for name in SUMS:
        expected = [brute[t][name] for t in sorted(brute)]
        np.testing.assert_allclose(got[name], expected, rtol=1e-12)
    for name in ("n", "hits", "pulled", "zero"):
        assert np.issubdtype(got[name].dtype, np.integer)
    assert sum(brute[t]["pulled"] for t in brute) > 0 and sum(brute[t]["hits"] for t in brute) > 0
    with pytest.raises(ValueError, match="differ in shape"):
        tile_sums(d_hat, d_gt, mask[:, :-1], labels, conflict_shift=k)


# --------------------------------------------------------------------------------------------
# 4. the counterfactual inputs
# --------------------------------------------------------------------------------------------


def test_shift_columns_matches_a_loop():
    rng = np.random.default_rng(30)
    field = rng.normal(size=(5, 9, 3))
    for shift in (-4, -1, 0, 2, 11):
        expected = np.empty_like(field)
        for x in range(9):
            expected[:, x] = field[:, min(max(x - shift, 0), 8)]
        np.testing.assert_array_equal(shift_columns(field, shift), expected)


@pytest.mark.parametrize("sign", [1, -1])
def test_conflict_moves_the_right_variance_to_d_plus_k(sign):
    """400 seeds whose left and right std fields line up at d: after the conflict's
    resampling the right renders' variance lines up with the left's at d + k (Eq. 2-3), not
    at d, while the right seed mean and the left renders are unchanged."""
    rng = np.random.default_rng(31)
    n_draws, h, w, d, k = 400, 24, 64, 5, 3
    sigma_left = rng.uniform(0.02, 0.2, (h, w))  # white: no structure from column to column
    sigma_right = rng.uniform(0.02, 0.2, (h, w))
    for x in range(w):
        if 0 <= x + sign * d <= w - 1:
            sigma_right[:, x + sign * d] = sigma_left[:, x]  # sigma_R(x + s d) = sigma_L(x)
    mean_left = texture(rng, h, w)[..., None] * np.array([1.0, 0.9, 0.8])
    mean_right = texture(rng, h, w)[..., None] * np.array([0.8, 1.0, 0.9])
    left = mean_left + sigma_left[..., None] * rng.normal(size=(n_draws, h, w, 3))
    right = mean_right + sigma_right[..., None] * rng.normal(size=(n_draws, h, w, 3))
    bar_left, bar_right = left.mean(axis=0), right.mean(axis=0)

    moved = np.empty_like(right)
    for n in range(n_draws):
        a, b = counterfactual_pair(
            "conflict", left[n], right[n], bar_left, bar_right, sign=sign, conflict_shift=k
        )
        np.testing.assert_array_equal(a, left[n])
        moved[n] = b
    np.testing.assert_allclose(moved.mean(axis=0), bar_right, atol=1e-12)

    var_left = left.var(axis=0).mean(axis=-1)
    inner = np.zeros((h, w), dtype=bool)
    inner[:, d + 2 * k : w - d - 2 * k] = True  # away from the edge columns, both signs

    def rho(field, disparity):
        warped, omega = warp_right_to_left(field, np.full((h, w), float(disparity)), sign=sign)
        return pearson_over_mask(var_left, warped, omega & inner)["rho"]

    var_moved = moved.var(axis=0).mean(axis=-1)
    var_normal = right.var(axis=0).mean(axis=-1)
    assert rho(var_normal, d) > 0.9  # the construction: normal renders line up at d
    assert rho(var_moved, d + k) > 0.9
    assert abs(rho(var_moved, d)) < 0.2
    assert abs(rho(var_normal, d + k)) < 0.2


def test_clean_camera_and_normal_inputs():
    rng = np.random.default_rng(33)
    shape = (8, 12, 3)
    left, right, bar_l, bar_r, eta_l, eta_r = (rng.normal(size=shape) for _ in range(6))
    a, b = counterfactual_pair("normal", left, right, bar_l, bar_r, sign=-1)
    np.testing.assert_array_equal(a, left)
    np.testing.assert_array_equal(b, right)
    a, b = counterfactual_pair("clean", left, right, bar_l, bar_r, sign=-1)
    np.testing.assert_array_equal(a, bar_l)
    np.testing.assert_array_equal(b, bar_r)
    a, b = counterfactual_pair("camera", left, right, bar_l, bar_r, sign=1, camera=(eta_l, eta_r))
    np.testing.assert_allclose(a, bar_l + eta_l, rtol=0, atol=0)
    np.testing.assert_allclose(b, bar_r + eta_r, rtol=0, atol=0)
    assert set(TEST_INPUTS) == {
        "normal", "shuffled", "camera", "camera_shuffled", "clean", "conflict"
    }
    with pytest.raises(ValueError, match="camera="):
        counterfactual_pair("camera", left, right, bar_l, bar_r, sign=1)
    with pytest.raises(ValueError, match="unknown test input"):
        counterfactual_pair("blurred", left, right, bar_l, bar_r, sign=1)
    with pytest.raises(ValueError, match="sign"):
        counterfactual_pair("normal", left, right, bar_l, bar_r, sign=0)
    with pytest.raises(ValueError, match="differ in shape"):
        counterfactual_pair("normal", left, right[:, :-1], bar_l, bar_r, sign=1)


# --------------------------------------------------------------------------------------------
# 5. the network input
# --------------------------------------------------------------------------------------------


def test_network_input_is_standardised_display_grey():
    rng = np.random.default_rng(40)
    render = rng.uniform(-0.3, 1.8, (12, 16, 3))
    render[0, 0, 1] = np.nan
    render[3, 4, 0] = np.inf
    render[5, 5, 2] = -np.inf
    x = network_input(render)
    assert x.dtype == np.float32 and x.shape == (12, 16)

    encoded, finite = {}, {}
    for y in range(12):
        for c in range(16):
            g = (render[y, c, 0] + render[y, c, 1] + render[y, c, 2]) / 3.0
            finite[y, c] = bool(np.isfinite(g))
            if finite[y, c]:
                encoded[y, c] = float(linear_to_srgb(min(max(g, 0.0), 1.0)))
    values = np.array(list(encoded.values()))
    mean, std = values.mean(), np.sqrt(np.mean((values - values.mean()) ** 2))
    for (y, c), ok in finite.items():
        expected = (encoded[y, c] - mean) / std if ok else 0.0
        assert x[y, c] == pytest.approx(expected, abs=1e-5)
    mask = np.array([[finite[y, c] for c in range(16)] for y in range(12)])
    assert (~mask).sum() == 3 and np.all(x[~mask] == 0.0)
    assert x[mask].mean() == pytest.approx(0.0, abs=1e-6)
    assert x[mask].std() == pytest.approx(1.0, abs=1e-5)
    # everything at or above 1 is clipped: one value, the image's largest
    bright = mask & (np.nan_to_num(render.mean(axis=2), nan=0.0) >= 1.0)
    assert bright.sum() > 5
    assert np.all(x[bright] == x.max())
    assert x.max() == pytest.approx((1.0 - mean) / std, abs=1e-5)

    grey = np.full((4, 5), 0.25)
    np.testing.assert_array_equal(network_input(grey), 0.0)  # constant: zero, not NaN
    with pytest.raises(ValueError, match="no finite pixel"):
        network_input(np.full((3, 3), np.nan))


# --------------------------------------------------------------------------------------------
# 6. determinism and the saved network
# --------------------------------------------------------------------------------------------


def test_training_is_deterministic_per_seed():
    rng = np.random.default_rng(50)
    pairs = [(*shifted_pair(rng, d, -1, noise=0.05, height=24, width=64), -1) for d in (2, 4)]
    frames = frames_of(pairs)
    settings = TrainSettings(steps=12, crops=2, crop_rows=8, crop_cols=32)
    net_a, hist_a = train_matcher(frames, settings, seed=3)
    net_b, hist_b = train_matcher(frames, settings, seed=3)
    net_c, _ = train_matcher(frames, settings, seed=4)
    params_a = dict(net_a.named_parameters())
    params_b = dict(net_b.named_parameters())
    params_c = dict(net_c.named_parameters())
    assert params_a.keys() == params_b.keys() == params_c.keys()
    for name in params_a:
        assert torch.equal(params_a[name], params_b[name]), name
    assert not all(torch.equal(params_a[n], params_c[n]) for n in params_a)
    assert hist_a["loss"] == hist_b["loss"]
    left, right, _ = pairs[0][:3]
    xl, xr = network_input(left), network_input(right)
    da = wta_disparity(net_a, xl, xr, sign=-1, max_disparity=6)
    db = wta_disparity(net_b, xl, xr, sign=-1, max_disparity=6)
    np.testing.assert_array_equal(da, db)
    # training changed the weights from their seeded initialisation
    init = dict(seeded_net(3).named_parameters())
    assert not all(torch.equal(init[n], params_a[n]) for n in init)


def test_save_and_load_round_trip(trained, tmp_path):
    net, _, settings = trained
    meta = {"condition": "none", "scenes": ["a", "b"], "fold": 1}
    path = save_matcher(tmp_path / "net.pt", net, settings=settings, seed=1, meta=meta)
    assert path.is_file()
    loaded, record = load_matcher(path)
    saved, restored = net.state_dict(), loaded.state_dict()
    assert saved.keys() == restored.keys()
    for name in saved:
        assert torch.equal(saved[name], restored[name]), name
    assert not loaded.training
    assert record["settings"] == asdict(settings)
    assert TrainSettings(**record["settings"]) == settings
    assert record["seed"] == 1 and record["meta"] == meta
    assert record["architecture"] == {"kind": "mccnn", "features": 64, "layers": 4, "kernel": 3}
    assert "state_dict" not in record
    left, right, _ = shifted_pair(np.random.default_rng(51), 5, 1, noise=NOISE)
    xl, xr = network_input(left), network_input(right)
    np.testing.assert_array_equal(
        wta_disparity(loaded, xl, xr, sign=1, max_disparity=9),
        wta_disparity(net, xl, xr, sign=1, max_disparity=9),
    )


@pytest.mark.parametrize("content", [b"not a network at all", b"", "dict", "list"])
def test_load_matcher_rejects_other_files(tmp_path, content):
    path = tmp_path / "bad.pt"
    if content == "dict":
        torch.save({"weights": torch.zeros(3)}, path)
    elif content == "list":
        torch.save([1, 2, 3], path)
    else:
        path.write_bytes(content)
    with pytest.raises(ValueError, match=re.escape(str(path))) as info:
        load_matcher(path)
    assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match=re.escape(str(tmp_path / "missing.pt"))):
        load_matcher(tmp_path / "missing.pt")


# --------------------------------------------------------------------------------------------
# 7. scene folds
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n_folds", [2, 3, 7])
def test_fold_scenes_hold_every_scene_out_once(n_folds):
    scenes = [f"scene{i}" for i in range(7)]
    folds = fold_scenes(scenes, n_folds)
    assert len(folds) == n_folds
    held_count = dict.fromkeys(scenes, 0)
    for f, (train, held) in enumerate(folds):
        assert held == [s for i, s in enumerate(scenes) if i % n_folds == f]
        assert not set(train) & set(held)
        assert sorted(train + held) == sorted(scenes)
        for s in held:
            held_count[s] += 1
    assert all(c == 1 for c in held_count.values())


@pytest.mark.parametrize("n_folds", [0, 1, 4])
def test_fold_scenes_rejects_bad_folds(n_folds):
    with pytest.raises(ValueError, match="probe.folds"):
        fold_scenes(["a", "b", "c"], n_folds)


# --------------------------------------------------------------------------------------------
# 8. one held-out scene
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("sign", [1, -1])
def test_test_scene_scores_every_valid_pixel_of_each_frame(sign):
    rng = np.random.default_rng(60)
    n_renders, h, w, tile = 3, 28, 44, 8
    base_l = texture(rng, h, w)[..., None] * np.ones(3)
    base_r = texture(rng, h, w)[..., None] * np.ones(3)
    left = base_l + 0.05 * rng.normal(size=(n_renders, h, w, 3))
    right = base_r + 0.05 * rng.normal(size=(n_renders, h, w, 3))
    disparity = rng.uniform(0.5, 9.0, (h, w))
    disparity[rng.random((h, w)) < 0.08] = np.nan
    disparity[rng.random((h, w)) < 0.05] = -2.0
    disparity[rng.random((h, w)) < 0.05] = 0.0
    disparity[:, :6] = 30.0  # some right pixels leave the image (either side for some sign)
    disparity[:, -6:] = 30.0
    valid = rng.random((h, w)) > 0.1
    glass = np.zeros((h, w), dtype=bool)
    glass[5:20, 10:30] = True
    gt = {"disparity": disparity, "valid": valid, "glass": glass}
    networks = {("none", "main", 0): seeded_net(0), (CONTROL, "main", 4): seeded_net(1)}
    settings = experiment.TestSettings(test_frames=2, max_disparity=6, tile=tile, conflict_shift=2)
    regions = ("all", "glass", "non_glass")
    rows = experiment.test_scene(
        networks,
        predict_matcher,
        left,
        right,
        gt,
        scene="s1",
        sign=sign,
        regions=regions,
        law=(0.01, 1e-4),
        settings=settings,
    )

    # independent count: d finite and > 0, x + s d inside the image, valid, not in the border
    n_tiles_x = -(-w // tile)
    expected = {r: {} for r in regions}
    for y in range(B, h - B):
        for x in range(B, w - B):
            d = disparity[y, x]
            if not (np.isfinite(d) and d > 0 and 0 <= x + sign * d <= w - 1 and valid[y, x]):
                continue
            t = (y // tile) * n_tiles_x + x // tile
            for region in ("all", "glass" if glass[y, x] else "non_glass"):
                expected[region][t] = expected[region].get(t, 0) + 2  # two test frames
    assert sum(expected["glass"].values()) > 0 and sum(expected["non_glass"].values()) > 0

    df = pd.DataFrame(rows)
    assert set(df["scene"]) == {"s1"}
    combos = set(zip(df["network"], df["train_seed"], df["test_input"], df["region"], strict=True))
    assert combos == {
        (net, seed, t, r) for net, _, seed in networks for t in TEST_INPUTS for r in regions
    }
    assert set(df["variant"]) == {"main"}
    for (*_, region), part in df.groupby(["network", "train_seed", "test_input", "region"]):
        assert dict(zip(part["tile"], part["n"], strict=True)) == expected[region]
        assert (part["hits"] <= part["n"]).all() and (part["pulled"] <= part["n"]).all()
        assert (part["abs_error"] >= 0).all()

    # the normal input's hits, recomputed from the network's own prediction of each frame
    d_gt = np.where(np.isfinite(disparity) & (disparity > 0), disparity, np.nan)
    for (net_name, _, _), net in networks.items():
        hits: dict = {}
        for frame in range(2):
            d_hat = wta_disparity(
                net,
                network_input(left[frame]),
                network_input(right[frame]),
                sign=sign,
                max_disparity=settings.max_disparity,
            )
            for y in range(B, h - B):
                for x in range(B, w - B):
                    d = d_gt[y, x]
                    if np.isfinite(d) and 0 <= x + sign * d <= w - 1 and valid[y, x]:
                        t = (y // tile) * n_tiles_x + x // tile
                        hits[t] = hits.get(t, 0) + int(abs(d_hat[y, x] - d) < 1)
        part = df[
            (df["network"] == net_name) & (df["test_input"] == "normal") & (df["region"] == "all")
        ]
        assert dict(zip(part["tile"], part["hits"], strict=True)) == {
            t: hits.get(t, 0) for t in expected["all"]
        }
