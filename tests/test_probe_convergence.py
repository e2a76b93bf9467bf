"""Training the probe's matcher to convergence: the plateau stop rule, the best weights kept,
the twin's common random numbers, the batched prediction and the network file's kind."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from stereovar.errors import MatcherFileError  # noqa: E402
from stereovar.probe import training  # noqa: E402
from stereovar.probe.convergence import (  # noqa: E402
    Plateau,
    StopRule,
    fixed_frames,
    validation_accuracy,
)
from stereovar.probe.network import MatchingNet, predict_matcher, wta_disparity  # noqa: E402
from stereovar.probe.training import (  # noqa: E402
    TrainingFrame,
    TrainSettings,
    load_matcher,
    save_matcher,
    train_matcher,
)


def expected_stop(steps, accuracies, rule):
    """Brute force: the record checks are those that beat every earlier record by more than
    min_delta; the run stops at the first check that has ``patience`` checks since the last
    record and has reached min_steps."""
    records = []
    for i, a in enumerate(accuracies):
        if not records or a > accuracies[records[-1]] + rule.min_delta:
            records.append(i)
        last = records[-1]
        if i - last >= rule.patience and steps[i] >= rule.min_steps:
            return i, steps[last], accuracies[last]
    return None, steps[records[-1]], accuracies[records[-1]]


@pytest.mark.parametrize("trial", range(40))
def test_plateau_stops_after_patience_checks_without_a_gain(trial):
    rng = np.random.default_rng(trial)
    rule = StopRule(
        check_every=10,
        patience=int(rng.integers(1, 5)),
        min_delta=float(rng.choice([0.0, 0.01, 0.05])),
        min_steps=int(rng.choice([0, 50])),
    )
    # a rising, saturating accuracy with noise: records early, a plateau later
    steps = [10 * (k + 1) for k in range(30)]
    acc = [0.9 * (1 - np.exp(-k / 5)) + 0.02 * rng.standard_normal() for k in range(30)]
    plateau = Plateau(rule)
    stopped = None
    for i, (s, a) in enumerate(zip(steps, acc, strict=True)):
        if plateau.update(s, a):
            stopped = i
            break
    want, best_step, best_acc = expected_stop(steps, acc, rule)
    assert stopped == want
    assert plateau.best_step == best_step
    assert plateau.best_accuracy == best_acc
    seen = len(steps) if want is None else want + 1
    assert plateau.history == list(zip(steps, acc, strict=True))[:seen]


def test_stop_rule_refuses_bad_values():
    with pytest.raises(ValueError, match="patience"):
        StopRule(patience=0)
    with pytest.raises(ValueError, match="min_delta"):
        StopRule(min_delta=-0.1)
    with pytest.raises(ValueError, match="check_every"):
        TrainSettings(check_every=0)


def textured_pair(rng, height, width, disparity, *, noise=0.0):
    """A random texture seen by the right view shifted left by ``disparity`` (sign -1: right
    pixel at x - d), with independent noise on each view."""
    texture = rng.standard_normal((height, width + disparity)).astype(np.float32)
    left = texture[:, :width] + noise * rng.standard_normal((height, width))
    right = texture[:, disparity:] + noise * rng.standard_normal((height, width))
    d = np.full((height, width), float(disparity), np.float32)
    return left.astype(np.float32), right.astype(np.float32), d


def easy_frames(seed, n, *, noise):
    rng = np.random.default_rng(seed)
    return [TrainingFrame(*textured_pair(rng, 24, 72, 3, noise=noise), -1) for _ in range(n)]


SMALL = dict(crops=2, crop_rows=8, crop_cols=24, learning_rate=3e-3)


def weights(net):
    return {k: v.clone() for k, v in net.state_dict().items()}


def test_training_stops_on_a_plateau_and_keeps_the_best_weights():
    # noisy views: an untrained network already matches some pixels, training adds a few
    # points, then the accuracy wanders on a plateau
    frames = easy_frames(0, 3, noise=1.0)
    held = easy_frames(1, 2, noise=1.0)
    settings = TrainSettings(
        steps=400, check_every=5, patience=3, min_delta=0.002, min_steps=0, **SMALL
    )
    net, history = train_matcher(frames, settings, seed=2, validation=held)
    steps, best = history["steps"], history["best_step"]
    assert steps < settings.steps  # stopped before the cap
    checks = history["validation"]
    assert [s for s, _ in checks] == list(range(5, steps + 1, 5))
    assert max(a for _, a in checks) > checks[0][1] + 0.02  # it learned before the plateau
    best_acc = dict(checks)[best]
    # the stop: patience checks after the best, none of them better by min_delta
    assert steps == best + settings.patience * settings.check_every
    assert all(a <= best_acc + settings.min_delta for s, a in checks if s > best)
    assert len(history["loss"]) == steps
    # the returned weights are those of the best check: its accuracy, and a plain run of
    # best_step steps with the same seed gives the same weights
    max_d = training.validation_disparity(frames + held, settings)
    again = validation_accuracy(partial(predict_matcher, net), held, max_disparity=max_d)
    assert again == pytest.approx(best_acc, abs=1e-12)
    plain = dict(settings.__dict__, steps=best)
    at_best, _ = train_matcher(frames, TrainSettings(**plain), seed=2)
    at_end, _ = train_matcher(frames, TrainSettings(**dict(plain, steps=steps)), seed=2)
    for k, v in weights(net).items():
        torch.testing.assert_close(v, at_best.state_dict()[k], rtol=0, atol=0)
    assert any(not torch.equal(v, at_end.state_dict()[k]) for k, v in weights(net).items())


def test_training_without_validation_takes_the_cap():
    settings = TrainSettings(steps=5, **SMALL)
    _, history = train_matcher(easy_frames(0, 1, noise=0.0), settings, seed=0)
    assert history["steps"] == history["best_step"] == 5
    assert history["validation"] == []


def test_twin_draws_the_same_crops_and_offsets_as_its_network(monkeypatch):
    """A twin frame's redraw uses its own generator: the crops, offsets and triplets the
    network and its twin of one seed see are the same, only the right input differs."""
    frames = easy_frames(3, 2, noise=0.0)
    calls = []

    def redraw_of(frame):
        def redraw(rng):
            calls.append(rng)
            return (frame.right + rng.standard_normal(frame.right.shape)).astype(np.float32)

        return redraw

    twins = [
        TrainingFrame(f.left, f.right, f.disparity, f.sign, redraw=redraw_of(f)) for f in frames
    ]
    drawn = {"main": [], "twin": []}
    original = training.draw_batch

    def recording(which):
        def draw(*args, **kwargs):
            batch = original(*args, **kwargs)
            drawn[which].append(batch)
            return batch

        return draw

    settings = TrainSettings(steps=4, **SMALL)
    for which, data in (("main", frames), ("twin", twins)):
        monkeypatch.setattr(training, "draw_batch", recording(which))
        train_matcher(data, settings, seed=5)
    assert len(drawn["main"]) == len(drawn["twin"]) == 4
    assert len(calls) == 4 * settings.crops  # one redraw per crop
    assert len({id(g) for g in calls}) == 1  # one generator of its own
    for (l_m, r_m, p_m, n_m, k_m), (l_t, r_t, p_t, n_t, k_t) in zip(
        drawn["main"], drawn["twin"], strict=True
    ):
        assert torch.equal(l_m, l_t)
        assert np.array_equal(p_m, p_t) and np.array_equal(n_m, n_t)
        assert torch.equal(k_m, k_t)
        assert r_m.shape == r_t.shape and not torch.equal(r_m, r_t)
    # and a different seed draws different crops
    drawn["main"].clear()
    monkeypatch.setattr(training, "draw_batch", recording("main"))
    train_matcher(frames, settings, seed=6)
    assert not all(
        torch.equal(a[0], b[0]) for a, b in zip(drawn["main"], drawn["twin"], strict=True)
    )


def test_validation_draws_a_twin_frames_right_input_once():
    frame = easy_frames(4, 1, noise=0.0)[0]
    twin = TrainingFrame(
        frame.left,
        frame.right,
        frame.disparity,
        -1,
        redraw=lambda rng: frame.right + rng.standard_normal(frame.right.shape).astype(np.float32),
    )
    a, b = fixed_frames([twin])[0], fixed_frames([twin])[0]
    assert a.redraw is None and np.array_equal(a.right, b.right)
    assert not np.array_equal(a.right, frame.right)
    expected = frame.right + np.random.default_rng(0).standard_normal(frame.right.shape).astype(
        np.float32
    )
    np.testing.assert_array_equal(a.right, expected)


def test_predict_matcher_equals_the_per_pair_scan():
    rng = np.random.default_rng(7)
    torch.manual_seed(7)
    net = MatchingNet()
    shared = rng.standard_normal((20, 40)).astype(np.float32)
    pairs = [(shared, rng.standard_normal((20, 40)).astype(np.float32)) for _ in range(3)]
    pairs.append((rng.standard_normal((16, 30)).astype(np.float32),) * 2)  # another shape
    pairs.append((rng.standard_normal((20, 40)).astype(np.float32), shared))
    for sign in (1, -1):
        # chunks of one image each and of all images at once
        for chunk in (1, 10**9):
            got = predict_matcher(net, pairs, sign=sign, max_disparity=9, chunk_pixels=chunk)
            assert len(got) == len(pairs)
            for (a, b), d_hat in zip(pairs, got, strict=True):
                want = wta_disparity(net, a, b, sign=sign, max_disparity=9)
                assert d_hat.dtype == np.float64 and d_hat.shape == a.shape
                assert np.array_equal(np.isnan(d_hat), np.isnan(want))
                same = np.mean(d_hat[~np.isnan(want)] == want[~np.isnan(want)])
                assert same >= 0.995  # float32 sums in another order may flip a near-tie
    with pytest.raises(ValueError, match="one shape"):
        predict_matcher(net, [(shared, shared[:, :-1])], sign=1, max_disparity=3)


def test_save_and_load_keep_the_network_kind(tmp_path, monkeypatch):
    torch.manual_seed(0)
    net = MatchingNet(features=8, layers=2)
    settings = TrainSettings(steps=1)
    path = save_matcher(tmp_path / "a.pt", net, settings=settings, seed=3, meta={"x": 1})
    loaded, record = load_matcher(path)
    assert record["architecture"] == {"kind": "mccnn", "features": 8, "layers": 2, "kernel": 3}
    assert isinstance(loaded, MatchingNet) and loaded.config() == net.config()
    for k, v in net.state_dict().items():
        assert torch.equal(v, loaded.state_dict()[k])
    # a file from before the kind was recorded holds an MC-CNN
    payload = torch.load(path, weights_only=True)
    payload["architecture"].pop("kind")
    torch.save(payload, tmp_path / "old.pt")
    old, _ = load_matcher(tmp_path / "old.pt")
    assert isinstance(old, MatchingNet) and old.config() == net.config()
    # an unknown kind is refused in one line
    payload["architecture"]["kind"] = "transformer"
    torch.save(payload, tmp_path / "bad.pt")
    with pytest.raises(MatcherFileError, match="transformer"):
        load_matcher(tmp_path / "bad.pt")


class TinyCostNet(torch.nn.Module):
    """A stand-in for the cost-volume network: a config and a weight."""

    def __init__(self, *, width: int = 2):
        super().__init__()
        self.width = int(width)
        self.conv = torch.nn.Conv2d(1, self.width, 1)

    def config(self):
        return {"width": self.width}


def test_save_and_load_dispatch_on_the_costvolume_kind(tmp_path, monkeypatch):
    import sys
    import types

    module = types.ModuleType("fake_costvolume")
    module.CostVolumeNet = type("CostVolumeNet", (TinyCostNet,), {})
    monkeypatch.setitem(sys.modules, "fake_costvolume", module)
    monkeypatch.setitem(training.NETWORK_KINDS, "costvolume", "fake_costvolume:CostVolumeNet")
    net = module.CostVolumeNet(width=5)
    path = save_matcher(tmp_path / "c.pt", net, settings=TrainSettings(), seed=0, meta={})
    loaded, record = load_matcher(path)
    assert record["architecture"] == {"kind": "costvolume", "width": 5}
    assert type(loaded) is module.CostVolumeNet
    assert torch.equal(loaded.conv.weight, net.conv.weight)
    with pytest.raises(TypeError, match="not a probe network"):
        save_matcher(tmp_path / "x.pt", TinyCostNet(), settings=TrainSettings(), seed=0, meta={})
