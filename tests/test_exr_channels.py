"""An EXR's channels picked by what their names mean: Blender 5's multi-part multilayer files
(each pass its own part: ``ViewLayer.Combined``, ``ViewLayer.Depth``, ``ViewLayer.Object
Index``), Blender's older single-part multilayer names (``IndexOB``), Kubric's and
BlenderProc's names, BlenderProc's ray distance refused as depth, ambiguous files refused with
one line listing their channels, ``audit.channels`` overrides, and an audit whose depth is a
Blender multilayer file.

The files are written with the OpenEXR bindings in the layout Blender 5.0.1 writes (checked
against its own renders: multilayer ``OPEN_EXR_MULTILAYER`` is one part per pass, named
``<ViewLayer>.<Pass>``, with channels ``<ViewLayer>.<Pass>.<Channel>``; Blender is not
needed here).
"""

from pathlib import Path

import numpy as np
import OpenEXR
import pytest
import yaml

from stereovar.audit.importer import import_audit, import_settings
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.config import load_config
from stereovar.errors import AuditError, ConfigError, ImageError
from stereovar.io.channels import field_channel, meaning, render_channels
from stereovar.io.headers import image_size
from stereovar.io.images import read_field, read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow/schemas/config.schema.yaml"
H, W = 5, 7
RNG = np.random.default_rng(25)
RGB = RNG.uniform(0.1, 0.9, (H, W, 3)).astype(np.float32)
DEPTH = RNG.uniform(2.0, 9.0, (H, W)).astype(np.float32)
INDEX = RNG.integers(0, 5, (H, W)).astype(np.float32)


def header() -> dict:
    """A fresh header (the bindings add the windows to the dict they are given)."""
    return {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}


def planes(prefix: str, image: np.ndarray, letters: str = "RGBA") -> dict:
    """Channels ``{prefix}.R`` ... of an ``(H, W, 3)`` image (alpha 1)."""
    stack = np.concatenate([image, np.ones((*image.shape[:2], 1), image.dtype)], axis=-1)
    sep = "." if prefix else ""
    return {f"{prefix}{sep}{c}": np.ascontiguousarray(stack[..., k]) for k, c in enumerate(letters)}


def write_single(path, channels: dict) -> Path:
    """One-part EXR with these channels."""
    with OpenEXR.File(header(), {k: np.ascontiguousarray(v) for k, v in channels.items()}) as f:
        f.write(str(path))
    return Path(path)


def write_parts(path, parts: dict, views: dict | None = None) -> Path:
    """Multi-part EXR: part name to its channels (Blender 5's multilayer layout); ``views``:
    part name to its ``view`` attribute."""
    objects = [
        OpenEXR.Part(
            {**header(), **({"view": views[name]} if views and name in views else {})},
            {k: np.ascontiguousarray(v) for k, v in channels.items()},
            name,
        )
        for name, channels in parts.items()
    ]
    with OpenEXR.File(objects) as f:
        f.write(str(path))
    return Path(path)


def blender5(path, *, depth=DEPTH, image=RGB, index=INDEX, layer="ViewLayer") -> Path:
    """What Blender 5.0.1 writes with the Depth and Object Index passes (denoising on)."""
    return write_parts(
        path,
        {
            f"{layer}.Combined": planes(f"{layer}.Combined", image),
            f"{layer}.Depth": {f"{layer}.Depth.Z": depth},
            f"{layer}.Object Index": {f"{layer}.Object Index.X": index},
            f"{layer}.Noisy Image": planes(f"{layer}.Noisy Image", 3 * image),
        },
    )


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


# --------------------------------------------------------------------------------------------
# Blender
# --------------------------------------------------------------------------------------------


def test_blender5_multipart_file_gives_depth_render_and_object_index(tmp_path):
    path = blender5(tmp_path / "blender.exr")
    assert len(OpenEXR.File(str(path), header_only=True).parts) == 4
    assert image_size(path) == (H, W)
    depth = read_field(path, role="depth")
    np.testing.assert_array_equal(depth, DEPTH)  # Depth.Z, not Combined.R
    assert not np.allclose(depth, RGB[..., 0])
    np.testing.assert_array_equal(read_image(path), RGB)  # Combined, not Noisy Image
    np.testing.assert_array_equal(read_field(path, role="segmentation"), INDEX)
    # decoded into a slice of a stack, as the import does
    stack = np.zeros((2, H, W, 3), np.float32)
    read_image(path, out=stack[1])
    np.testing.assert_array_equal(stack[1], RGB)


