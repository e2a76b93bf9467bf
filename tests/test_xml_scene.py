"""Scenes that point at a user's own Mitsuba XML file."""

import subprocess
import sys

import numpy as np
import pytest

from stereovar.errors import SceneError
from stereovar.geometry import focal_length_px
from stereovar.ground_truth import MATERIAL_CLASSES
from stereovar.io.store import open_dataset
from stereovar.jobs.common import prepare_scene
from stereovar.jobs.ground_truth import ground_truth_job
from stereovar.scenes.spec import load_scene_spec

XML = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world">
            <lookat origin="0.3, 1, -1" target="0.3, 1, 1" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm"><integer name="width" value="640"/>
        <integer name="height" value="360"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="10" y="10" z="1"/><rotate y="1" angle="180"/>
            <translate x="0.3" y="1" z="2"/>
        </transform>
        <bsdf type="diffuse"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.3" y="1" z="0.5"/>
        <float name="radius" value="0.3"/>
        <bsdf type="dielectric"/>
    </shape>
</scene>
"""


@pytest.fixture
def xml_scene(tmp_path):
    (tmp_path / "room.xml").write_text(XML)
    (tmp_path / "mine.yaml").write_text("name: mine\nmitsuba_xml: room.xml\n")
    return tmp_path


def test_rig_is_added_to_first_sensor_and_ground_truth_is_exact(mi, xml_scene, tmp_path):
    out = tmp_path / "gt.zarr"
    width, height, baseline = 64, 36, 0.03
    ground_truth_job(
        xml_scene / "mine.yaml",
        out,
        width=width,
        height=height,
        baseline_m=baseline,
        convention="paper",
    )
    ds = open_dataset(out).load()
    g = ds.sel(view="left")
    # The sensor looks along +z from z=-1; the wall is at z=2: planar depth 3 m.
    wall = g.material.values == MATERIAL_CLASSES.index("diffuse")
    np.testing.assert_allclose(g.depth.values[wall], 3.0, rtol=1e-5)
    expected = focal_length_px(50.0, width) * baseline / 3.0
    np.testing.assert_allclose(g.disparity.values[wall & g.valid.values], expected, rtol=1e-4)
    # The dielectric sphere sits on the optical axis.
    assert MATERIAL_CLASSES[int(g.material.values[height // 2, width // 2])] == "glass"
    rig = prepare_scene(
        xml_scene / "mine.yaml",
        variant="auto",
        width=width,
        height=height,
        baseline_m=baseline,
        convention="paper",
    ).rig
    np.testing.assert_allclose(rig.origin("left"), [0.3, 1.0, -1.0], atol=1e-6)
    assert rig.fov_deg == pytest.approx(50.0)


def test_missing_xml_is_one_line_error_naming_the_file(xml_scene):
    (xml_scene / "room.xml").unlink()
    with pytest.raises(SceneError) as err:
        load_scene_spec(xml_scene / "mine.yaml")
    assert "room.xml" in str(err.value)
    assert "\n" not in str(err.value)


def test_unparsable_xml_is_one_line_error_naming_the_file(mi, xml_scene):
    (xml_scene / "room.xml").write_text("<scene version='3.0.0'><shape type='nosuch'/>")
    with pytest.raises(SceneError) as err:
        prepare_scene(
            xml_scene / "mine.yaml",
            variant="auto",
            width=8,
            height=8,
            baseline_m=0.02,
            convention="paper",
        )
    assert "room.xml" in str(err.value)
    assert "\n" not in str(err.value)


def test_job_reports_bad_scene_as_one_line_without_traceback(xml_scene, tmp_path):
    (xml_scene / "room.xml").write_text("not xml at all")
    code = (
        "from stereovar.jobs.common import run_job\n"
        "from stereovar.jobs.ground_truth import ground_truth_job\n"
        f"run_job(None, ground_truth_job, spec={str(xml_scene / 'mine.yaml')!r}, "
        f"out={str(tmp_path / 'o.zarr')!r}, width=8, height=8, baseline_m=0.02, "
        "convention='paper')\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    errors = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert len(errors) == 1 and "room.xml" in errors[0]
    assert not (tmp_path / "o.zarr").exists()
