"""Kubric's outputs read by meaning: ``rgba_%05d.png``, ``depth_%05d.tiff`` (the distance from
the camera centre, converted to planar depth with the camera of ``metadata.json``),
``segmentation_%05d.png`` (palette indices are the segment ids).

Files: ``tests/fixtures/generators/kubric/scene/`` was written by kubric-nightly
2023.12.27's own ``kubric.file_io`` (``write_depth_batch``, ``write_segmentation_batch``,
``write_rgba_batch``, ``write_json``) with the ray distance from its own
``PerspectiveCamera.z_to_depth`` (``tests/fixtures/generators/make_kubric.py``; Kubric does not
install here: it imports TensorFlow and its own Blender build). The frames below are written
in-test to the same specification: an 8-bit RGBA PNG, a float32 one-channel TIFF, an 8-bit
palette PNG, and ``metadata.json`` with ``camera.focal_length``, ``camera.sensor_width`` (mm)
and ``metadata.resolution`` (``kubric/file_io.py`` lines 120-143, 189-196, 266-279;
``kubric/utils.py`` lines 132-156).
"""

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from stereovar.audit.generators import kubric_planar_depth, read_camera, read_depth
from stereovar.audit.importer import import_audit
from stereovar.errors import AuditError, ImageError
from stereovar.io.images import read_image, read_labels
from stereovar.io.transfer import linear_to_srgb, srgb_to_linear
from stereovar.rig import VIEWS

from .audit_formats import FOCAL_PX, assert_same_import, frame, stores, write_exr_reference

FIXTURES = Path(__file__).parent / "fixtures" / "generators" / "kubric"
FOCAL_MM = 35.0
SENSOR_MM = FOCAL_MM * 48 / FOCAL_PX  # 14 mm: 120 px at 48 px wide


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def ray_distance(z, *, focal_mm, sensor_mm):
    """Kubric's depth from planar depth, written out from its definition: the length of the
    ray to the pixel centre's point, whose sensor position (u, v) in mm lies at focal length
    f_mm: r = z * |(u, v, f_mm)| / f_mm."""
    height, width = z.shape
    out = np.empty((height, width))
    for j in range(height):
        for i in range(width):
            u = (i + 0.5 - width / 2) * sensor_mm / width
            v = (j + 0.5 - height / 2) * sensor_mm / width
            out[j, i] = z[j, i] * np.sqrt(u * u + v * v + focal_mm**2) / focal_mm
    return out


def metadata(folder: Path, width: int, height: int, *, focal_mm=FOCAL_MM) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "metadata.json").write_text(json.dumps({
        "metadata": {"resolution": [width, height], "num_frames": 1},
        "camera": {"focal_length": focal_mm, "sensor_width": SENSOR_MM,
                   "field_of_view": 2 * np.arctan2(SENSOR_MM / 2, focal_mm)},
    }))


def rgba_png(path: Path, image) -> np.ndarray:
    """An 8-bit RGBA PNG of a linear image (sRGB-encoded, alpha 255); returns its bytes."""
    q = np.round(linear_to_srgb(np.clip(image, 0, 1)) * 255).astype(np.uint8)
    rgba = np.concatenate([q, np.full(q.shape[:2] + (1,), 255, np.uint8)], axis=-1)
    path.parent.mkdir(parents=True, exist_ok=True)
    assert cv2.imwrite(str(path), rgba[..., [2, 1, 0, 3]])
    return q


def kubric_audit(root: Path):
    """The synthetic frame as Kubric writes frame 0 of a scene, one scene folder per view
    and seed; depth and segmentation in seed 0's folders."""
    f, z, d = frame()
    height, width = z.shape
    decoded = {v: np.empty_like(f.renders[v]) for v in VIEWS}
    seg = np.where(np.arange(width)[None, :] < 10, 5, 2).astype(np.uint8).repeat(height, 0)
    for s in range(f.renders["left"].shape[0]):
        for view, letter in zip(VIEWS, "LR", strict=True):
            folder = root / f"kb/seed_{s}/{letter}"
            q = rgba_png(folder / "rgba_00000.png", f.renders[view][s])
            decoded[view][s] = srgb_to_linear(q / 255.0)
            metadata(folder, width, height)
            ray = ray_distance(z, focal_mm=FOCAL_MM, sensor_mm=SENSOR_MM).astype(np.float32)
            assert cv2.imwrite(str(folder / "depth_00000.tiff"), ray)
            image = Image.fromarray(seg, mode="P")
            image.putpalette([0, 0, 0, 200, 30, 30, 30, 200, 30, 30, 30, 200, 90, 90, 0,
                              250, 250, 250])
            image.save(folder / "segmentation_00000.png")
    settings = {
        "name": "kb",
        "renders": f"{root}/kb/seed_{{seed}}/{{view}}/rgba_{{frame}}.png",
        "views": {"left": "L", "right": "R"},
        "depth": f"{root}/kb/seed_0/L/depth_{{frame}}.tiff",
        "segmentation": f"{root}/kb/seed_0/L/segmentation_{{frame}}.png",
        "glass_ids": [5],
        "baseline_m": 0.1,
        "transfer": "srgb",
    }
    return settings, f, z, d, decoded, seg


