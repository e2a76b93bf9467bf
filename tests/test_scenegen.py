"""Tests of the procedural scene generator (stereovar.scenes.generate); no rendering."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from stereovar.geometry import camera_frame, transform_matrix
from stereovar.scenes.generate import (
    GENERATOR_VERSION,
    estimate_glass_fraction,
    generate_scene,
    generate_scenes,
    glass_coverage,
    raycast_labels,
    write_scenes,
)
from stereovar.scenes.spec import load_scene_spec, write_scene_spec

REPO = Path(__file__).resolve().parents[1]
COMMITTED = REPO / "scenes"
COUNT, SEED = 20, 0


@pytest.fixture(scope="module")
def scenes():
    return generate_scenes(COUNT, SEED)


@pytest.fixture(scope="module")
def fresh_dir(scenes, tmp_path_factory):
    """The 20 scenes written like ``stereovar scenes generate --count 20 --seed 0``."""
    out = tmp_path_factory.mktemp("fresh")
    for spec in scenes:
        write_scene_spec(spec, out / f"{spec['name']}.yaml")
    return out


@pytest.fixture(scope="module")
def loaded(fresh_dir):
    return [load_scene_spec(p) for p in sorted(fresh_dir.glob("scene_*.yaml"))]


def glass_objects(spec):
    return [o for o in spec["objects"] if spec["materials"][o["material"]]["type"] == "glass"]


def test_names_and_provenance(scenes):
    assert [s["name"] for s in scenes] == [f"scene_{i:03d}" for i in range(COUNT)]
    for i, spec in enumerate(scenes):
        gen = spec["generator"]
        assert (gen["seed"], gen["index"], gen["version"]) == (SEED, i, GENERATOR_VERSION)


def test_write_scenes_is_byte_deterministic(tmp_path, fresh_dir):
    a = write_scenes(tmp_path / "a", 3, SEED)
    b = write_scenes(tmp_path / "b", 3, SEED)
    assert [p.name for p in a] == ["scene_000.yaml", "scene_001.yaml", "scene_002.yaml"]
    for pa, pb in zip(a, b, strict=True):
        assert pa.read_bytes() == pb.read_bytes()
        # and equal to the same scenes from a run of 20 (scene i does not depend on count)
        assert pa.read_bytes() == (fresh_dir / pa.name).read_bytes()


def test_committed_scenes_match_fresh_generation(fresh_dir):
    committed = sorted(p.name for p in COMMITTED.glob("scene_*.yaml"))
    assert committed == [f"scene_{i:03d}.yaml" for i in range(COUNT)], (
        "regenerate with: stereovar scenes generate --count 20 --seed 0"
    )
    for name in committed:
        assert (COMMITTED / name).read_bytes() == (fresh_dir / name).read_bytes(), (
            f"{name} differs from a fresh generation; regenerate with "
            "'stereovar scenes generate --count 20 --seed 0' (and bump GENERATOR_VERSION "
            "if the generator changed)"
        )


def test_scene_independent_of_count(scenes):
    assert generate_scenes(5, SEED)[2] == scenes[2]
    assert generate_scene(2, SEED) == scenes[2]


def test_different_seeds_give_different_scenes():
    assert generate_scene(0, 1) != generate_scene(0, 0)


def test_every_scene_validates(loaded):
    assert len(loaded) == COUNT


def test_lights_glass_and_materials(loaded):
    n_glossy = n_conductor = 0
    for spec in loaded:
        assert 1 <= len(spec["lights"]) <= 3, spec["name"]
        assert 1 <= len(glass_objects(spec)) <= 4, spec["name"]
        types = {spec["materials"][o["material"]]["type"] for o in spec["objects"]}
        assert types & {"glossy", "conductor"}, spec["name"]
        n_glossy += "glossy" in types
        n_conductor += "conductor" in types
        for light in spec["lights"]:
            assert min(light["radiance"]) > 0
    # at least one of each in most scenes
    assert n_glossy >= 0.8 * COUNT and n_conductor >= 0.8 * COUNT


def test_room_surfaces_are_textured_diffuse(loaded):
    for spec in loaded:
        names = {o["name"]: o for o in spec["objects"]}
        room = [n for n in names if n.startswith(("floor", "wall_"))]
        assert any(n.startswith("floor") for n in room)
        assert sum(n.startswith("wall_") for n in room) >= 3
        for n in room:
            mat = spec["materials"][names[n]["material"]]
            assert mat["type"] == "diffuse" and "texture" in mat, (spec["name"], n)


def test_room_is_closed_and_surfaces_face_inwards(loaded):
    """Every room rectangle's normal points towards the room centre; no ray escapes."""
    for spec in loaded:
        objs = {o["name"]: o for o in spec["objects"]}
        floor = objs[next(n for n in objs if n.startswith("floor"))]
        ceiling = objs[next(n for n in objs if n.startswith("ceiling"))]
        centre = np.array(
            [0.0, ceiling["transform"]["translate"][1] / 2, floor["transform"]["translate"][2]]
        )
        for name, obj in objs.items():
            if obj["shape"] != "rectangle":
                continue
            m = transform_matrix(**obj["transform"])
            normal = m[:3, :3] @ np.array([0.0, 0.0, 1.0])
            assert normal @ (centre - m[:3, 3]) > 0, (spec["name"], name)
        labels, _ = raycast_labels(spec, width=64, height=36)
        assert (labels >= 0).all(), spec["name"]


