"""The probe experiment's data: counterfactual inputs that keep one render's noise variance,
cue-blind twin frames, the validation split, the camera law and the planted conditions."""

from __future__ import annotations

import numpy as np
import pytest

from stereovar.errors import ConfigError
from stereovar.probe import experiment
from stereovar.probe.conditions import check_probe, planted_factor, probe_conditions
from stereovar.probe.experiment import scene_law, split_validation, training_frames
from stereovar.probe.inputs import network_input, noise_scale


def _stack(rng, n, shape=(24, 40), law=(0.02, 1e-4)):
    """N renders of a smooth clean image with noise of variance a*mu + b per channel."""
    yy, xx = np.indices(shape)
    mean = 0.2 + 0.15 * np.sin(xx / 5.0)[..., None] * np.ones(3) + 0.05 * (yy / shape[0])[
        ..., None
    ]
    sd = np.sqrt(law[0] * mean + law[1])
    return mean, mean + sd * rng.standard_normal((n, *mean.shape))


@pytest.mark.parametrize("n", [3, 6])
def test_every_counterfactual_input_holds_one_renders_noise_variance(n):
    rng = np.random.default_rng(1)
    mean, left = _stack(rng, n)
    _, right = _stack(rng, n)
    law = (0.02, 1e-4)
    settings = experiment.TestSettings(
        test_frames=n, inputs=("normal", "shuffled", "camera", "conflict")
    )
    # network_input standardises: compare the linear noise instead, through a spy on its input
    seen = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(experiment, "network_input", lambda x: x)
        pairs = experiment.test_pairs(left, right, scene="s", sign=-1, law=law, settings=settings)
    for (_, kind), (_, r) in pairs.items():
        seen.setdefault(kind, []).append(r - mean)
    expected = law[0] * mean + law[1]
    for kind, noise in seen.items():
        ratio = np.mean(np.stack(noise) ** 2) / expected.mean()
        # n frames x 24 x 40 x 3 values: the ratio's standard error is under 3%
        assert ratio == pytest.approx(1.0, abs=0.1), kind


def test_noise_scale_balances_a_leave_one_out_reference():
    for m in (2, 5, 29):
        c = noise_scale(m, residual=True)
        assert c**2 * (1 + 1 / m) + 1 / m == pytest.approx(1.0)
        c = noise_scale(m, residual=False)
        assert c**2 + 1 / m == pytest.approx(1.0)
    with pytest.raises(ValueError):
        noise_scale(0, residual=True)


def test_twin_frames_keep_the_left_and_redraw_the_right():
    rng = np.random.default_rng(2)
    _, left = _stack(rng, 4)
    _, right = _stack(rng, 4)
    truth = {"disparity": np.full(left.shape[1:3], 2.0), "valid": np.ones(left.shape[1:3], bool)}
    plain = training_frames(left, right, truth, sign=-1)
    twin = training_frames(left, right, truth, sign=-1, twin=True, strata=4)
    g = np.random.default_rng(0)
    for p, t in zip(plain, twin, strict=True):
        assert np.array_equal(p.left, t.left)
        assert p.redraw is None
        a, b = t.right_input(g), t.right_input(g)
        assert a.shape == p.right.shape and not np.array_equal(a, b)
        # the redraw is a shuffle of the same residual: the same pixel values, moved
        assert not np.allclose(a, p.right)
    np.testing.assert_allclose(
        plain[0].right, network_input(right[0]), rtol=0, atol=0
    )


def test_split_validation_holds_out_the_last_frame_of_each_scene():
    train, validation = split_validation([["a0", "a1", "a2"], ["b0", "b1"], ["c0"]])
    assert validation == ["a2", "b1"]
    assert train == ["a0", "a1", "b0", "c0"]


def test_scene_law_is_one_renders_variance():
    rng = np.random.default_rng(3)
    truth = (0.03, 2e-4)
    _, stack = _stack(rng, 4, shape=(60, 80), law=truth)
    a, b = scene_law(stack)
    # the biased Eq. 1 field alone would give (N-1)/N = 0.75 of the slope
    assert a == pytest.approx(truth[0], rel=0.1)
    with pytest.raises(ValueError, match="N >= 2"):
        scene_law(stack[:1])


def test_planted_conditions_and_their_names():
    cfg = {
        "render": {"renderer": "mitsuba", "spp": 4},
        "scenes": ["a", "b"],
        "mitigations": {"names": []},
        "probe": {"conditions": ["none", "sensor_only"], "planted": [0.5, 2], "mitigations": []},
    }
    names = [c.name for c in probe_conditions(cfg)]
    assert names == ["none", "sensor_only", "planted_x0.5", "planted_x2"]
    assert [planted_factor(n) for n in names] == [None, None, 0.5, 2.0]
    cfg["probe"]["planted"] = [0]
    with pytest.raises(ConfigError, match="probe.planted"):
        probe_conditions(cfg)


