"""Files an XML scene reads, and the content-addressed render cache."""

import numpy as np
import pytest

from stereovar.errors import SceneError
from stereovar.io.cache import KEY_FIELDS, RenderCache, render_key
from stereovar.scenes.references import xml_references

SCENE = """<scene version="3.0.0">
    <default name="mesh" value="meshes/bunny.obj"/>
    <include filename="parts/lights.xml"/>
    <shape type="obj"><string name="filename" value="$mesh"/></shape>
    <texture type="bitmap"><string name="filename" value="wood.png"/></texture>
    <spectrum name="eta" filename="/ABS/ior.spd"/>
</scene>
"""
LIGHTS = """<scene version="3.0.0">
    <shape type="ply"><string name="filename" value="lamp.ply"/></shape>
    <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
</scene>
"""


@pytest.fixture
def xml_tree(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "parts").mkdir()
    files = {
        "meshes/bunny.obj": "o bunny",
        "wood.png": "png",
        "parts/lamp.ply": "ply",
        "sky.exr": "exr",  # next to the top-level scene, not to the include
        "ior.spd": "1.5",
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "parts" / "lights.xml").write_text(LIGHTS)
    (tmp_path / "room.xml").write_text(SCENE.replace("/ABS", str(tmp_path)))
    return tmp_path


def test_every_referenced_file_is_found_through_includes_and_defaults(xml_tree):
    got = xml_references(xml_tree / "room.xml")
    want = ["parts/lights.xml", "parts/lamp.ply", "sky.exr", "meshes/bunny.obj", "wood.png"]
    want = [(xml_tree / p).resolve() for p in want] + [(xml_tree / "ior.spd").resolve()]
    assert sorted(got) == sorted(want) and len(got) == len(set(got))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: (d / "wood.png").unlink(), "referenced file 'wood.png' not found"),
        (lambda d: (d / "parts" / "lights.xml").write_text("<scene><shape>"), "malformed XML"),
        (
            lambda d: (d / "room.xml").write_text(
                (d / "room.xml").read_text().replace('<default name="mesh"', '<default name="m"')
            ),
            r"\$mesh is used in a file name but has no <default",
        ),
        (
            lambda d: (d / "parts" / "lights.xml").write_text(
                '<scene><include filename="../room.xml"/></scene>'
            ),
            "includes itself",
        ),
    ],
)
def test_reference_problems_are_one_line_errors(xml_tree, edit, message):
    edit(xml_tree)
    with pytest.raises(SceneError, match=message) as err:
        xml_references(xml_tree / "room.xml")
    assert "\n" not in str(err.value)


def _fields(**change):
    fields = {k: f"v-{k}" for k in KEY_FIELDS}
    fields.update(change)
    return fields


def test_render_key_depends_on_every_key_field_and_nothing_else():
    base = render_key(_fields())
    assert render_key({**_fields(), "log_level": "debug"}) == base
    keys = {render_key(_fields(**{k: "other"})) for k in KEY_FIELDS}
    assert base not in keys and len(keys) == len(KEY_FIELDS)
    with pytest.raises(KeyError, match="variant"):
        render_key({k: v for k, v in _fields().items() if k != "variant"})


def test_cache_round_trip_and_damaged_entries_are_misses(tmp_path):
    cache = RenderCache(tmp_path / "cache")
    key = render_key(_fields())
    assert cache.get(key) is None
    image = np.random.default_rng(0).random((5, 7, 3)).astype(np.float32)
    cache.put(key, image, {"scene": "s", "variant": "llvm_ad_rgb", "unused": None})
    np.testing.assert_array_equal(cache.get(key), image)
    # a chunk file lost: a miss (logged), never an exception or a wrong image
    chunks = [p for p in (cache.path(key) / "radiance").iterdir() if not p.name.startswith(".")]
    for chunk in chunks:
        chunk.write_bytes(b"garbage")
    assert cache.get(key) is None
    # an entry stored under another key's name is not served
    import shutil

    other = render_key(_fields(view="right"))
    cache.put(other, image, {})
    shutil.rmtree(cache.path(key))
    shutil.copytree(cache.path(other), cache.path(key))
    assert cache.get(key) is None
    np.testing.assert_array_equal(cache.get(other), image)


def test_scenes_validate_checks_the_xml_files_and_the_back_end(xml_tree):
    import subprocess
    import sys

    (xml_tree / "room.yaml").write_text("name: room\nmitsuba_xml: room.xml\n")

    def validate(*args):
        code = "from stereovar.cli import main; raise SystemExit(main())"
        return subprocess.run(
            [sys.executable, "-c", code, "scenes", "validate", str(xml_tree / "room.yaml"), *args],
            capture_output=True,
            text=True,
            env={**__import__("os").environ, "CUDA_VISIBLE_DEVICES": ""},
        )

    ok = validate("--variant", "scalar_rgb")
    assert ok.returncode == 0, ok.stderr
    assert "room.yaml: ok" in ok.stdout and "variant scalar_rgb" in ok.stdout
    bad = validate("--variant", "cuda_ad_rgb")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "'cuda_ad_rgb' is not available" in bad.stderr
    (xml_tree / "wood.png").unlink()
    missing = validate("--variant", "none")
    assert missing.returncode == 2 and "'wood.png' not found" in missing.stderr
    assert "back end" not in missing.stdout
