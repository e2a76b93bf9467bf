"""The user's network when it or its weights are not what the probe needs: a weights path
that is a folder or a named pipe, a model with no finite output, a model with NaN on part
of the image (stereovar.probe.user_model, stereovar.jobs.probe_model, ``stereovar probe``).

Every case ends in one line naming the cause; the expected numbers are counted here pixel by
pixel from the inputs the model was given.
"""

from __future__ import annotations

import json
import logging
import os
import re

import numpy as np
import pytest

torch = pytest.importorskip("torch")
from torch import nn  # noqa: E402

from stereovar.cli import main  # noqa: E402
from stereovar.errors import StereovarError  # noqa: E402
from stereovar.probe.scoring import SUMS, tile_sums  # noqa: E402
from stereovar.probe.user_loading import ModelError, load_user_model  # noqa: E402
from stereovar.probe.user_model import (  # noqa: E402
    MODEL_INPUTS,
    ModelSettings,
    frame_law,
    model_image,
    model_pairs,
)
from stereovar.probe.user_summary import model_rows  # noqa: E402

from .test_probe_user_model import (  # noqa: E402
    D0,
    STEP,
    TRUTH,
    CleanNet,
    H,
    NearlyConstant,
    W,
    frame,
    truth,
)
from .test_probe_user_model import rows_of as scored_rows  # noqa: E402

SETTINGS = ModelSettings(test_frames=2, tile=8, reps=50, batch=8)
SIGN = -1  # TRUTH's frames: the right pixel of left pixel x is at x - D0


def rows_of(model, frames):
    return scored_rows(model, frames, sign=SIGN, settings=SETTINGS)


OMEGA = np.zeros((H, W), bool)
OMEGA[:, D0:] = True  # the left pixels whose match x - D0 lies in the image
BOUND = max(D0, 1.0)  # a non-finite prediction's end-point error: the largest disparity, >= 1


