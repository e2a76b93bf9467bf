"""``stereovar sample``: a data set of one render per view gets a re-render plan (its frame
count for a stated power, from the power curve at N = 2 on its own frames), and the plan's
Blender command, run on Blender's factory scene, renders what the sample's audit imports.

Files: written by Blender itself (the ``bpy`` module of the ``cycles`` extra) on its factory
scene, 64 x 48 px, 8 SPP, the camera zoomed to a 120 mm lens (as
``tests/test_audit_formats_blender_snippet.py``)."""

import math
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest
import yaml

from stereovar.audit.importer import import_audit
from stereovar.audit.sample import PowerPoint, frames_for_power, power_at, single_render_frames
from stereovar.cli import main
from stereovar.errors import AuditError

SNIPPET = Path(__file__).parents[1] / "workflow" / "snippets" / "render_seeds.py"
WIDTH, HEIGHT, LENS_MM, SENSOR_MM, BASELINE_M = 64, 48, 120.0, 36.0, 0.2
FOCAL = LENS_MM / SENSOR_MM * WIDTH

SETUP = f"""
import bpy
bpy.ops.wm.read_factory_settings(use_empty=False)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.render.resolution_x, scene.render.resolution_y = {WIDTH}, {HEIGHT}
scene.render.resolution_percentage = 100
scene.cycles.samples = 8
scene.cycles.device = "CPU"
scene.cycles.use_denoising = True
scene.camera.data.lens = {LENS_MM}
"""

DATA_SET = SETUP + f"""
import runpy, sys
out, blend = sys.argv[1], sys.argv[2]
bpy.ops.wm.save_as_mainfile(filepath=blend)  # the frame's scene, as a team keeps it
sys.argv = ["render_seeds.py", "--", out, "1", "{BASELINE_M}"]
runpy.run_path({str(SNIPPET)!r}, run_name="__main__")
"""

RUN_PLAN = """
import runpy, shlex, sys
import bpy
blend, command = sys.argv[1], shlex.split(sys.argv[2])
bpy.ops.wm.open_mainfile(filepath=blend)
script = command[command.index("-P") + 1]
sys.argv = [script, *command[command.index("--"):]]
runpy.run_path(script, run_name="__main__")
"""


def _python(code, *args):
    done = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True,
                          text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.skipif(find_spec("bpy") is None, reason="needs the cycles extra (bpy)")
def test_a_one_render_data_set_gets_a_plan_whose_blender_command_audits(tmp_path,
                                                                        monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scenes").mkdir()
    for frame in ("f0", "f1", "f2"):  # three frames of one render per view
        _python(DATA_SET, tmp_path / "data" / frame, tmp_path / "scenes" / f"{frame}.blend")
    settings = {"name": "team", "renders": "data/{frame}/{view}/seed_000.exr",
                "views": {"left": "L", "right": "R"},
                "depth": "data/{frame}/{view}/seed_000.exr", "focal_px": FOCAL,
                "baseline_m": BASELINE_M, "convention": "conventional", "spp": 8}
    (tmp_path / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
    assert list(single_render_frames({**settings, "root": str(tmp_path)})) == ["f0", "f1", "f2"]
    rc = main(["sample", "audit.yaml", "--blend", "scenes/{frame}.blend", "--out", "plan",
               "--replicates", "4", "--probe-frames", "1"])
    assert rc == 0
    said = capsys.readouterr().err
    record = yaml.safe_load((tmp_path / "plan/plan.yaml").read_text())
    assert record["frames_in_data_set"] == 3
    assert record["frames_to_render"] == min(3, record["frames_needed"])
    curve = [PowerPoint(p["strength"], p["difference"], p["se"], p["power_one_frame"])
             for p in record["power_curve_n2"]["points"]]
    # the plan's power is the curve's at the frames it chose, and what it needed reaches 80%
    assert record["power"] == pytest.approx(power_at(curve, 1.0, record["frames_to_render"]))
    needed, reached = frames_for_power(curve, 1.0, 0.8)
    assert needed == record["frames_needed"] and reached >= 0.8
    assert f"render {record['frames_to_render']} of 3 frames again" in said
    # a stronger planted cue reads a larger difference
    assert curve[-1].delta > curve[0].delta
    first = record["renders"][0]
    assert first["command"].startswith(f"blender -b {tmp_path / 'scenes'}/")
    assert "render_seeds.py -- " in first["command"] and first["command"].endswith(
        f" 2 {BASELINE_M!r}")
    assert (tmp_path / "plan/render_seeds.py").read_text() == SNIPPET.read_text()
    script = (tmp_path / "plan/render.sh").read_text()
    assert first["command"] in script and "stereovar audit" in script
    # run the plan's first command on its scene, then import the sample's audit
    _python(RUN_PLAN, first["blend"], first["command"])
    sample = yaml.safe_load((tmp_path / "plan/audit.yaml").read_text())["audit"]
    report = import_audit(sample)
    assert report.discovery.summary() == "1 frame × 2 views × 2 seeds"
    (fr,) = report.frames
    assert fr.sign["conclusive"] and fr.sign["error"] < 0.5 * fr.sign["opposite_error"]
    frame_dir = tmp_path / "plan" / "renders" / first["frame"]
    assert (frame_dir / "audit_noisy.yaml").is_file()  # the denoiser is on: before it, too


def test_a_cue_below_what_n2_shows_is_refused_with_the_strength_that_can(tmp_path):
    """No frame count detects a cue whose difference does not exceed the rule's minimum;
    the plan names the weakest strength that can be detected."""
    from stereovar.audit import sample

    curve = [PowerPoint(0.125, 0.01, 0.005, 0.0), PowerPoint(0.5, 0.2, 0.006, 1.0)]
    assert frames_for_power(curve, 0.125, 0.8) == (None, 0.0)
    assert frames_for_power(curve, 0.5, 0.8)[0] == 1
    # between the points the difference and its error interpolate in log strength
    frames, achieved = frames_for_power(curve, 0.25, 0.8)
    delta = 0.01 + (0.2 - 0.01) * math.log(2) / math.log(4)
    se = 0.005 + 0.001 * math.log(2) / math.log(4)
    expected = math.ceil(((1.959964 + 0.841621) * se / (delta - 0.05)) ** 2)
    assert frames == expected and achieved >= 0.8
    settings = {"renders": "nothing/{frame}_{view}.exr", "root": str(tmp_path)}
    with pytest.raises(AuditError, match="matches no file"):
        sample.single_render_frames(settings)
    assert np.isfinite(achieved)


@pytest.mark.parametrize(
    ("audit", "message"),
    [
        (None, "no such config file"),
        ({"name": "x"}, "has no audit: section with renders"),
        ({"renders": "d/{frame}_{view}.exr"}, "has no baseline_m"),
        ({"renders": "d/{frame}_{view}.exr", "baseline_m": 0.1}, "matches no file"),
    ],
)
def test_bad_input_is_one_line_before_any_work(tmp_path, monkeypatch, capsys, audit, message):
    monkeypatch.chdir(tmp_path)
    if audit is not None:
        (tmp_path / "audit.yaml").write_text(yaml.safe_dump({"audit": audit}))
    assert main(["sample", "audit.yaml"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("stereovar: error:") and message in line
    assert not (tmp_path / "sample_plan").exists()
