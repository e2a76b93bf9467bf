"""The user's own network on the counterfactual inputs (stereovar.probe.user_model).

Synthetic frames whose only matching information beyond a weak texture is a planted
cross-view variance cue: a smooth pattern z sets the noise level of both views, carried into
the right view by a constant disparity, while every render's noise is drawn independently. A
small network trained here to match by local noise energy uses the cue, so the Monte Carlo
shuffle costs it accuracy and the camera-noise shuffle does not; a network that reads only the
smoothed (clean) image does not, so neither shuffle costs it anything.
"""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")
from torch import nn  # noqa: E402
from torch.nn import functional as F  # noqa: E402

from stereovar.calibration.synthesis import smooth_field  # noqa: E402
from stereovar.errors import StereovarError  # noqa: E402
from stereovar.probe.user_checks import shift_response  # noqa: E402
from stereovar.probe.user_checks import testability as checks_of  # noqa: E402
from stereovar.probe.user_loading import ModelError, load_user_model  # noqa: E402
from stereovar.probe.user_model import (  # noqa: E402
    ModelSettings,
    frame_law,
    model_image,
    predict_user,
    score_frame,
)
from stereovar.probe.user_summary import model_reading, model_rows  # noqa: E402

H, W, D, D0, N = 32, 48, 6, 2, 4
SETTINGS = ModelSettings(test_frames=N, tile=8, reps=400, batch=8)