def test_blender_single_part_names_pick_depth_by_pass_not_by_last_letter(tmp_path):
    # older Blender (one part, IndexOB); Mist.Z and Normal.Z end in Z but are not depth
    channels = {
        **planes("ViewLayer.Combined", RGB),
        "ViewLayer.Mist.Z": np.full((H, W), 0.5, np.float32),
        **{f"ViewLayer.Normal.{c}": np.zeros((H, W), np.float32) for c in "XYZ"},
        "ViewLayer.Depth.Z": DEPTH,
        "ViewLayer.IndexOB.X": INDEX,
    }
    path = write_single(tmp_path / "old.exr", channels)
    np.testing.assert_array_equal(read_field(path, role="depth"), DEPTH)
    np.testing.assert_array_equal(read_field(path, role="segmentation"), INDEX)
    np.testing.assert_array_equal(read_image(path), RGB)


def test_two_view_layers_are_refused_until_one_is_named(tmp_path):
    parts = {}
    for layer, scale in (("ViewLayer", 1.0), ("Glass", 2.0)):
        parts[f"{layer}.Combined"] = planes(f"{layer}.Combined", scale * RGB)
        parts[f"{layer}.Depth"] = {f"{layer}.Depth.Z": scale * DEPTH}
    path = write_parts(tmp_path / "layers.exr", parts)
    with pytest.raises(ImageError) as err:
        read_image(path)
    assert one_line(err) == (
        f"{path}: several RGB layers (Glass.Combined, ViewLayer.Combined) and more than one "
        "is the render (Combined); set audit.channels: {render: <one of them>}"
    )
    with pytest.raises(ImageError, match=r"several depth channels \(Glass\.Depth\.Z, View"):
        read_field(path, role="depth")
    np.testing.assert_array_equal(read_image(path, channel="Glass.Combined"), 2 * RGB)
    np.testing.assert_array_equal(
        read_field(path, role="depth", channel="Glass.Depth.Z"), 2 * DEPTH
    )


def test_a_multiview_file_is_refused_naming_the_views(tmp_path):
    parts = {
        f"ViewLayer.Depth-{v}": {"ViewLayer.Depth.Z": DEPTH + k}
        for k, v in enumerate(("left", "right"))
    }
    path = write_parts(tmp_path / "stereo.exr", parts, views={p: p.split("-")[1] for p in parts})
    with pytest.raises(ImageError) as err:
        read_field(path, role="depth")
    assert one_line(err) == (
        f"{path}: channel 'ViewLayer.Depth.Z' is in 2 parts (left, right): a multi-view file; "
        "export one file per view (Blender: Output Properties > Views > Views Format: "
        "Individual)"
    )


def test_parts_of_different_sizes_are_refused_by_the_header(tmp_path):
    window = (np.array([0, 0], np.int32), np.array([W - 1, H], np.int32))  # one row more
    display = (np.array([0, 0], np.int32), np.array([W - 1, H - 1], np.int32))
    parts = [
        OpenEXR.Part(header(), {"a.Z": DEPTH}, "a"),
        OpenEXR.Part(
            {**header(), "dataWindow": window, "displayWindow": display},
            {"b.Z": np.zeros((H + 1, W), np.float32)},
            "b",
        ),
    ]
    path = tmp_path / "sizes.exr"
    with OpenEXR.File(parts) as f:
        f.write(str(path))
    with pytest.raises(ImageError, match=r"its parts differ in size \(a 7x5, b 7x6\); export"):
        image_size(path)


# --------------------------------------------------------------------------------------------
# Kubric, BlenderProc, plain files
# --------------------------------------------------------------------------------------------


def test_kubric_names(tmp_path):
    # its layers (rgba, depth, segmentation) and its Blender compositor file (Image, Depth.V)
    layers = write_single(
        tmp_path / "kubric.exr",
        {**planes("rgba", RGB), "depth": DEPTH, "segmentation": INDEX},
    )
    np.testing.assert_array_equal(read_image(layers), RGB)
    np.testing.assert_array_equal(read_field(layers, role="depth"), DEPTH)
    np.testing.assert_array_equal(read_field(layers, role="segmentation"), INDEX)
    compositor = write_single(
        tmp_path / "kubric_raw.exr",
        {**planes("Image", RGB), "Depth.V": DEPTH, **planes("Normal", RGB, "XYZ")},
    )
    np.testing.assert_array_equal(read_image(compositor), RGB)
    np.testing.assert_array_equal(read_field(compositor, role="depth"), DEPTH)