def probe_line(capsys, *args) -> str:
    """The one line ``stereovar probe ARGS`` prints to stderr, and it fails."""
    assert main(["probe", "--model", "some_nets:build", *args]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


# ------------------------------------------------------------------------------------------
# --weights that is not a file
# ------------------------------------------------------------------------------------------


def test_weights_that_is_a_folder_are_named_a_folder_with_the_file_inside(tmp_path, capsys):
    folder = tmp_path / "run7"
    folder.mkdir()
    torch.save({"w": torch.ones(1)}, folder / "model.pt")
    line = probe_line(capsys, "--weights", str(folder))
    assert f"{folder} is a directory" in line and "does not exist" not in line
    assert "give the weights file inside it" in line and str(folder / "model.pt") in line
    with pytest.raises(ModelError, match="is a directory"):
        load_user_model("some_nets:build", folder)


def test_weights_that_is_a_named_pipe_are_named_a_pipe(tmp_path, capsys):
    fifo = tmp_path / "weights.pt"
    os.mkfifo(fifo)  # nothing writes to it: opening it for reading would wait for ever
    line = probe_line(capsys, "--weights", str(fifo))
    assert f"{fifo} is a named pipe" in line and "does not exist" not in line
    with pytest.raises(ModelError, match="is a named pipe"):
        load_user_model("some_nets:build", fifo)


def test_missing_weights_still_say_so(tmp_path, capsys):
    line = probe_line(capsys, "--weights", str(tmp_path / "nowhere.pt"))
    assert "nowhere.pt does not exist" in line


# ------------------------------------------------------------------------------------------
# models with non-finite disparity
# ------------------------------------------------------------------------------------------


class Constant(nn.Module):
    """Returns ``value`` everywhere (B, 1, H, W)."""

    def __init__(self, value):
        super().__init__()
        self.value = float(value)

    def forward(self, left, right):
        return torch.full_like(left[:, :1], self.value)


class NanWhereBright(nn.Module):
    """D0 where the left view's red channel is at most ``threshold``, NaN where above: a NaN
    pattern that follows the input."""

    def __init__(self, threshold):
        super().__init__()
        self.threshold = float(threshold)

    def forward(self, left, right):
        red = left[:, :1]
        return torch.where(red > self.threshold, torch.nan, torch.full_like(red, float(D0)))


class NanOnTheRightHalf(nn.Module):
    """D0 on the left half of the image, NaN on the right half, whatever the input."""

    def forward(self, left, right):
        d = torch.full_like(left[:, :1], float(D0))
        d[..., W // 2 :] = torch.nan
        return d


@pytest.fixture(scope="module")
def frames():
    rng = np.random.default_rng(3)
    return [frame(rng, texture=0.05) for _ in range(2)]


@pytest.mark.parametrize(
    ("value", "words"), [(np.nan, "are NaN"), (np.inf, "are Inf"), (-np.inf, "are Inf")]
)
def test_a_model_without_finite_disparity_stops_in_one_line(frames, value, words):
    with pytest.raises(ModelError) as info:
        model_rows(rows_of(Constant(value), frames[:1]), reps=SETTINGS.reps)
    message = str(info.value)
    assert isinstance(info.value, StereovarError) and "\n" not in message
    predictions = SETTINGS.test_frames * len(MODEL_INPUTS)
    assert message.startswith("the model returned no finite disparity")
    assert f"all {predictions} of its predictions" in message and words in message
    assert "frame f0" in message and all(kind in message for kind in MODEL_INPUTS)
    assert f"{H}x{W}" in message


def expected_table(model, frames) -> dict:
    """Per input, counted pixel by pixel over the model's own outputs on the inputs of every
    test render: scored pixels, hits, summed end-point error (a non-finite prediction is a
    miss at BOUND) and non-finite predictions."""
    out = {kind: dict(n=0, hits=0, abs_error=0.0, nonfinite=0) for kind in MODEL_INPUTS}
    ys, xs = np.nonzero(OMEGA)
    for i, (left, right, _) in enumerate(frames):
        pairs = model_pairs(
            left, right, scene=f"f{i}", sign=SIGN, law=frame_law(left), settings=SETTINGS
        )
        for (_, kind), (a, b) in pairs.items():
            x_l = torch.from_numpy(model_image(a))[None]
            x_r = torch.from_numpy(model_image(b))[None]
            with torch.no_grad():
                d_hat = model(x_l, x_r)[0, 0].double().numpy()
            acc = out[kind]
            for y, x in zip(ys, xs, strict=True):
                acc["n"] += 1
                if not np.isfinite(d_hat[y, x]):
                    acc["nonfinite"] += 1
                    acc["abs_error"] += BOUND
                    continue
                err = abs(d_hat[y, x] - TRUTH["disparity"][y, x])
                acc["hits"] += int(err < 1)
                acc["abs_error"] += err
    return out


def check_table(table, expected):
    for kind in MODEL_INPUTS:
        e, r = expected[kind], table[kind]
        assert r["n_pixels"] == e["n"]
        assert r["accuracy"] == pytest.approx(e["hits"] / e["n"], abs=1e-12)
        assert r["epe"] == pytest.approx(e["abs_error"] / e["n"], abs=1e-12)
        assert r["nonfinite_share"] == pytest.approx(e["nonfinite"] / e["n"], abs=1e-12)
    for name, (before, after) in (
        ("mc_shuffle", ("normal", "shuffled")),
        ("camera_shuffle", ("camera", "camera_shuffled")),
    ):
        assert table[name]["accuracy"] == pytest.approx(
            table[before]["accuracy"] - table[after]["accuracy"], abs=1e-12
        )
        assert table[name]["nonfinite_share"] == pytest.approx(
            table[after]["nonfinite_share"] - table[before]["nonfinite_share"], abs=1e-12
        )


def test_nan_on_half_the_image_counts_as_misses_on_every_pixel(frames):
    """The issue's case: NaN on the right half. Every input is scored on all of Omega; the
    right half (W / 2 of its W - D0 columns) is missed at the bound."""
    table = {r["row"]: r for r in model_rows(rows_of(NanOnTheRightHalf(), frames), reps=50)}
    pixels = len(frames) * SETTINGS.test_frames * H * (W - D0)
    share = (W / 2) / (W - D0)
    for kind in MODEL_INPUTS:
        assert table[kind]["n_pixels"] == pixels
        assert table[kind]["accuracy"] == pytest.approx(1 - share, abs=1e-12)
        assert table[kind]["epe"] == pytest.approx(BOUND * share, abs=1e-12)
        assert table[kind]["nonfinite_share"] == pytest.approx(share, abs=1e-12)
    check_table(table, expected_table(NanOnTheRightHalf(), frames))


def test_a_nan_pattern_that_follows_the_input_is_scored_on_the_same_pixels(frames):
    """NaN where the left view is bright: the camera inputs' left view differs from the
    renders', so the pattern differs between the inputs; all are still scored on the same
    pixels, each NaN a miss."""
    left = frames[0][0]
    threshold = float(np.median(model_image(left[0])[0]))
    model = NanWhereBright(threshold)
    expected = expected_table(model, frames)
    shares = [expected[k]["nonfinite"] / expected[k]["n"] for k in MODEL_INPUTS]
    assert 0.2 < min(shares) and max(shares) < 0.8 and shares[0] != shares[2]
    table = {r["row"]: r for r in model_rows(rows_of(model, frames), reps=50)}
    check_table(table, expected)


def test_tile_sums_score_non_finite_predictions_at_the_bound_when_asked():
    rng = np.random.default_rng(5)
    h, w, bound = 9, 11, 7.5
    d_gt = rng.uniform(0, 6, (h, w))
    d_gt[0, :3] = np.nan
    d_hat = d_gt + rng.normal(0, 1.5, (h, w))
    d_hat[rng.random((h, w)) < 0.3] = np.nan
    d_hat[rng.random((h, w)) < 0.1] = np.inf
    mask = rng.random((h, w)) < 0.8
    labels = rng.integers(0, 4, (h, w))
    got = tile_sums(d_hat, d_gt, mask, labels, conflict_shift=2, nonfinite_error=bound)
    expected = {}
    for y in range(h):
        for x in range(w):
            if not (mask[y, x] and np.isfinite(d_gt[y, x])):
                continue
            acc = expected.setdefault(labels[y, x], dict.fromkeys((*SUMS, "nonfinite"), 0))
            acc["n"] += 1
            if not np.isfinite(d_hat[y, x]):
                acc["nonfinite"] += 1
                acc["abs_error"] += bound
                continue
            err = abs(d_hat[y, x] - d_gt[y, x])
            acc["hits"] += int(err < 1)
            acc["abs_error"] += err
            acc["pulled"] += int(abs(d_hat[y, x] - d_gt[y, x] - 2) < 1)
            acc["zero"] += int(abs(d_hat[y, x]) < 0.5)
    assert got["tile"].tolist() == sorted(expected)
    for i, t in enumerate(got["tile"]):
        for s in (*SUMS, "nonfinite"):
            assert got[s][i] == pytest.approx(expected[t][s], abs=1e-9), (t, s)
    # without the bound, non-finite predictions are not scored (the learned probe's sums)
    plain = tile_sums(d_hat, d_gt, mask, labels, conflict_shift=2)
    assert "nonfinite" not in plain
    assert plain["n"].sum() == sum(e["n"] - e["nonfinite"] for e in expected.values())


# ------------------------------------------------------------------------------------------
# the job's warnings
# ------------------------------------------------------------------------------------------


def run_job(monkeypatch, model, frames, *, truth_left=TRUTH, outputs=None):
    from stereovar.jobs import probe_model

    data = {f"f{i}": (f[0], f[1], truth_left, SIGN) for i, f in enumerate(frames)}
    monkeypatch.setattr(probe_model, "frame_data", lambda stores, scene: data[scene])
    settings = {"test_frames": SETTINGS.test_frames, "batch": 8, "reps": 50, "tile": 8}
    return probe_model.probe_model_job(
        {},
        outputs or {},
        scenes=list(data),
        factory="nets:build",
        weights="w.pt",
        settings=settings,
        model=model,
    )


def warnings_of(caplog, about: str = "") -> list:
    """The warning lines logged (those holding ``about``)."""
    return [
        r.getMessage()
        for r in caplog.records
        if r.levelno == logging.WARNING and about in r.getMessage()
    ]


def test_non_finite_predictions_are_warned_in_one_line_with_their_share(
    monkeypatch, caplog, frames
):
    caplog.set_level(logging.INFO, logger="stereovar")
    record = run_job(monkeypatch, NanOnTheRightHalf(), frames)
    (line,) = warnings_of(caplog, "NaN or Inf")
    share = (W / 2) / (W - D0)
    assert line.startswith("warning: the model returned NaN or Inf disparity") and "\n" not in line
    assert ", ".join(f"{k} {100 * share:.1f} %" for k in MODEL_INPUTS) in line
    rows = {r["row"]: r for r in record["rows"]}
    assert rows["normal"]["nonfinite_share"] == pytest.approx(share, abs=1e-12)


def test_a_model_with_finite_disparity_gets_no_such_warning(monkeypatch, caplog, frames):
    caplog.set_level(logging.INFO, logger="stereovar")
    record = run_job(monkeypatch, Constant(D0), frames[:1])
    assert warnings_of(caplog, "NaN") == [] and warnings_of(caplog) != []  # (not testable)
    assert all(r["nonfinite_share"] == 0 for r in record["rows"])


def test_the_low_accuracy_warning_prints_one_percent_sign(monkeypatch, caplog, frames):
    caplog.set_level(logging.INFO, logger="stereovar")
    run_job(monkeypatch, Constant(D0 + 3), frames[:1])  # every prediction 3 px off: a miss
    (line,) = warnings_of(caplog, "under 5")
    assert "accuracy on the renders is under 5 %:" in line and "%%" not in line
    assert line.startswith("warning: ") and "\n" not in line


# ------------------------------------------------------------------------------------------
# a network the probe cannot test: warned, stored, and read as not testable
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def step_frames():
    rng = np.random.default_rng(6)
    return [frame(rng, texture=0.15, strength=1.0, step=STEP) for _ in range(2)]


def test_a_nearly_constant_network_is_warned_stored_and_read_as_not_testable(
    monkeypatch, caplog, step_frames, tmp_path
):
    caplog.set_level(logging.INFO, logger="stereovar")
    outputs = {"json": tmp_path / "probe_model.json", "md": tmp_path / "probe_model.md"}
    record = run_job(
        monkeypatch, NearlyConstant(), step_frames, truth_left=truth(STEP), outputs=outputs
    )
    (line,) = warnings_of(caplog)
    assert line.startswith("warning: the probe cannot test this network: the network's output "
                           "does not respond to its input") and "\n" not in line
    assert record["testable"] is False and record["checks"]["responds"] is False
    assert record["warnings"] == [line.removeprefix("warning: ")]
    assert record["reading"].startswith("not testable: ")
    assert "no use of the Monte Carlo cue detected" not in record["reading"]
    stored = json.loads(outputs["json"].read_text())
    assert stored["testable"] is False and stored["reading"] == record["reading"]
    rows = {r["row"]: r for r in stored["rows"]}
    assert {"constant", "over_constant"} <= set(rows)
    page = outputs["md"].read_text()
    for row in ("constant", "over_constant"):
        assert re.search(rf"^\| {row} +\|", page, re.M), page
    assert "testable no: the network's output does not respond" in page
    # the printed lines: every input beside the best constant
    header, *inputs = record["lines"]
    assert "best constant" in header and [s.split()[0] for s in inputs] == list(MODEL_INPUTS)
    c = rows["constant"]
    assert all(s.endswith(f"{100 * c['accuracy']:.1f} % {c['epe']:8.3f}") for s in inputs)


def test_a_network_that_matches_gets_no_warning(monkeypatch, caplog, step_frames):
    caplog.set_level(logging.INFO, logger="stereovar")
    net = CleanNet(candidates=D0 + STEP + 3).eval()
    record = run_job(monkeypatch, net, step_frames, truth_left=truth(STEP))
    assert warnings_of(caplog) == []
    assert record["testable"] is True and record["warnings"] == []
    assert record["checks"]["mean_change_px"] == pytest.approx(2.0, abs=0.1)
    assert not record["reading"].startswith("not testable")