def test_room_sizes_and_camera(loaded):
    for spec in loaded:
        objs = {o["name"]: o for o in spec["objects"]}
        floor = objs[next(n for n in objs if n.startswith("floor"))]["transform"]
        ceiling = objs[next(n for n in objs if n.startswith("ceiling"))]["transform"]
        width = 2 * floor["scale"][0] - 0.02
        depth = 2 * floor["scale"][1] - 0.02
        height = ceiling["translate"][1]
        assert 3.5 <= width <= 7.0 and 4.0 <= depth <= 8.0 and 2.5 <= height <= 3.2
        cam = spec["camera"]
        assert 50 <= cam["fov_deg"] <= 70
        assert cam["up"] == [0.0, 1.0, 0.0]
        x, y, z = cam["origin"]
        assert abs(x) < width / 2 and 0.9 <= y <= 1.8 and 0 < z < 1.0
        forward = camera_frame(cam["origin"], cam["target"], cam["up"])[2]
        assert forward[2] > 0.8  # looking into the room


def test_scenes_differ(loaded):
    sizes = {
        tuple(o["transform"]["scale"])
        for s in loaded
        for o in s["objects"]
        if o["name"].startswith("floor")
    }
    assert len(sizes) == COUNT
    floors = {
        tuple(map(tuple, s["textures"][s["materials"]["floor"]["texture"]]["colors"]))
        for s in loaded
    }
    assert len(floors) == COUNT
    patterns = {t["pattern"] for s in loaded for t in s["textures"].values()}
    assert len(patterns) >= 5
    fovs = {s["camera"]["fov_deg"] for s in loaded}
    assert len(fovs) > COUNT // 2
    glass_shapes = {o["shape"] for s in loaded for o in glass_objects(s)}
    assert glass_shapes == {"sphere", "box", "lathe", "cylinder"}


def test_furniture_on_the_floor_inside_the_room(loaded):
    """Boxes and cylinders stay inside the room and do not sink below the floor."""
    for spec in loaded:
        objs = {o["name"]: o for o in spec["objects"]}
        floor = objs[next(n for n in objs if n.startswith("floor"))]["transform"]
        ceiling = objs[next(n for n in objs if n.startswith("ceiling"))]["transform"]
        half_w, depth = floor["scale"][0] - 0.01, 2 * floor["scale"][1] - 0.02
        height = ceiling["translate"][1]
        for o in spec["objects"]:
            if o["shape"] == "rectangle":
                continue
            m = transform_matrix(**o["transform"])
            if o["shape"] == "lathe":
                prof = np.asarray(o["profile"])
                r = prof[:, 0].max()
                local = np.array(
                    [
                        [sx * r, y, sz * r]
                        for sx in (-1, 1)
                        for sz in (-1, 1)
                        for y in (prof[0, 1], prof[-1, 1])
                    ]
                )
            else:
                y0 = 0.0 if o["shape"] == "cylinder" else -1.0
                local = np.array(
                    [[sx, y, sz] for sx in (-1, 1) for sz in (-1, 1) for y in (y0, 1.0)]
                )
            world = local @ m[:3, :3].T + m[:3, 3]
            tol = 2e-3
            assert world[:, 1].min() >= -tol, (spec["name"], o["name"])
            assert world[:, 1].max() <= height + tol, (spec["name"], o["name"])
            assert np.abs(world[:, 0]).max() <= half_w + tol, (spec["name"], o["name"])
            assert world[:, 2].min() >= -tol and world[:, 2].max() <= depth + tol