def truth(step=0):
    """The left view's ground truth: D0 in the top half of the rows, D0 + step below."""
    d = np.full((H, W), float(D0))
    d[H // 2 :] += step
    return {"disparity": d, "valid": np.ones((H, W), bool)}


def frame(rng, *, strength=2.5, texture=0.0, step=0):
    """N renders per view (sign -1: right pixel at x - d, d of ``truth(step)``) around a mean
    that varies only with the row (plus an optional weak texture carried by d), with noise of
    standard deviation 0.04 exp(strength z / 2), z a smooth pattern also carried by d."""
    span = W + D0 + step
    rows = np.linspace(0.12, 0.4, H)[:, None] * np.ones((H, span))
    base = rows + texture * smooth_field((H, span), rng, scale=2.0)
    z = smooth_field((H, span), rng, scale=2.0)
    # left pixel x sees the fields at x; its match, right pixel x - d, sees them there too
    shifts = truth(step)["disparity"][:, 0].astype(int)

    def right_of(field):
        return np.stack([field[y, s : s + W] for y, s in enumerate(shifts)])

    mean_l, mean_r = base[:, :W], right_of(base)
    sd_l = 0.04 * np.exp(strength * z[:, :W] / 2)
    sd_r = 0.04 * np.exp(strength * right_of(z) / 2)
    left = mean_l[..., None] + sd_l[..., None] * rng.standard_normal((N, H, W, 3))
    right = mean_r[..., None] + sd_r[..., None] * rng.standard_normal((N, H, W, 3))
    return left, right, np.repeat(mean_r[..., None], 3, axis=2)


TRUTH = truth()


class EnergyNet(nn.Module):
    """(left, right) sRGB (B, 3, H, W) -> disparity (B, 1, H, W): log local energy of a
    learned high-pass filter, compared across D disparities, aggregated over 5x5, WTA."""

    def __init__(self, features: int = 4):
        super().__init__()
        self.high = nn.Conv2d(1, features, 3, padding=1)
        self.mix = nn.Conv2d(features, features, 1)
        self.scale = nn.Parameter(torch.tensor(5.0))

    def features(self, x):
        g = x.mean(1, keepdim=True)
        e = F.avg_pool2d(self.high(g) ** 2, 5, stride=1, padding=2, count_include_pad=False)
        f = self.mix(torch.log(e + 1e-4))
        return f - f.mean((2, 3), keepdim=True)

    def scores(self, left, right):
        fl, fr = self.features(left), self.features(right)
        cost = torch.stack(
            [
                -(fl - F.pad(fr, (d, 0, 0, 0), mode="replicate")[..., : fr.shape[-1]]).abs().mean(1)
                for d in range(D)
            ],
            1,
        )
        return self.scale * F.avg_pool2d(cost, 5, stride=1, padding=2, count_include_pad=False)

    def forward(self, left, right):
        return self.scores(left, right).argmax(1, keepdim=True).float()


class CleanNet(nn.Module):
    """Reads only the smoothed image: SAD of Gaussian-blurred grey over 9x9 windows, WTA over
    disparities 0 to ``candidates - 1``; returns (B, H, W)."""

    def __init__(self, candidates=D):
        super().__init__()
        self.candidates = candidates
        x = torch.arange(-6, 7, dtype=torch.float32)
        k = torch.exp(-(x**2) / (2 * 2.0**2))
        self.register_buffer("kernel", (k / k.sum())[None, None, None])

    def blur(self, x):
        g = x.mean(1, keepdim=True)
        g = F.conv2d(F.pad(g, (6, 6, 0, 0), mode="replicate"), self.kernel)
        return F.conv2d(F.pad(g, (0, 0, 6, 6), mode="replicate"), self.kernel.transpose(2, 3))

    def forward(self, left, right):
        bl, br = self.blur(left), self.blur(right)
        cost = torch.cat(
            [
                (bl - F.pad(br, (d, 0, 0, 0), mode="replicate")[..., : br.shape[-1]]).abs()
                for d in range(self.candidates)
            ],
            1,
        )
        cost = F.avg_pool2d(cost, 9, stride=1, padding=4, count_include_pad=False)
        return cost.argmin(1).float()


def batch(stack):
    return torch.from_numpy(np.stack([model_image(a) for a in stack]))


def train_energy(frames, steps=120, seed=0):
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    net = EnergyNet()
    opt = torch.optim.Adam(net.parameters(), lr=0.05)
    target = torch.full((1, H, W - D), D0)
    for step in range(steps):
        left, right, _ = frames[step % len(frames)]
        n = int(rng.integers(N))
        scores = net.scores(batch(left[n : n + 1]), batch(right[n : n + 1]))[..., D:]
        loss = F.cross_entropy(scores, target)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return net.eval()


def rows_of(net, frames, *, sign=-1, settings=SETTINGS, truth_left=TRUTH):
    """The scored rows of ``net`` on ``frames`` (left, right, _), frame ``i`` named ``f{i}``."""
    rows = []
    for i, (left, right, _) in enumerate(frames):
        rows += score_frame(
            net,
            left,
            right,
            truth_left,
            scene=f"f{i}",
            sign=sign,
            law=frame_law(left),
            settings=settings,
        )
    return rows


def table_of(net, frames, *, sign=-1, truth_left=TRUTH):
    return checked_table(net, frames, sign=sign, truth_left=truth_left)[0]


def checked_table(net, frames, *, sign=-1, truth_left=TRUTH):
    """The table of ``net`` on ``frames`` by row, and its checks (testability)."""
    rows = rows_of(net, frames, sign=sign, truth_left=truth_left)
    table = model_rows(rows, reps=SETTINGS.reps)
    return {r["row"]: r for r in table}, checks_of(table, shift_response(rows))


@pytest.fixture(scope="module")
def cue_frames():
    rng = np.random.default_rng(1)
    return [frame(rng, texture=0.05) for _ in range(6)]


def test_a_network_trained_on_the_cue_drops_under_the_mc_shuffle_only(cue_frames):
    torch.set_num_threads(1)
    net = train_energy(cue_frames[:3])
    table = table_of(net, cue_frames[3:])
    mc, cam, diff = table["mc_shuffle"], table["camera_shuffle"], table["mc_minus_camera"]
    assert table["normal"]["accuracy"] > 0.35  # it matches (chance is 1/6)
    assert mc["accuracy_low"] > 0.05
    assert diff["accuracy_low"] > 0.05 and diff["accuracy"] > 2 * abs(cam["accuracy"])
    assert mc["epe"] > 0 and diff["epe_low"] > 0
    for r in table.values():
        assert r["accuracy_low"] <= r["accuracy"] <= r["accuracy_high"]
    assert model_reading(table.values()).startswith("the model uses the Monte Carlo cue")


STEP = 2  # frames of two disparities, D0 and D0 + STEP: no constant answers both


@pytest.mark.parametrize("sign", [-1, 1])
def test_a_network_that_reads_the_clean_image_shows_no_drop(sign):
    """It matches (it follows the 2-px move of its right view, in either sign, and beats the
    best constant), and the shuffle costs it nothing: a trustworthy no use."""
    rng = np.random.default_rng(2)
    frames = [frame(rng, texture=0.15, strength=1.0, step=STEP) for _ in range(3)]
    if sign == 1:  # mirrored frames: the right pixel is at x + d
        frames = [(f[0][:, :, ::-1], f[1][:, :, ::-1], f[2]) for f in frames]
    net = CleanNet(candidates=D0 + STEP + 3).eval()  # the moved disparities stay in range
    table, checks = checked_table(net, frames, sign=sign, truth_left=truth(STEP))
    diff = table["mc_minus_camera"]
    assert table["normal"]["accuracy"] > 0.8
    assert diff["accuracy_low"] < 0 < diff["accuracy_high"]
    assert abs(diff["accuracy"]) < 0.03
    assert checks["responds"] and checks["beats_constant"] and checks["testable"]
    assert checks["mean_change_px"] == pytest.approx(checks["shift_px"], abs=0.1)
    assert table["over_constant"]["accuracy_low"] > 0.1
    assert model_reading(table.values(), checks).startswith("no use of the Monte Carlo cue")


# ------------------------------------------------------------------------------------------
# networks the probe cannot test: their "no use" would mean nothing
# ------------------------------------------------------------------------------------------


class NearlyConstant(nn.Module):
    """The issue's network: random weights whose output is ``value`` px plus at most a
    thousandth of a pixel that depends on the input."""

    def __init__(self, value=D0 + STEP + 0.4):
        super().__init__()
        self.value = float(value)
        self.conv = nn.Conv2d(6, 1, 3, padding=1)
        weights = np.random.default_rng(0).normal(0, 0.5, (1, 6, 3, 3))
        self.conv.weight.data = torch.from_numpy(weights).float()

    def forward(self, left, right):
        return self.value + 1e-3 * torch.tanh(self.conv(torch.cat([left, right], 1)))


class RowOracle(nn.Module):
    """The ground truth of truth(STEP), whatever the views: right, but blind to them."""

    def forward(self, left, right):
        d = torch.full_like(left[:, :1], float(D0))
        d[..., left.shape[-2] // 2 :, :] += STEP
        return d


class Garbage(nn.Module):
    """Follows its input, but not to a match: 3 + 3 tanh of a random filter of L - R."""

    def __init__(self):
        super().__init__()
        self.conv = nn.Conv2d(3, 1, 3, padding=1)
        weights = np.random.default_rng(1).normal(0, 30.0, (1, 3, 3, 3))
        self.conv.weight.data = torch.from_numpy(weights).float()

    def forward(self, left, right):
        return 3 + 3 * torch.tanh(self.conv(left - right))


@pytest.fixture(scope="module")
def step_frames():
    rng = np.random.default_rng(4)
    return [frame(rng, texture=0.15, strength=1.0, step=STEP) for _ in range(2)]


def test_a_nearly_constant_network_is_not_testable_and_never_reads_no_use(step_frames):
    table, checks = checked_table(NearlyConstant(), step_frames, truth_left=truth(STEP))
    # it hits the lower half only (|4.4 - 4| < 1), as many pixels as the constant at most
    half = (W - D0 - STEP) / ((W - D0) + (W - D0 - STEP))
    assert table["normal"]["accuracy"] == pytest.approx(half, abs=1e-12)
    assert table["constant"]["accuracy"] == pytest.approx(1 - half, abs=1e-12)
    assert checks["mean_abs_change_px"] < 1e-3 and checks["responds"] is False
    assert checks["beats_constant"] is False and checks["testable"] is False
    plain = model_reading(table.values())  # without the checks it would read no use
    assert plain.startswith("no use of the Monte Carlo cue detected")
    reading = model_reading(table.values(), checks)
    assert reading.startswith("not testable: the network's output does not respond to its input")
    assert "no better than a constant disparity" in reading
    assert "no use of the Monte Carlo cue detected" not in reading and "\n" not in reading


def test_a_network_blind_to_its_views_is_not_testable_even_when_right(step_frames):
    table, checks = checked_table(RowOracle(), step_frames, truth_left=truth(STEP))
    assert table["normal"]["accuracy"] == 1.0 and table["normal"]["epe"] == 0.0
    assert checks["beats_constant"] and checks["mean_abs_change_px"] == 0.0
    assert not checks["testable"] and "does not respond" in checks["problem"]
    assert "no better" not in checks["problem"]
    assert model_reading(table.values(), checks).startswith("not testable: ")


def test_a_network_that_follows_its_input_but_does_not_match_is_not_testable(step_frames):
    table, checks = checked_table(Garbage(), step_frames, truth_left=truth(STEP))
    assert checks["responds"] and checks["mean_abs_change_px"] > 0.5
    assert not checks["beats_constant"] and not checks["testable"]
    assert checks["problem"].startswith("the network is no better than a constant disparity")
    assert model_reading(table.values(), checks).startswith("not testable: ")


# ------------------------------------------------------------------------------------------
# the best constant, counted by brute force
# ------------------------------------------------------------------------------------------

GRID = np.arange(-2.0, 12.0, 0.25)
"""Candidate constants: on a 0.5-px lattice of disparities, the best of each measure lies on
this grid (a median is a lattice value; a window of hits is open, (c - 1, c + 1))."""


def brute_force(d):
    """The most hits (|c - d| < 1) and the least summed |c - d| of any constant on GRID."""
    d = np.asarray(d, dtype=np.float64)[:, None]
    return int((np.abs(GRID - d) < 1).sum(0).max()), float(np.abs(GRID - d).sum(0).min())


def lattice_truth(rng, low, high):
    """Disparities on a 0.5-px lattice in [low, high], a fifth of the pixels not valid."""
    d = rng.integers(2 * low, 2 * high + 1, (H, W)) / 2.0
    return {"disparity": d, "valid": rng.random((H, W)) > 0.2}


def test_best_constants_match_a_grid_search():
    from stereovar.probe.user_checks import best_constants

    rng = np.random.default_rng(7)
    for _ in range(50):
        d = rng.integers(0, 21, rng.integers(1, 40)) / 2.0
        c_acc, c_epe = best_constants(d)
        hits, error = brute_force(d)
        assert (np.abs(c_acc - d) < 1).sum() == hits
        assert np.abs(c_epe - d).sum() == pytest.approx(error, abs=1e-9)


def test_the_constant_row_is_the_best_constant_of_each_frame(step_frames):
    """Two frames of known, different disparities: the constant row is, pooled over the
    frames, the most hits and the least error any constant of each frame gets on the scored
    pixels (valid, the match x - d inside the image), counted here by grid search."""
    rng = np.random.default_rng(8)
    truths = [lattice_truth(rng, 1, 4), lattice_truth(rng, 3, 9)]
    rows, hits, errors, pixels = [], 0, 0.0, 0
    for i, ((left, right, _), t) in enumerate(zip(step_frames, truths, strict=True)):
        rows += score_frame(
            NearlyConstant(), left, right, t, scene=f"f{i}", sign=-1, law=frame_law(left),
            settings=SETTINGS,
        )
        scored = t["valid"] & (np.arange(W)[None, :] >= t["disparity"])  # x - d >= 0
        best_hits, best_error = brute_force(t["disparity"][scored])
        hits, errors, pixels = hits + best_hits, errors + best_error, pixels + scored.sum()
    table = {r["row"]: r for r in model_rows(rows, reps=50)}
    constant = table["constant"]
    assert constant["n_pixels"] == SETTINGS.test_frames * pixels == table["normal"]["n_pixels"]
    assert constant["accuracy"] == pytest.approx(hits / pixels, abs=1e-12)
    assert constant["epe"] == pytest.approx(errors / pixels, abs=1e-12)
    assert constant["accuracy_low"] <= constant["accuracy"] <= constant["accuracy_high"]
    gain = table["over_constant"]
    assert gain["accuracy"] == pytest.approx(
        table["normal"]["accuracy"] - constant["accuracy"], abs=1e-12
    )
    assert gain["epe"] == pytest.approx(constant["epe"] - table["normal"]["epe"], abs=1e-12)


def test_intervals_resample_tiles_within_frames():
    """One frame's tiles all hit, the other's all miss: stratified by frame, every replicate
    keeps the 50 % mix, so the interval has zero width (an unstratified bootstrap would not)."""
    rows = [
        {"scene": scene, "test_input": kind, "tile": t, "n": 10, "hits": hits, "abs_error": 0.0}
        for scene, hits in (("a", 10), ("b", 0))
        for kind in ("normal", "shuffled", "camera", "camera_shuffled")
        for t in range(5)
    ]
    normal = {r["row"]: r for r in model_rows(rows, reps=200)}["normal"]
    assert normal["accuracy"] == normal["accuracy_low"] == normal["accuracy_high"] == 0.5


def test_predict_user_mirrors_frames_of_sign_plus_one():
    class Column(nn.Module):  # "disparity" = the column index, conventional sign
        def forward(self, left, right):
            b, _, h, w = left.shape
            return torch.arange(w, dtype=torch.float32).expand(b, 1, h, w)

    pair = (np.zeros((2, 5, 3)), np.zeros((2, 5, 3)))
    (conv,) = predict_user(Column(), [pair], sign=-1)
    (paper,) = predict_user(Column(), [pair], sign=1)
    assert conv[0].tolist() == [0, 1, 2, 3, 4]
    assert paper[0].tolist() == [4, 3, 2, 1, 0]


# ------------------------------------------------------------------------------------------
# loading: one line each
# ------------------------------------------------------------------------------------------

MODULE = """
import torch
from torch import nn

class Net(nn.Module):
    def __init__(self):
        super().__init__()
        self.w = nn.Parameter(torch.zeros(1))
    def forward(self, left, right):
        return left[:, :1] * 0 + self.w

class Flat(Net):
    def forward(self, left, right):
        return left.mean(1)[:, :, :-1]

def build():
    return Net()

def flat():
    return Flat()

def broken():
    raise RuntimeError("no checkpoint\\nconfigured")
"""


@pytest.fixture
def user_package(tmp_path, monkeypatch):
    (tmp_path / "h5_user_nets.py").write_text(MODULE)
    (tmp_path / "h5_bad_nets.py").write_text("import not_a_module_anywhere\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    weights = tmp_path / "w.pt"
    torch.save({"w": torch.ones(1)}, weights)
    return tmp_path, weights


def test_load_user_model_reads_a_state_dict_or_a_checkpoint(user_package):
    root, weights = user_package
    model = load_user_model("h5_user_nets:build", weights)
    assert not model.training and float(model.w.detach()) == 1.0
    torch.save({"state_dict": {"w": torch.full((1,), 2.0)}, "epoch": 3}, root / "c.pt")
    assert float(load_user_model("h5_user_nets:build", root / "c.pt").w.detach()) == 2.0
    assert float(load_user_model(f"{root / 'h5_user_nets.py'}:build", weights).w.detach()) == 1.0


@pytest.mark.parametrize(
    ("spec", "weights", "words"),
    [
        ("h5_user_nets:build", "missing.pt", "weights file"),
        ("h5_user_nets.build", None, "is not package.module:factory"),
        ("h5_no_such_module:build", None, "found neither in the current folder"),
        ("h5_bad_nets:build", None, "install the package it imports (not_a_module_anywhere)"),
        ("h5_user_nets:missing", None, "has no attribute 'missing'"),
        ("h5_user_nets:broken", None, "raised RuntimeError: no checkpoint configured"),
        ("h5_user_nets:flat", "pickle", "does not load with torch.load(weights_only=True)"),
        ("h5_user_nets:flat", "other", "does not fit the model"),
    ],
)
def test_loading_errors_are_one_line(user_package, spec, weights, words):
    root, good = user_package
    path = good
    if weights == "missing.pt":
        path = root / "missing.pt"
    elif weights == "pickle":
        path = root / "p.pt"
        torch.save({"w": object()}, path)
    elif weights == "other":
        path = root / "o.pt"
        torch.save({"v": torch.ones(1)}, path)
    with pytest.raises(ModelError) as info:
        load_user_model(spec, path)
    message = str(info.value)
    assert isinstance(info.value, StereovarError)
    assert words in message and "\n" not in message


def test_wrong_output_shape_names_the_expected_shape(user_package):
    _, weights = user_package
    model = load_user_model("h5_user_nets:flat", weights)
    pair = (np.zeros((4, 6, 3)), np.zeros((4, 6, 3)))
    with pytest.raises(ModelError) as info:
        predict_user(model, [pair, pair], sign=-1)
    message = str(info.value)
    assert "(2, 4, 5)" in message and "(2, 1, 4, 6) or (2, 4, 6)" in message
    assert "\n" not in message


# ------------------------------------------------------------------------------------------
# --model nets:build: the current folder is searched
# ------------------------------------------------------------------------------------------


@pytest.fixture
def here(tmp_path, monkeypatch):
    """A folder holding h5_here_nets.py and w.pt, made the current one, with no entry of the
    import path pointing at it (as for the installed ``stereovar`` script)."""
    import os
    import sys

    (tmp_path / "h5_here_nets.py").write_text(MODULE)
    torch.save({"w": torch.full((1,), 3.0)}, tmp_path / "w.pt")
    monkeypatch.chdir(tmp_path)
    kept = [p for p in sys.path if p and os.path.abspath(p) != str(tmp_path)]
    monkeypatch.setattr(sys, "path", kept)  # restored after the test
    monkeypatch.delitem(sys.modules, "h5_here_nets", raising=False)
    yield tmp_path
    sys.modules.pop("h5_here_nets", None)


def test_a_module_in_the_current_folder_is_found(here):
    import importlib.util
    import sys

    assert importlib.util.find_spec("h5_here_nets") is None  # not importable before
    model = load_user_model("h5_here_nets:build", "w.pt")
    assert float(model.w.detach()) == 3.0
    assert sys.path[0] == str(here)


def test_a_module_found_nowhere_names_the_current_folder_and_the_fixes(here):
    with pytest.raises(ModelError) as info:
        load_user_model("h5_elsewhere.nets:build", "w.pt")
    message = str(info.value)
    assert "\n" not in message
    assert f"h5_elsewhere is found neither in the current folder {here}" in message
    assert "run stereovar from the folder that holds h5_elsewhere/nets.py" in message
    assert "(h5_elsewhere/nets.py:factory)" in message and "PYTHONPATH" in message


def test_stereovar_probe_loads_the_model_from_the_current_folder(here, monkeypatch, capsys):
    """`stereovar probe --model h5_here_nets:build` gets past loading the model (stopped
    just after it, before any workflow)."""
    from stereovar.cli import main, probe

    loaded = []
    original = load_user_model

    def spy(*args, **kwargs):
        loaded.append(original(*args, **kwargs))
        return loaded[-1]

    def stop():
        raise StereovarError("stopped after loading")

    monkeypatch.setattr("stereovar.probe.user_loading.load_user_model", spy)
    monkeypatch.setattr(probe, "_project_root", stop)
    assert main(["probe", "--model", "h5_here_nets:build", "--weights", "w.pt"]) != 0
    assert "stopped after loading" in capsys.readouterr().err
    assert len(loaded) == 1 and float(loaded[0].w.detach()) == 3.0
