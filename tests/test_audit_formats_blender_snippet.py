"""The documentation's Blender snippet (``workflow/snippets/render_seeds.py``) renders N seeds per
view with Cycles and writes what ``stereovar audit`` reads.

Files: written by Blender itself (the ``bpy`` module of the ``cycles`` extra) running the
snippet on Blender's factory scene (the default cube, its camera zoomed to a 120 mm lens so
that the cube fills most of the image), 64 x 48 px, 8 SPP, 2 seeds per view.
"""

import math
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest
import yaml

from stereovar.audit.importer import import_audit
from stereovar.io.images import read_image

from .audit_formats import stores

SNIPPET = Path(__file__).parents[1] / "workflow" / "snippets" / "render_seeds.py"
WIDTH, HEIGHT, LENS_MM, SENSOR_MM, BASELINE_M = 64, 48, 120.0, 36.0, 0.2
CAMERA = (7.3589, -6.9258, 4.9583)
"""Where Blender's factory scene puts its camera (the cube, 2 m wide, sits at the origin)."""

RUN = f"""
import runpy, sys
import bpy
bpy.ops.wm.read_factory_settings(use_empty=False)
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y = {WIDTH}, {HEIGHT}
scene.render.resolution_percentage = 100
scene.cycles.samples = 8
scene.cycles.device = "CPU"
scene.camera.data.lens = {LENS_MM}
scene.cycles.use_denoising = True  # the snippet keeps the render before the denoiser too
sys.argv = ["render_seeds.py", "--", sys.argv[1], "2", "{BASELINE_M}"]
runpy.run_path({str(SNIPPET)!r}, run_name="__main__")
"""


@pytest.mark.skipif(find_spec("bpy") is None, reason="needs the cycles extra (bpy)")
def test_the_docs_blender_snippet_writes_an_audit_that_imports(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "cube"
    done = subprocess.run([sys.executable, "-c", RUN, str(out)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    settings = yaml.safe_load((out / "audit.yaml").read_text())["audit"]
    focal = LENS_MM / SENSOR_MM * WIDTH  # the sensor width spans the wider side
    assert settings["focal_px"] == pytest.approx(focal, rel=1e-12)
    report = import_audit(settings)
    assert report.discovery.summary() == "1 frame × 2 views × 2 seeds"
    (fr,) = report.frames
    # the declared rig (right camera to the image's right: x_R = x_L - d) wins clearly
    assert fr.sign["conclusive"] and fr.sign["error"] < 0.5 * fr.sign["opposite_error"]
    got = stores("cube", "frame")
    first = read_image(out / "L" / "seed_000.exr", channel="ViewLayer.Combined")
    np.testing.assert_array_equal(got["left"]["radiance"].values[0], first)
    assert not np.array_equal(got["left"]["radiance"].values[0], got["left"]["radiance"].values[1])
    left = got["ground_truth"].sel(view="left")
    z, d = left["depth"].values, left["disparity"].values
    cube = left["valid"].values & (z < 100)  # the world is Blender's 1e10
    distance = math.dist(CAMERA, (0, 0, 0))
    assert cube.mean() > 0.3
    assert (np.abs(z[cube] - distance) < math.sqrt(3)).all()  # on the cube's bounding sphere
    np.testing.assert_allclose(d[cube], focal * BASELINE_M / z[cube], rtol=1e-6)
    # the render before the denoiser, audited by audit_noisy.yaml
    noisy = yaml.safe_load((out / "audit_noisy.yaml").read_text())["audit"]
    assert noisy["channels"] == {"render": "ViewLayer.Noisy Image"}
    assert import_audit(noisy).discovery.summary() == "1 frame × 2 views × 2 seeds"
    before = stores("cube_noisy", "frame")["left"]["radiance"].values[0]
    np.testing.assert_array_equal(
        before, read_image(out / "L" / "seed_000.exr", channel="ViewLayer.Noisy Image"))
    assert np.abs(before - first).max() > 0  # the denoiser changed it
