"""Tests of scene spec loading, validation, digests and writing (stereovar.scenes.spec)."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from stereovar.errors import SceneError
from stereovar.scenes.spec import load_scene_spec, scene_spec_digest, write_scene_spec

SRC = Path(__file__).resolve().parents[1] / "src"

BASE = {
    "name": "PLACEHOLDER",
    "camera": {"origin": [0.0, 1.5, 0.4], "target": [0.0, 0.8, 3.0], "fov_deg": 55.0},
    "textures": {
        "wood": {"pattern": "grain", "colors": [[0.5, 0.3, 0.1], [0.2, 0.1, 0.05]]},
    },
    "materials": {
        "oak": {"type": "diffuse", "texture": "wood"},
        "red": {"type": "glossy", "reflectance": [0.5, 0.1, 0.1]},
        "steel": {"type": "conductor", "metal": "Cr"},
        "clear": {"type": "glass"},
    },
    "objects": [
        {
            "name": "floor",
            "shape": "rectangle",
            "material": "oak",
            "transform": {"rotate": [-90, 0, 0], "scale": [3, 3, 1]},
        },
        {
            "name": "ball",
            "shape": "sphere",
            "material": "clear",
            "transform": {"translate": [0, 0.3, 3], "scale": [0.3, 0.3, 0.3]},
        },
        {
            "name": "vase",
            "shape": "lathe",
            "material": "clear",
            "profile": [[0.1, 0.0], [0.15, 0.2], [0.05, 0.4]],
        },
    ],
    "lights": [
        {
            "name": "panel",
            "radiance": [10, 10, 10],
            "transform": {"translate": [0, 2.9, 3], "rotate": [90, 0, 0]},
        },
    ],
}


def write(tmp_path: Path, name: str, data) -> Path:
    path = tmp_path / f"{name}.yaml"
    if isinstance(data, dict) and data.get("name") == "PLACEHOLDER":
        data = {**data, "name": name}
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def variant(mutate):
    data = copy.deepcopy(BASE)
    mutate(data)
    return data


def assert_scene_error(path: Path, *fragments: str):
    with pytest.raises(SceneError) as info:
        load_scene_spec(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    for fragment in fragments:
        assert fragment in message, message
    return message


# --------------------------------------------------------------------------------------------
# valid specs
# --------------------------------------------------------------------------------------------


def test_valid_spec_fills_defaults(tmp_path):
    spec = load_scene_spec(write(tmp_path, "good", copy.deepcopy(BASE)))
    assert spec["name"] == "good"
    assert spec["camera"]["up"] == [0.0, 1.0, 0.0]
    assert spec["textures"]["wood"]["repeat"] == [1.0, 1.0]
    assert spec["textures"]["wood"]["seed"] == 0
    assert spec["textures"]["wood"]["resolution"] == 256
    # defaults of the material's own branch only
    assert spec["materials"]["red"]["roughness"] == 0.1
    assert spec["materials"]["red"]["ior"] == 1.49
    assert spec["materials"]["steel"]["roughness"] == 0.0
    assert spec["materials"]["clear"] == {
        "type": "glass",
        "ior": 1.5,
        "roughness": 0.0,
        "tint": [1.0, 1.0, 1.0],
    }
    assert spec["materials"]["oak"] == {"type": "diffuse", "texture": "wood"}
    floor = spec["objects"][0]
    assert floor["transform"]["translate"] == [0.0, 0.0, 0.0]
    assert floor["segments"] == 64
    assert spec["lights"][0]["shape"] == "rectangle"
    assert spec["lights"][0]["transform"]["scale"] == [1.0, 1.0, 1.0]


def test_load_does_not_need_optional_collections(tmp_path):
    data = variant(lambda d: d.pop("textures"))
    data["materials"]["oak"] = {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}
    spec = load_scene_spec(write(tmp_path, "notex", data))
    assert spec["textures"] == {}


def test_mitsuba_xml_resolved_relative_to_spec(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "room.xml").write_text('<scene version="3.0.0"/>')
    path = write(tmp_path, "user", {"name": "user", "mitsuba_xml": "sub/room.xml"})
    cwd = os.getcwd()
    try:
        os.chdir("/")
        spec = load_scene_spec(path)
    finally:
        os.chdir(cwd)
    assert spec["mitsuba_xml"] == str((tmp_path / "sub" / "room.xml").resolve())
    assert Path(spec["mitsuba_xml"]).is_absolute()
    for key in ("camera", "objects", "lights", "materials", "textures"):
        assert key not in spec


def test_digest_is_stable_and_sensitive(tmp_path):
    spec = load_scene_spec(write(tmp_path, "good", copy.deepcopy(BASE)))
    d1 = scene_spec_digest(spec)
    assert len(d1) == 64 and int(d1, 16) >= 0
    assert scene_spec_digest(copy.deepcopy(spec)) == d1
    reordered = dict(reversed(list(spec.items())))
    assert scene_spec_digest(reordered) == d1
    changed = copy.deepcopy(spec)
    changed["lights"][0]["radiance"] = [11, 10, 10]
    assert scene_spec_digest(changed) != d1
    # spelled-out defaults give the same digest once loaded
    explicit = copy.deepcopy(BASE)
    explicit["camera"]["up"] = [0.0, 1.0, 0.0]
    (tmp_path / "x").mkdir()
    assert scene_spec_digest(load_scene_spec(write(tmp_path / "x", "good", explicit))) == d1


def test_write_is_deterministic_atomic_and_round_trips(tmp_path):
    spec = load_scene_spec(write(tmp_path, "good", copy.deepcopy(BASE)))
    spec["camera"]["origin"] = [0.123456789, 1.5, -0.0]
    out1 = write_scene_spec(spec, tmp_path / "a" / "good.yaml")
    out2 = write_scene_spec(copy.deepcopy(spec), tmp_path / "b" / "good.yaml")
    assert out1.read_bytes() == out2.read_bytes()
    text = out1.read_text()
    assert "0.1235" in text and "0.123456789" not in text
    assert "-0.0" not in text
    assert text.splitlines()[0] == "name: good"
    # no temporary files left behind
    assert sorted(p.name for p in out1.parent.iterdir()) == ["good.yaml"]
    again = load_scene_spec(out1)
    assert again["camera"]["origin"] == [0.1235, 1.5, 0.0]
    assert again["objects"] == spec["objects"]
    # writing twice over the same file keeps the same bytes
    write_scene_spec(again, out1)
    assert out1.read_bytes() == out2.read_bytes()


# --------------------------------------------------------------------------------------------
# invalid specs: one line naming the file and the key
# --------------------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    assert_scene_error(tmp_path / "nope.yaml", "not found")


def test_yaml_parse_error(tmp_path):
    path = write(tmp_path, "broken", "name: broken\ncamera: {origin: [0, 1\n")
    assert_scene_error(path, "yaml", "line")


def test_top_level_not_a_mapping(tmp_path):
    assert_scene_error(write(tmp_path, "list", "- 1\n- 2\n"), "mapping")


@pytest.mark.parametrize(
    ("name", "mutate", "fragments"),
    [
        (
            "enum_shape",
            lambda d: d["objects"][0].update(shape="cube"),
            ["objects.0.shape", "'cube'", "rectangle, box, sphere, cylinder, lathe"],
        ),
        (
            "enum_pattern",
            lambda d: d["textures"]["wood"].update(pattern="marble"),
            ["textures.wood.pattern", "planks", "grain"],
        ),
        (
            "enum_metal",
            lambda d: d["materials"]["steel"].update(metal="Fe"),
            ["materials.steel.metal", "'Fe'", "Al"],
        ),
        (
            "material_type",
            lambda d: d["materials"].update(bad={"type": "plastic"}),
            ["materials.bad.type", "diffuse, glossy, conductor, glass"],
        ),
        (
            "unknown_key",
            lambda d: d["objects"][1].update(colour=[1, 0, 0]),
            ["objects.1.colour", "unknown key", "allowed keys", "material", "transform"],
        ),
        (
            "unknown_top_key",
            lambda d: d.update(sky="blue"),
            ["sky", "unknown key", "camera", "lights"],
        ),
        (
            "unknown_material_key",
            lambda d: d["materials"]["red"].update(shine=2),
            ["materials.red.shine", "unknown key", "roughness"],
        ),
        (
            "both_albedos",
            lambda d: d["materials"]["oak"].update(reflectance=[1, 1, 1]),
            ["materials.oak", "exactly one of reflectance, texture"],
        ),
        (
            "range",
            lambda d: d["materials"]["red"].update(roughness=2),
            ["materials.red.roughness", "<= 1"],
        ),
        ("vec3", lambda d: d["camera"].update(origin=[0, 1]), ["camera.origin", "at least 3"]),
        ("fov", lambda d: d["camera"].update(fov_deg=190), ["camera.fov_deg", "< 180"]),
        (
            "type",
            lambda d: d["lights"][0].update(radiance="bright"),
            ["lights.0.radiance", "expected array"],
        ),
        (
            "missing_required",
            lambda d: d["objects"][0].pop("material"),
            ["objects.0.material", "missing required key"],
        ),
        ("no_camera", lambda d: d.pop("camera"), ["camera", "missing required key"]),
        (
            "xml_and_objects",
            lambda d: d.update(mitsuba_xml="room.xml"),
            ["mitsuba_xml", "camera", "objects"],
        ),
        (
            "unknown_material",
            lambda d: d["objects"][1].update(material="gold"),
            ["objects.1.material", "'gold'", "unknown material", "clear, oak, red, steel"],
        ),
        (
            "unknown_texture",
            lambda d: d["materials"]["oak"].update(texture="pine"),
            ["materials.oak.texture", "'pine'", "unknown texture", "wood"],
        ),
        (
            "glossy_unknown_texture",
            lambda d: d["materials"]["red"].update(texture="pine"),
            ["materials.red.texture", "'pine'"],
        ),
        (
            "sphere_scale",
            lambda d: d["objects"][1]["transform"].update(scale=[0.3, 0.6, 0.3]),
            ["objects.1.transform.scale", "uniform"],
        ),
        (
            "lathe_no_profile",
            lambda d: d["objects"][2].pop("profile"),
            ["objects.2.profile", "at least 2"],
        ),
        (
            "lathe_short_profile",
            lambda d: d["objects"][2].update(profile=[[0.1, 0.0]]),
            ["objects.2.profile", "at least 2"],
        ),
        (
            "lathe_bad_profile",
            lambda d: d["objects"][2].update(profile=[[0.1, 0.2], [0.1, 0.1]]),
            ["objects.2.profile", "increase"],
        ),
        (
            "duplicate_name",
            lambda d: d["objects"][1].update(name="floor"),
            ["objects.1.name", "duplicate"],
        ),
    ],
)
def test_invalid_spec(tmp_path, name, mutate, fragments):
    assert_scene_error(write(tmp_path, name, variant(mutate)), *fragments)


def test_name_must_equal_stem(tmp_path):
    path = write(tmp_path, "kitchen", {**copy.deepcopy(BASE), "name": "bathroom"})
    assert_scene_error(path, "name", "'bathroom'", "'kitchen'")


def test_missing_mitsuba_xml(tmp_path):
    path = write(tmp_path, "user", {"name": "user", "mitsuba_xml": "missing/room.xml"})
    assert_scene_error(path, "mitsuba_xml", "not found", "room.xml")


# --------------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------------


def run_cli(*args):
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(SRC), *filter(None, [os.environ.get("PYTHONPATH")])]),
    }
    return subprocess.run(
        [sys.executable, "-m", "stereovar.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def test_cli_validate_bad_file_exits_2_with_one_line(tmp_path):
    path = write(tmp_path, "bad", variant(lambda d: d["objects"][0].update(shape="cube")))
    proc = run_cli("scenes", "validate", str(path))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("stereovar: error: ")
    assert str(path) in lines[0] and "objects.0.shape" in lines[0]
    assert "Traceback" not in proc.stderr


def test_cli_validate_good_files(tmp_path):
    a = write(tmp_path, "a", copy.deepcopy(BASE))
    b = write(tmp_path, "b", copy.deepcopy(BASE))
    proc = run_cli("scenes", "validate", str(a), str(b))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count(": ok") == 2


def test_cli_main_in_process(tmp_path, capsys):
    from stereovar.cli import main

    path = write(tmp_path, "bad", variant(lambda d: d["materials"]["oak"].update(texture="x")))
    assert main(["scenes", "validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "materials.oak.texture" in err
    with pytest.raises(SystemExit) as info:
        main(["scenes"])  # missing sub-command: argparse usage error
    assert info.value.code == 2