def test_an_architectures_planted_series_and_the_judged_mitigations():
    """probe.planted_series: factors one architecture trains beside probe.planted;
    probe.mitigations: conditions trained with their own twin (the control too)."""
    cfg = {
        "render": {"renderer": "mitsuba", "spp": 4},
        "scenes": ["a", "b"],
        "mitigations": {"names": []},
        "probe": {"planted": [1], "planted_series": {"costvolume": [1, 2, 8], "mccnn": [4]},
                  "architectures": ["mccnn", "costvolume"], "mitigations": ["denoise"]},
    }
    conditions = {c.name: c for c in probe_conditions(cfg)}
    assert list(conditions) == ["none", "sensor_only", "denoise", "planted_x1", "planted_x2",
                                "planted_x8", "planted_x4"]
    trains = {name: [a for a in ("mccnn", "costvolume") if c.trains(a)]
              for name, c in conditions.items()}
    assert trains["planted_x1"] == ["mccnn", "costvolume"]  # probe.planted: every one
    assert trains["planted_x2"] == trains["planted_x8"] == ["costvolume"]
    assert trains["planted_x4"] == ["mccnn"]
    assert conditions["denoise"].variants == ("main", "twin")
    assert conditions["sensor_only"].variants == ("main",)  # not judged: the control alone
    # a judged seed-mean mitigation trains on what it ships, from none's renders, with its
    # twin; the control it is stays as it was
    cfg["probe"]["mitigations"] = ["sensor_only", "equalise"]
    conditions = {c.name: c for c in probe_conditions(cfg)}
    assert conditions["sensor_only"].variants == ("main",)
    assert "equalise" not in conditions  # only its shipped condition trains
    for name in ("sensor_only", "equalise"):
        shipped = conditions[f"{name}_shipped"]
        assert (shipped.shipped, shipped.run.name, shipped.variants) == (
            name, "none", ("main", "twin"))
    with pytest.raises(ConfigError, match=r"needs 8 renders per view.*there are 6") as info:
        check_probe(cfg, 6)
    assert "\n" not in str(info.value) and "probe.mitigations" in str(info.value)
    check_probe(cfg, 8)
    cfg["probe"]["architectures"] = ["mccnn"]  # a series of an architecture not trained
    assert "planted_x8" not in {c.name for c in probe_conditions(cfg)}
    cfg["probe"]["mitigations"] = ["none"]
    with pytest.raises(ConfigError, match="probe.mitigations.*baseline") as info:
        probe_conditions(cfg)
    assert "\n" not in str(info.value)
    cfg["probe"]["mitigations"] = ["blur"]
    with pytest.raises(ConfigError, match="'probe.mitigations': unknown mitigation 'blur'"):
        probe_conditions(cfg)


def test_the_probe_refuses_too_few_renders_and_a_missing_gpu_in_one_line(monkeypatch):
    import torch

    from stereovar.probe.conditions import check_probe

    check_probe({"probe": {"device": "cpu"}}, 4)
    with pytest.raises(ConfigError, match=r"render.n_seeds .* is 3: .*at least 4") as info:
        check_probe({"probe": {"device": "cpu"}}, 3)
    assert "\n" not in str(info.value) and "50%" in str(info.value)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    with pytest.raises(ConfigError, match="probe.device.*no CUDA GPU") as info:
        check_probe({"probe": {"device": "cuda"}}, 8)
    assert "\n" not in str(info.value)


def test_channel_correlation_of_renders_and_of_independent_noise():
    rng = np.random.default_rng(5)
    mean = np.full((40, 40, 3), 0.4)
    for rho in (0.0, 0.5, 0.9):
        shared = rng.standard_normal((8, 40, 40, 1))
        own = rng.standard_normal((8, 40, 40, 3))
        stack = mean + 0.05 * (np.sqrt(rho) * shared + np.sqrt(1 - rho) * own)
        # 12 800 pixel variances of 8 draws: the estimate is good to a few hundredths
        assert experiment.channel_correlation(stack) == pytest.approx(rho, abs=0.05)


