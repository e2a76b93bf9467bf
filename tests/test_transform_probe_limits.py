"""Inputs past what the camera model, the store transforms and the learned probe can hold, and
the conda post-deploy script's requirement: each is refused in one line naming the setting
and the fix, or handled by a documented law, never run as code, never left to hang."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from stereovar.config import validate_config
from stereovar.controls.sensor import SensorFrames, SensorModel
from stereovar.errors import ConfigError, MatcherFileError, StoreError
from stereovar.transforms import TransformInputs, get_transform

REPO = Path(__file__).resolve().parents[1]
POST_DEPLOY = REPO / "envs" / "stereovar.post-deploy.sh"
SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"


# --- the conda post-deploy script ------------------------------------------------------------


def _post_deploy(tmp_path, requirement) -> subprocess.CompletedProcess:
    """Run the post-deploy script with ``requirement``; ``python -m pip`` is a stub that
    installs nothing, every other ``python`` call is this interpreter (stereovar installed)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    stub = bin_dir / "python"
    stub.write_text(
        "#!/bin/sh\n"
        'if [ "$1" = "-m" ] && [ "$2" = "pip" ]; then exit 0; fi\n'
        f'exec {shlex.quote(sys.executable)} "$@"\n'
    )
    stub.chmod(0o755)
    env = {
        "PATH": f"{bin_dir}{os.pathsep}/usr/bin{os.pathsep}/bin",
        "HOME": str(tmp_path),
        "STEREOVAR_REQUIREMENT": requirement,
    }
    return subprocess.run(
        ["bash", str(POST_DEPLOY)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


def test_post_deploy_never_runs_the_requirement_as_python(tmp_path):
    requirement = '/srv/x{__import__("os").system("id > INJECTED")}y'
    proc = _post_deploy(tmp_path, requirement)
    assert not (tmp_path / "INJECTED").exists()
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.endswith(f"installed from {requirement}\n")


def test_post_deploy_takes_a_checkout_path_with_a_quote(tmp_path):
    requirement = "/home/o'brien/stereovar"
    proc = _post_deploy(tmp_path, requirement)
    assert proc.returncode == 0, proc.stderr
    import stereovar

    assert proc.stdout == f"stereovar {stereovar.__version__} installed from {requirement}\n"


# --- the camera model on very bright pixels --------------------------------------------------


def _inputs(seed_mean, *, render=None, seed_var=None, rng_seed=7) -> TransformInputs:
    seed_mean = np.asarray(seed_mean, dtype=np.float64)
    return TransformInputs(
        render=(seed_mean if render is None else render).astype(np.float32),
        view="left",
        seed_index=0,
        rng_seed=rng_seed,
        seed_mean=seed_mean,
        seed_var=seed_var,
        n_seeds=None if seed_var is None else 4,
    )


def test_sensor_only_gives_a_very_bright_pixel_its_value_and_keeps_the_other_draws():
    mean = np.full((3, 4, 3), 0.5)
    bright = mean.copy()
    bright[1, 2, 0] = 1e20  # 1e23 electrons at the default gain: past numpy's Poisson sampler
    dark = mean.copy()
    dark[1, 2, 0] = 0.0
    sensor_only = get_transform("sensor_only")
    out = sensor_only(_inputs(bright))
    assert np.isfinite(out).all()
    # shot noise sqrt(1e23) / 1000 = 3e8 is far below float32's spacing at 1e20 (9e12)
    assert out[1, 2, 0] == np.float32(1e20)
    others = np.ones(mean.shape, bool)
    others[1, 2, 0] = False
    np.testing.assert_array_equal(out[others], sensor_only(_inputs(dark))[others])


def test_counts_above_the_exact_range_have_the_poisson_mean_and_variance():
    from stereovar.controls.sensor import normal_counts, photon_counts

    # 1e20 electrons, past numpy's exact sampler: sd 1e10, resolved in float64
    lam = np.full(30_000, 1e20)
    exact, large = photon_counts(lam, np.random.default_rng(5))
    counts = normal_counts(lam, large, np.random.default_rng(6))
    assert large.all() and not exact.any()
    # 30 000 draws: the sample mean within 5 standard errors, the sd within 4 %
    sd = np.sqrt(1e20)
    assert abs(counts.mean() - 1e20) < 5 * sd / np.sqrt(counts.size)
    assert counts.std(ddof=1) == pytest.approx(sd, rel=0.04)
    # the frames, gain 1 and 4e12 electrons: Var = lambda + r^2 in electrons^2
    frame = SensorFrames(np.full((100, 100, 3), 4e12), 1, SensorModel(gain=1.0), seed=3)[0]
    values = frame.astype(np.float64).ravel()
    sd = np.sqrt(4e12 + 4.0)
    assert abs(values.mean() - 4e12) < 5 * sd / np.sqrt(values.size)
    assert values.std(ddof=1) == pytest.approx(sd, rel=0.04)


# --- extreme camera settings -----------------------------------------------------------------


def _one_line(err) -> str:
    message = str(err.value)
    assert "\n" not in message
    return message


def test_the_config_bounds_the_camera_to_settings_whose_frames_are_finite():
    from stereovar.controls.sensor import GAIN_RANGE, READ_NOISE_MAX

    with pytest.raises(ConfigError) as err:
        validate_config({"controls": {"sensor": {"gain": 1e-300}}}, SCHEMA)
    assert "controls.sensor.gain" in _one_line(err)
    with pytest.raises(ConfigError) as err:
        validate_config({"controls": {"sensor": {"read_noise": 1e300}}}, SCHEMA)
    assert "controls.sensor.read_noise" in _one_line(err)
    with pytest.raises(ConfigError, match="controls.sensor.gain"):
        validate_config({"controls": {"sensor": {"gain": GAIN_RANGE[1] * 10}}}, SCHEMA)
    # every corner of the bounds is accepted, and gives finite frames and equalised renders
    rng = np.random.default_rng(0)
    mean = rng.uniform(0.0, 1e4, (4, 5, 3))
    mean[0, 0] = np.finfo(np.float32).max / 2  # the brightest a float32 render's mean gets
    render = mean + rng.normal(0.0, 1.0, mean.shape)
    var = np.full(mean.shape, 1.0)
    for gain in GAIN_RANGE:
        for read_noise in (0.0, READ_NOISE_MAX):
            sensor = {"gain": gain, "read_noise": read_noise}
            assert validate_config({"controls": {"sensor": sensor}}, SCHEMA)["controls"][
                "sensor"
            ] == {**sensor, "seed": 0}
            inputs = _inputs(mean, render=render, seed_var=var)
            for name in ("sensor_only", "equalise"):
                assert np.isfinite(get_transform(name)(inputs, **sensor)).all(), (name, sensor)


GAIN_FIX = "keep controls.sensor.gain within [0.001, 1e+07]"
READ_NOISE_FIX = "keep controls.sensor.read_noise within [0, 1000]"


@pytest.mark.parametrize(
    "name, sensor, camera, fix",
    [
        ("sensor_only", {"gain": 1e-300}, "gain 1e-300 e-/unit and read_noise 2 e-", GAIN_FIX),
        ("sensor_only", {"read_noise": 1e300}, "gain 1000 e-/unit and read_noise 1e+300 e-",
         READ_NOISE_FIX),
        ("equalise", {"gain": 1e-300}, "gain 1e-300 e-/unit and read_noise 2 e-", GAIN_FIX),
        ("equalise", {"read_noise": 1e300}, "gain 1000 e-/unit and read_noise 1e+300 e-",
         READ_NOISE_FIX),
    ],
)
def test_a_transform_refuses_a_non_finite_output_naming_itself_and_the_camera(
    name, sensor, camera, fix
):
    mean = np.full((2, 3, 3), 0.5)
    inputs = _inputs(mean, render=mean + 0.1, seed_var=np.full(mean.shape, 0.01))
    with pytest.raises(ConfigError) as err:
        get_transform(name)(inputs, **sensor)
    message = _one_line(err)
    assert message.startswith(f"transform '{name}' with {camera} gives ")
    # only the setting past its bounds is named
    largest = 0.5 if name == "sensor_only" else 0.6  # its input: the seed mean, the render
    assert message.endswith(f" from finite input (largest input {largest}); {fix}"), message


@pytest.mark.parametrize("name", ["sensor_only", "equalise"])
def test_an_input_past_float32_is_named_as_the_cause_and_not_the_camera(name):
    mean = np.full((2, 3, 3), 0.5)
    mean[1, 1, 2] = 1e300  # the camera is the default, within its bounds
    render = np.full(mean.shape, 0.6)
    inputs = _inputs(mean, render=render, seed_var=np.full(mean.shape, 0.01))
    with pytest.raises(ConfigError) as err:
        get_transform(name)(inputs)
    assert _one_line(err) == (
        f"transform '{name}' with gain 1000 e-/unit and read_noise 2 e- gives 1 non-finite "
        "value from finite input (largest input 1e+300); keep the input within float32's "
        "range (magnitude at most 3.40282e+38)"
    )


# --- the learned probe: a diverged network, a network path that is not a file ----------------


def _torch():
    """PyTorch, or a skip: the probe is the ``probe`` extra, and without it the other tests
    of this module still run."""
    return pytest.importorskip("torch", reason="the probe extra (PyTorch) is not installed")


def _tiny_frame():
    """A 16x48 random texture and its copy shifted by 3 px (sign -1): a frame crops of 4x16
    features fit."""
    from stereovar.probe.training import TrainingFrame

    d, height, width = 3, 16, 48
    t = np.random.default_rng(0).normal(size=(height, width + d)).astype(np.float32)
    disparity = np.full((height, width), float(d), np.float32)
    return TrainingFrame(t[:, d:], t[:, :width], disparity, -1)  # right(x - 3) = left(x)


TINY_TRAINING = {"steps": 4, "crops": 1, "crop_rows": 4, "crop_cols": 16}


def test_training_refuses_a_diverging_loss_with_the_step_and_the_fix():
    _torch()
    from stereovar.probe.training import TrainSettings, train_matcher

    with pytest.raises(ConfigError, match="probe.training.learning_rate"):
        validate_config({"probe": {"training": {"learning_rate": 1e30}}}, SCHEMA)
    settings = TrainSettings(**TINY_TRAINING, learning_rate=1e30)
    with pytest.raises(ConfigError) as err:
        train_matcher([_tiny_frame()], settings, seed=0)
    message = _one_line(err)
    # step 1 scores the finite initial weights; Adam's first update moves every weight by
    # about the learning rate, 1e30, so step 2's four layers overflow float32 to NaN
    assert "at step 2 the loss is nan" in message
    assert "lower probe.training.learning_rate (now 1e+30, default 0.001)" in message
    # a learning rate that does not diverge trains as before
    net, history = train_matcher([_tiny_frame()], TrainSettings(**TINY_TRAINING), seed=0)
    assert np.isfinite(history["loss"]).all()


def _nan_network():
    """A probe network whose first bias is NaN, and its training settings."""
    from stereovar.probe.network import MatchingNet
    from stereovar.probe.training import TrainSettings

    net = MatchingNet(features=4, layers=2)
    with _torch().no_grad():
        net.body[0].bias[1] = float("nan")
    return net, TrainSettings(**TINY_TRAINING)


def test_a_network_with_nan_weights_is_neither_saved_nor_loaded(tmp_path, monkeypatch):
    _torch()
    from stereovar.probe import training

    net, settings = _nan_network()
    path = tmp_path / "net.pt"
    with pytest.raises(ConfigError) as err:
        training.save_matcher(path, net, settings=settings, seed=0, meta={"condition": "none"})
    message = _one_line(err)
    assert str(path) in message and "body.0.bias" in message and "learning_rate" in message
    assert not any(tmp_path.iterdir())
    # the same network written by save_matcher itself with its weights check switched off
    # (what a version without the check, or a file edited afterwards, leaves)
    with monkeypatch.context() as m:
        m.setattr(training, "nonfinite_weights", lambda net: None)
        training.save_matcher(path, net, settings=settings, seed=0, meta={"condition": "none"})
    with pytest.raises(ValueError) as err:
        training.load_matcher(path)
    assert isinstance(err.value, StoreError)  # a job reports it in one line
    assert _one_line(err) == (
        f"{path}: the probe network's weights body.0.bias are NaN or Inf (its training "
        "diverged); delete it and rerun the probe with a lower probe.training.learning_rate"
    )


def test_load_matcher_refuses_a_fifo_and_a_folder_without_waiting(tmp_path):
    _torch()
    from stereovar.probe.training import load_matcher

    fifo = tmp_path / "net.pt"
    os.mkfifo(fifo)
    outcome = []

    def load():
        try:
            load_matcher(fifo)
        except Exception as err:  # noqa: BLE001 - the test inspects it
            outcome.append(err)

    worker = threading.Thread(target=load, daemon=True)
    worker.start()
    worker.join(5)
    if worker.is_alive():  # it opened the FIFO and waits for a writer: give it end of file
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        worker.join(5)
        pytest.fail("load_matcher waited on a FIFO")
    (err,) = outcome
    assert isinstance(err, MatcherFileError)  # from stereovar.errors
    assert isinstance(err, ValueError) and isinstance(err, StoreError)
    # the kinds in the words every reader of the project uses
    assert str(err) == (
        f"{fifo}: not a regular file (a named pipe), so not a probe network; remove it and "
        "rerun the probe to train the network"
    )
    with pytest.raises(MatcherFileError) as err:
        load_matcher(tmp_path)
    assert _one_line(err) == (
        f"{tmp_path}: not a regular file (a directory), so not a probe network; remove it and "
        "rerun the probe to train the network"
    )


def test_load_matcher_reads_the_file_it_checked(tmp_path, monkeypatch):
    """A path looked at as a regular file and then replaced by a named pipe: the file is
    checked on the descriptor torch reads, so nothing waits on the pipe."""
    torch = _torch()
    from stereovar.probe.network import MatchingNet
    from stereovar.probe.training import TrainSettings, load_matcher, save_matcher

    net = MatchingNet(features=4, layers=2)
    path = save_matcher(tmp_path / "net.pt", net, settings=TrainSettings(**TINY_TRAINING),
                        seed=0, meta={"condition": "none"})
    real_stat, swapped = os.stat, []

    def stat_then_swap(target, *args, **kwargs):
        result = real_stat(target, *args, **kwargs)
        if os.fspath(target) == str(path) and not swapped:  # another process swaps it
            swapped.append(True)
            path.rename(tmp_path / "kept.pt")
            os.mkfifo(path)
        return result

    monkeypatch.setattr(os, "stat", stat_then_swap)
    outcome = []

    def load():
        try:
            outcome.append(load_matcher(path))
        except Exception as err:  # noqa: BLE001 - the test inspects it
            outcome.append(err)

    worker = threading.Thread(target=load, daemon=True)
    worker.start()
    worker.join(5)
    if worker.is_alive():
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        worker.join(5)
        pytest.fail("load_matcher looked at the file, then opened the named pipe put there")
    (result,) = outcome
    if swapped:  # it was swapped after a look that the open did not repeat: refused
        assert isinstance(result, MatcherFileError) and "(a named pipe)" in str(result)
    else:  # never looked at by path: the network it opened
        loaded, _ = result
        for name, value in net.state_dict().items():
            assert torch.equal(loaded.state_dict()[name], value), name