def test_lights_emit_into_the_room(loaded):
    for spec in loaded:
        objs = {o["name"]: o for o in spec["objects"]}
        floor = objs[next(n for n in objs if n.startswith("floor"))]["transform"]
        centre = np.array([0.0, 1.2, floor["translate"][2]])
        for light in spec["lights"]:
            m = transform_matrix(**light["transform"])
            normal = m[:3, :3] @ np.array([0.0, 0.0, 1.0])
            assert normal @ (centre - m[:3, 3]) > 0, (spec["name"], light["name"])
            assert normal[1] < -0.3, "lights point downwards into the room"
        # at least one small panel (the shadow caster)
        areas = [
            4 * li["transform"]["scale"][0] * li["transform"]["scale"][1] for li in spec["lights"]
        ]
        assert min(areas) <= 0.4, spec["name"]


def test_glass_estimate(scenes):
    for spec in scenes:
        cov = glass_coverage(spec)
        assert cov["fraction"] >= 0.03, (spec["name"], cov["fraction"])
        assert cov["fraction"] >= 0.05  # the generator's margin
        assert math.isclose(cov["fraction"], spec["generator"]["glass_estimate"], abs_tol=1e-4)
        assert cov["light_fraction"] == 0.0 and cov["miss_fraction"] == 0.0
        names = {o["name"] for o in glass_objects(spec)}
        assert set(cov["per_object"]) == names
        assert all(v > 0 for v in cov["per_object"].values()), spec["name"]
        # glossy and metal surfaces are on screen, not only in the file
        assert cov["by_type"]["glossy"] > 0 and cov["by_type"]["conductor"] > 0, spec["name"]
        assert sum(cov["by_type"].values()) == pytest.approx(1.0)


def test_glass_estimate_against_analytic_sphere():
    """A lone sphere straight ahead: the ray-cast fraction matches the cone's solid angle."""
    spec = {
        "camera": {"origin": [0.0, 0.0, 0.0], "target": [0.0, 0.0, 1.0], "fov_deg": 60.0},
        "materials": {"g": {"type": "glass"}},
        "objects": [
            {
                "name": "s",
                "shape": "sphere",
                "material": "g",
                "transform": {"translate": [0.0, 0.0, 3.0], "scale": [0.5, 0.5, 0.5]},
            }
        ],
        "lights": [],
    }
    width, height = 320, 180
    frac = estimate_glass_fraction(spec, width=width, height=height)
    f = 0.5 * width / math.tan(math.radians(30))
    # silhouette of a sphere on the axis: a disc of radius f * tan(asin(r / d))
    radius_px = f * math.tan(math.asin(0.5 / 3.0))
    expected = math.pi * radius_px**2 / (width * height)
    assert frac == pytest.approx(expected, rel=0.03)


def test_glass_estimate_box_pane():
    spec = {
        "camera": {"origin": [0.0, 0.0, 0.0], "target": [0.0, 0.0, 1.0], "fov_deg": 60.0},
        "materials": {"g": {"type": "glass"}},
        "objects": [
            {
                "name": "p",
                "shape": "box",
                "material": "g",
                "transform": {
                    "translate": [0.0, 0.0, 2.0],
                    "rotate": [0, 0, 0],
                    "scale": [0.4, 0.3, 0.01],
                },
            }
        ],
        "lights": [],
    }
    width, height = 320, 180
    f = 0.5 * width / math.tan(math.radians(30))
    expected = (2 * 0.4 * f / 1.99) * (2 * 0.3 * f / 1.99) / (width * height)
    assert estimate_glass_fraction(spec, width=width, height=height) == pytest.approx(
        expected, rel=0.03
    )


def test_invalid_arguments():
    with pytest.raises(ValueError):
        generate_scene(-1, 0)