def test_files_written_by_kubric_are_read_by_meaning():
    expected = np.load(FIXTURES / "expected.npz")
    scene = FIXTURES / "scene"
    camera = read_camera(scene / "metadata.json")
    assert camera.size == (6, 8) and camera.focal_px == pytest.approx(35.0 / 32.0 * 8)
    # the TIFF holds Kubric's own z_to_depth of a known planar depth: converted back
    z = read_depth(scene / "depth_00000.tiff", size=(6, 8), camera=camera)
    np.testing.assert_allclose(z, expected["z"], rtol=2e-7)
    # the palette PNG's indices are the ids (OpenCV alone would give the palette's colours)
    np.testing.assert_array_equal(read_labels(scene / "segmentation_00000.png"), expected["seg"])
    np.testing.assert_allclose(read_image(scene / "rgba_00000.png", transfer="srgb"),
                               srgb_to_linear(expected["rgba"][..., :3] / 255.0), rtol=1e-6)


def test_planar_depth_from_kubric_depth_against_the_ray_written_out():
    z = np.linspace(1.0, 9.0, 7 * 10).reshape(7, 10)
    ray = ray_distance(z, focal_mm=20.0, sensor_mm=36.0)
    assert (ray > z).all()  # a ray distance is longer than the depth off the axis
    np.testing.assert_allclose(kubric_planar_depth(ray, focal_mm=20.0, sensor_mm=36.0), z,
                               rtol=1e-12)


def test_kubric_round_trip_and_the_same_import_as_exr(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, f, z, d, decoded, seg = kubric_audit(tmp_path)
    import_audit(settings)
    got = stores("kb", "00000")
    for view in VIEWS:
        np.testing.assert_array_equal(got[view]["radiance"].values, decoded[view])
    gt = got["ground_truth"]
    assert gt.attrs["focal_px"] == pytest.approx(FOCAL_PX)  # from metadata.json
    left = gt.sel(view="left")
    np.testing.assert_allclose(left["depth"].values, z, rtol=1e-6)  # planar, not the ray
    np.testing.assert_allclose(left["disparity"].values, np.where(f.valid, d, 0),
                               rtol=1e-5)
    np.testing.assert_array_equal(left["glass"].values, seg == 5)
    assert any(p.endswith("L/metadata.json") for p in gt.attrs["source_files"])
    # the same frames as EXR renders (the PNGs' decoded values) and an EXR planar depth
    reference = write_exr_reference(tmp_path / "exr", decoded, z, frame_name="00000")
    np.save(tmp_path / "exr/seg_00000.npy", seg.astype(np.int32))
    import_audit({**reference, "segmentation": f"{tmp_path}/exr/seg_{{frame}}.npy",
                  "glass_ids": [5]})
    assert_same_import(got, stores("exr", "00000"))


def test_a_tiff_depth_without_kubric_metadata_is_refused_with_the_choices(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, *_ = kubric_audit(tmp_path)
    (tmp_path / "kb/seed_0/L/metadata.json").unlink()
    (tmp_path / "kb/seed_0/R/metadata.json").unlink()
    with pytest.raises(ImageError) as err:
        import_audit(settings)
    depth = tmp_path / "kb/seed_0/L/depth_00000.tiff"
    assert one_line(err) == (
        f"{depth}: a TIFF depth map says not whether it holds planar depth or the distance "
        "from the camera centre (Kubric's depth_%05d.tiff holds the latter); put Kubric's "
        "metadata.json beside it (its camera converts the distance to planar depth), or "
        "give planar depth as EXR, NPY or PFM"
    )
    assert not Path("results/audit/kb/ground_truth").exists()


def test_kubric_camera_that_contradicts_the_settings_or_the_images_is_refused(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, *_ = kubric_audit(tmp_path)
    with pytest.raises(AuditError) as err:
        import_audit({**settings, "focal_px": 100.0})
    assert one_line(err) == (
        f"audit.focal_px is 100 px but {tmp_path}/kb/seed_0/L/metadata.json gives 120 px; "
        "remove audit.focal_px to use the generator's camera, or set it to 120"
    )
    metadata(tmp_path / "kb/seed_0/R", 64, 32)
    with pytest.raises(AuditError, match=r"gives the image size 64x32 but the renders of frame "
                                          r"00000 are 48x32"):
        import_audit(settings)
