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
from stereovar.probe.user_model import (  # noqa: E402
    ModelError,
    ModelSettings,
    frame_law,
    load_user_model,
    model_image,
    model_reading,
    model_rows,
    predict_user,
    score_frame,
)

H, W, D, D0, N = 32, 48, 6, 2, 4
SETTINGS = ModelSettings(test_frames=N, tile=8, reps=400, batch=8)


def frame(rng, *, strength=2.5, texture=0.0):
    """N renders per view (sign -1: right pixel at x - D0) around a mean that varies only with
    the row (plus an optional weak texture carried by D0), with noise of standard deviation
    0.04 exp(strength z / 2), z a smooth pattern also carried by D0."""
    rows = np.linspace(0.12, 0.4, H)[:, None] * np.ones((H, W + D0))
    base = rows + texture * smooth_field((H, W + D0), rng, scale=2.0)
    z = smooth_field((H, W + D0), rng, scale=2.0)
    # left pixel x sees the fields at x; its match, right pixel x - D0, sees them there too
    mean_l, mean_r = base[:, :W], base[:, D0:]
    sd_l = 0.04 * np.exp(strength * z[:, :W] / 2)
    sd_r = 0.04 * np.exp(strength * z[:, D0:] / 2)
    left = mean_l[..., None] + sd_l[..., None] * rng.standard_normal((N, H, W, 3))
    right = mean_r[..., None] + sd_r[..., None] * rng.standard_normal((N, H, W, 3))
    return left, right, np.repeat(mean_r[..., None], 3, axis=2)


TRUTH = {"disparity": np.full((H, W), float(D0)), "valid": np.ones((H, W), bool)}


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
    """Reads only the smoothed image: SAD of Gaussian-blurred grey over 9x9 windows, WTA;
    returns (B, H, W)."""

    def __init__(self):
        super().__init__()
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
                for d in range(D)
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


def rows_of(net, frames, *, sign=-1, settings=SETTINGS):
    """The scored rows of ``net`` on ``frames`` (left, right, _), frame ``i`` named ``f{i}``."""
    rows = []
    for i, (left, right, _) in enumerate(frames):
        rows += score_frame(
            net,
            left,
            right,
            TRUTH,
            scene=f"f{i}",
            sign=sign,
            law=frame_law(left),
            settings=settings,
        )
    return rows


def table_of(net, frames, *, sign=-1):
    return {r["row"]: r for r in model_rows(rows_of(net, frames, sign=sign), reps=SETTINGS.reps)}


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


@pytest.mark.parametrize("sign", [-1, 1])
def test_a_network_that_reads_the_clean_image_shows_no_drop(sign):
    rng = np.random.default_rng(2)
    frames = [frame(rng, texture=0.15, strength=1.0) for _ in range(3)]
    if sign == 1:  # mirrored frames: the right pixel is at x + d
        frames = [(f[0][:, :, ::-1], f[1][:, :, ::-1], f[2]) for f in frames]
    table = table_of(CleanNet().eval(), frames, sign=sign)
    diff = table["mc_minus_camera"]
    assert table["normal"]["accuracy"] > 0.9
    assert diff["accuracy_low"] < 0 < diff["accuracy_high"]
    assert abs(diff["accuracy"]) < 0.03
    assert model_reading(table.values()).startswith("no use of the Monte Carlo cue")


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
        ("h5_no_such_module:build", None, "does not import (ModuleNotFoundError"),
        ("h5_bad_nets:build", None, "does not import (ModuleNotFoundError"),
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