def test_the_verdict_names_the_networks_the_cap_stopped():
    from stereovar.jobs.probe import _caveats

    def row(arch, training, variant, networks, at_cap):
        return {"architecture": arch, "training": training, "variant": variant,
                "networks": networks, "at_cap": at_cap}

    trained = [row("mccnn", "none", "main", 6, 2), row("mccnn", "none", "twin", 6, 0),
               row("costvolume", "planted_x4", "main", 6, 1),
               row("costvolume", "none", "main", 6, 0)]
    text = _caveats(trained, None)
    assert "3 of the 18 networks stopped at the step cap" in text
    assert "mccnn none 2 of 6; costvolume planted_x4 1 of 6" in text
    assert "costvolume none" not in text
    assert "collapsed" not in text
    assert _caveats([row("mccnn", "none", "main", 6, 0)], None) == ""
    collapsed = {**row("costvolume", "none", "main", 6, 0), "collapsed": 2}
    text = _caveats([collapsed], None)
    assert ("2 networks never predicted a validation pixel within 1 px (costvolume none 2 of 6)"
            in text)


def test_the_training_table_counts_each_network_once_by_how_it_stopped(monkeypatch):
    """A network that never predicted a validation pixel within 1 px is ``collapsed``, not
    on a plateau and not at the cap, however many steps it ran; a twin is none of the three."""
    import stereovar.probe.training as training
    from stereovar.jobs.probe import training_rows

    def record(seed, steps, accuracies, *, variant="main", matched=False):
        checks = [[50 * (i + 1), a] for i, a in enumerate(accuracies)]
        meta = {"condition": "none", "architecture": "costvolume", "variant": variant,
                "fold": 0, "steps": steps, "cap": 400, "seconds": 1.0,
                "best_step": checks[-1][0] if checks else None, "validation": checks}
        if matched:
            meta["matched_steps"] = steps
        return {"seed": seed, "meta": meta}

    records = {
        "plateau": record(0, 200, [0.5, 0.7, 0.7, 0.7]),
        "cap": record(1, 400, [0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.92, 0.95]),
        "collapsed early": record(2, 150, [0.0, 0.0, 0.0]),
        "collapsed at the cap": record(3, 400, [0.0] * 8),
        "twin": record(0, 200, [], variant="twin", matched=True),
    }
    monkeypatch.setattr(training, "load_matcher", lambda path: (None, records[path]))
    rows = {r["variant"]: r for r in training_rows(list(records))}
    main = rows["main"]
    assert (main["networks"], main["plateau"], main["at_cap"], main["collapsed"]) == (4, 1, 1, 2)
    assert main["each"] == ("f0/s0: 200 (200), f0/s1: 400 (400) cap, "
                            "f0/s2: 150 (150) collapsed, f0/s3: 400 (400) collapsed")
    twin = rows["twin"]
    assert (twin["plateau"], twin["at_cap"], twin["collapsed"]) == (0, 0, 0)


def test_shipped_images_each_come_from_their_own_group_of_seeds(tmp_path):
    """A shipped condition's images (jobs.probe._condition_data): one per disjoint pair of
    renders, each built from its own pair's seed mean. Renders whose pair g reads g + 1
    everywhere, through sensor_only at a camera of negligible noise: image g reads g + 1."""
    import xarray as xr

    from stereovar.io.renders import render_dataset
    from stereovar.io.store import write_dataset
    from stereovar.jobs.probe import _condition_data

    n, h, w = 8, 6, 10
    renders = np.repeat(np.arange(1, n // 2 + 1, dtype=np.float32), 2)[:, None, None, None]
    renders = np.broadcast_to(renders, (n, h, w, 3)).copy()
    stores = {}
    for view in ("left", "right"):
        path = tmp_path / f"{view}.zarr"
        write_dataset(render_dataset(renders, view=view, seeds=list(range(n)),
                                     sampler_seeds=list(range(n)), attrs={}), path)
        stores[f"{view}_s"] = [str(path)]  # a view's render stores
    gt = tmp_path / "gt.zarr"
    zeros = np.zeros((2, h, w))
    write_dataset(xr.Dataset(
        {"disparity": (("view", "y", "x"), zeros), "valid": (("view", "y", "x"), zeros > -1),
         "glass": (("view", "y", "x"), zeros > 0)},
        coords={"view": ["left", "right"], "y": np.arange(h), "x": np.arange(w)},
        attrs={"disparity_sign": 1}), gt)
    stores["gt_s"] = str(gt)
    camera = {"gain": 1e9, "read_noise": 0.0}  # photon noise ~1e-4.5 of the signal
    left, right, _, _, law = _condition_data(
        stores, "s", factor=None, planted=None, seed_key=0,
        shipped={"transform": "sensor_only", "options": camera})
    assert left.shape == right.shape == (n // 2, h, w, 3) and law is None
    for g in range(n // 2):
        assert np.allclose(left[g], g + 1, rtol=1e-3) and np.allclose(right[g], g + 1, rtol=1e-3)