def test_blenderproc_names_and_its_segmaps(tmp_path):
    path = write_single(
        tmp_path / "bproc.exr",
        {**planes("colors", RGB, "RGB"), "depth": DEPTH, "instance_segmaps": INDEX},
    )
    np.testing.assert_array_equal(read_image(path), RGB)
    np.testing.assert_array_equal(read_field(path, role="depth"), DEPTH)
    np.testing.assert_array_equal(read_field(path, role="segmentation"), INDEX)
    both = write_single(
        tmp_path / "both.exr", {"instance_segmaps": INDEX, "class_segmaps": INDEX + 10}
    )
    with pytest.raises(ImageError) as err:
        read_field(both, role="segmentation")
    assert one_line(err) == (
        f"{both}: several segmentation channels (class_segmaps, instance_segmaps); set "
        "audit.channels: {segmentation: <one of them>}"
    )
    np.testing.assert_array_equal(
        read_field(both, role="segmentation", channel="class_segmaps"), INDEX + 10
    )


def test_blenderproc_distance_is_refused_as_depth(tmp_path):
    expected = (
        "channel 'distance' is ray distance (BlenderProc's distance output), not planar "
        "depth, and d = f B / z needs planar depth; export depth "
        "(bproc.renderer.enable_depth_output) or give audit.disparity"
    )
    alone = write_single(tmp_path / "distance.exr", {"distance": DEPTH})
    with pytest.raises(ImageError) as err:
        read_field(alone, role="depth")
    assert one_line(err) == f"{alone}: {expected}"
    beside = write_single(tmp_path / "beside.exr", {**planes("colors", RGB), "distance": DEPTH})
    with pytest.raises(ImageError) as err:
        read_field(beside, role="depth")
    assert one_line(err) == f"{beside}: {expected}"
    with pytest.raises(ImageError, match="is ray distance"):
        read_field(beside, role="depth", channel="distance")
    # with planar depth beside it, depth is read
    both = write_single(tmp_path / "both.exr", {"distance": DEPTH + 1, "depth": DEPTH})
    np.testing.assert_array_equal(read_field(both, role="depth"), DEPTH)


def test_one_channel_is_the_field_whatever_its_name(tmp_path):
    path = tmp_path / "disparity.exr"
    write_field(path, DEPTH)  # our own writer: one channel Z
    np.testing.assert_array_equal(read_field(path, role="disparity"), DEPTH)
    grey = write_single(tmp_path / "grey.exr", {"V": DEPTH})  # Blender's BW EXR
    np.testing.assert_array_equal(read_field(grey, role="glass_mask"), DEPTH)
    np.testing.assert_array_equal(read_image(grey), np.repeat(DEPTH[..., None], 3, -1))


def test_ambiguous_files_are_refused_listing_their_channels(tmp_path):
    two = write_single(tmp_path / "two.exr", {"A": DEPTH, "B": DEPTH + 1})
    with pytest.raises(ImageError) as err:
        read_field(two, role="depth")
    assert one_line(err) == (
        f"{two}: no depth channel among its 2 channels (A, B); set audit.channels: "
        "{depth: <one of them>}"
    )
    rgb = write_single(tmp_path / "rgb.exr", planes("", RGB))
    for role in ("depth", "disparity", "segmentation", None):
        with pytest.raises(ImageError) as err:  # never R, never the first channel
            read_field(rgb, role=role)
        text = one_line(err)
        assert f"no {role or 'field'} channel among its 4 channels (A, B, G, R); " in text
    with pytest.raises(ImageError) as err:
        read_image(two)
    assert one_line(err) == (
        f"{two}: no R, G, B channels (has A, B); write an RGB image, or set audit.channels: "
        "{render: <one of them>}"
    )


def test_overrides_pick_the_named_channel_and_refuse_a_missing_one(tmp_path):
    path = blender5(tmp_path / "blender.exr")
    noisy = read_image(path, channel="ViewLayer.Noisy Image")
    np.testing.assert_allclose(noisy, 3 * RGB, rtol=1e-6)
    np.testing.assert_array_equal(
        read_field(path, role="depth", channel="ViewLayer.Object Index.X"), INDEX
    )
    two = write_single(tmp_path / "two.exr", {"A": DEPTH, "B": DEPTH + 1})
    np.testing.assert_array_equal(read_field(two, role="depth", channel="B"), DEPTH + 1)
    with pytest.raises(ImageError) as err:
        read_field(path, role="depth", channel="ViewLayer.Depth.V")
    text = one_line(err)
    assert text.startswith(
        f"{path}: audit.channels.depth is 'ViewLayer.Depth.V' but the file has no such "
        "channel (it has ViewLayer.Combined.A, ViewLayer.Combined.B,"
    )
    assert "ViewLayer.Depth.Z" in text and text.endswith(
        "; set audit.channels.depth to one of them"
    )
    with pytest.raises(ImageError, match=r"audit\.channels\.render is 'RenderLayer\.Combined'"):
        read_image(path, channel="RenderLayer.Combined")


def test_names_by_meaning():
    assert [meaning(n) for n in ("Z", "depth", "Depth.V", "ViewLayer.Denoising Depth.Z")] == [
        "depth",
        "depth",
        "depth",
        None,
    ]
    assert meaning("category_id_segmaps") == meaning("IndexOB") == "segmentation"
    assert meaning("glass_mask") == "glass_mask" and meaning("disparity") == "disparity"
    assert field_channel(["x.Y", "glass"], "glass_mask", "m.exr") == "glass"
    assert render_channels(["colors.R", "colors.G", "colors.B", "Y"], "c.exr") == (
        "colors.R",
        "colors.G",
        "colors.B",
    )
    with pytest.raises(ValueError, match="unknown field role 'mask'"):
        field_channel(["Z"], "mask", "m.exr")


# --------------------------------------------------------------------------------------------
# the audit
# --------------------------------------------------------------------------------------------


def test_audit_reads_depth_from_a_blender_multilayer_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    small = {"width": 64, "height": 40, "n_seeds": 4}
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **small)
    focal, baseline = 800.0, 0.12
    (tmp_path / "d" / "depth").mkdir()
    for k, frame in enumerate(frames):
        depth = (focal * baseline / frame.disparity).astype(np.float32)
        blender5(
            tmp_path / "d" / "depth" / f"f{k:02d}.exr",
            depth=depth,
            image=np.full((*depth.shape, 3), 0.5, np.float32),
            index=np.zeros(depth.shape, np.float32),
        )
    settings = {
        **{k: v for k, v in settings.items() if k != "disparity"},
        "depth": f"{tmp_path}/d/depth/{{frame}}.exr",
        "focal_px": focal,
        "baseline_m": baseline,
    }
    report = import_audit(settings)
    assert report.frames[0].imported
    gt = open_dataset("results/audit/synthetic/ground_truth/f00.zarr").sel(view="left")
    valid = gt["valid"].values
    assert valid.sum() > 0.8 * valid.size
    np.testing.assert_allclose(gt["disparity"].values[valid], frames[0].disparity[valid], rtol=1e-5)
    # a channels setting is an import setting: naming the same channel imports again
    named = {**settings, "channels": {"depth": "ViewLayer.Depth.Z"}}
    assert import_audit(named).frames[0].imported
    assert not import_audit(named).frames[0].imported
    with pytest.raises(ImageError, match=r"audit\.channels\.depth is 'Depth\.Z' but the file"):
        import_audit({**settings, "channels": {"depth": "Depth.Z"}})


def test_audit_channels_are_checked_by_the_schema_and_the_import(tmp_path):
    good = {
        "name": "a",
        "renders": "r/{view}/{seed}.exr",
        "channels": {"depth": "ViewLayer.Depth.Z", "render": "ViewLayer.Combined"},
    }
    (tmp_path / "good.yaml").write_text(yaml.safe_dump({"audit": good}))
    loaded = load_config([REPO / "config.yaml", tmp_path / "good.yaml"], SCHEMA)["audit"]
    assert import_settings(loaded)["channels"] == {
        "render": "ViewLayer.Combined",
        "depth": "ViewLayer.Depth.Z",
    }
    bad = {**good, "channels": {"normals": "ViewLayer.Normal.X"}}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump({"audit": bad}))
    with pytest.raises(ConfigError, match="normals"):
        load_config([REPO / "config.yaml", tmp_path / "bad.yaml"], SCHEMA)
    with pytest.raises(AuditError) as err:
        import_settings(bad)
    assert one_line(err) == (
        "audit.channels has the unknown role 'normals'; use render, depth, segmentation, "
        "disparity, glass_mask"
    )
    with pytest.raises(AuditError, match=r"audit\.channels\.depth is 3, not a channel name"):
        import_settings({**good, "channels": {"depth": 3}})


def test_audit_reads_renders_from_the_layer_audit_channels_names(tmp_path, monkeypatch):
    # each render written with two view layers: refused until audit.channels.render names one
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(
        tmp_path / "d", n_frames=1, width=48, height=32, n_seeds=3
    )
    for view, letter in (("left", "L"), ("right", "R")):
        for s, image in enumerate(frames[0].renders[view]):
            path = settings["renders"].format(frame="f00", view=letter, seed=f"{s:03d}")
            write_parts(path, {
                "Front.Combined": planes("Front.Combined", image),
                "Back.Combined": planes("Back.Combined", np.full_like(image, 0.5)),
            })
    with pytest.raises(ImageError) as err:
        import_audit(settings)
    assert "audit.channels: {render: <one of them>}" in one_line(err)
    import_audit({**settings, "channels": {"render": "Front.Combined"}})
    stored = open_dataset("results/audit/synthetic/renders/f00/right/spp0/seeds0-2.zarr")
    np.testing.assert_array_equal(
        stored["radiance"].transpose("seed", "y", "x", "channel").values,
        frames[0].renders["right"],
    )
