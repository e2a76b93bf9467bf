"""Infinigen's frame folders read by meaning: ``frames/Image/camera_<i>/Image_*.exr``,
``frames/Depth/camera_<i>/Depth_*.npy`` (planar depth at twice the image size, ``DBL_MAX``
where nothing is hit), ``frames/ObjectSegmentation/...`` and
``frames/camview/camera_<i>/camview_*.npz`` (``K``, ``T``, ``HW``), whose poses give the
focal length, the baseline and which camera is to the right.

Files: written in-test to Infinigen's specification (Infinigen installs only with its own
Blender and compiled ground-truth tools; its files are plain NumPy ones): the names
``<Pass>_<rig>_<resample>_<frame>_<subcam>`` (``src/infinigen/tools/suffixes.py`` lines
9-28) filed under ``frames/<Pass>/camera_<subcam>/`` (``tools/datarelease_toolkit.py``
lines 314-337), ``np.savez(K, T, HW)`` with ``T`` the camera-to-world pose in OpenCV axes
(``core/placement/camera.py`` lines 834-866), the depth as the OpenGL ground truth saves it
(``datagen/customgt/main.cpp`` lines 200-205 and 399-419: float64, 2H x 2W, ``DBL_MAX`` for
no hit).
"""

from pathlib import Path

import cv2
import numpy as np
import pytest

from stereovar.audit.generators import downsample_2x
from stereovar.audit.importer import import_audit
from stereovar.errors import AuditError, ImageError
from stereovar.io.writers import write_image
from stereovar.rig import VIEWS

from .audit_formats import (
    BASELINE_M,
    FOCAL_PX,
    assert_same_import,
    frame,
    stores,
    write_exr_reference,
)

NO_HIT = np.finfo(np.float64).max
"""What Infinigen's OpenGL depth holds where nothing is hit."""


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def rotation(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def camview(path: Path, *, height, width, pose) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    K = np.array([[FOCAL_PX, 0, width / 2], [0, FOCAL_PX, height / 2], [0, 0, 1]], np.float64)
    np.savez(path, K=K, T=pose, HW=np.array((height, width)))


def poses(*, right_offset=(BASELINE_M, 0.0, 0.0), right_yaw=0.0):
    """Camera-to-world poses (OpenCV axes) of a rig turned 0.3 rad: the right camera moved by
    ``right_offset`` in the left camera's frame."""
    left = np.eye(4)
    left[:3, :3], left[:3, 3] = rotation(0.3), (1.0, 2.0, 0.5)
    right = np.eye(4)
    right[:3, :3] = rotation(0.3 + right_yaw)
    right[:3, 3] = left[:3, 3] + left[:3, :3] @ np.asarray(right_offset)
    return {"left": left, "right": right}


def infinigen_audit(root: Path, *, frame_id="0048", **pose_options):
    """The synthetic frame as Infinigen's frame folders, one scene folder per seed (EXR
    images; seed 0 with the depth, object segmentation and camviews)."""
    f, z, d = frame()
    height, width = z.shape
    big = np.kron(z.astype(np.float64), np.ones((2, 2)))  # 2H x 2W
    big[:4] = NO_HIT  # nothing hit in the top two image rows
    seg = np.where(np.arange(width)[None, :] < 10, 7, 1).repeat(height, 0).astype(np.int32)
    for s in range(f.renders["left"].shape[0]):
        frames = root / f"ig/seed_{s}/frames"
        for k, view in enumerate(VIEWS):
            suffix = f"_0_0_{frame_id}_{k}"
            path = frames / f"Image/camera_{k}/Image{suffix}.exr"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_image(path, f.renders[view][s])
            if s == 0:
                for kind, data in (("Depth", big), ("ObjectSegmentation", seg)):
                    out = frames / f"{kind}/camera_{k}/{kind}{suffix}.npy"
                    out.parent.mkdir(parents=True, exist_ok=True)
                    np.save(out, data)
                camview(frames / f"camview/camera_{k}/camview{suffix}.npz", height=height,
                        width=width, pose=poses(**pose_options)[view])
    settings = {
        "name": "ig",
        "renders": f"{root}/ig/seed_{{seed}}/frames/Image/camera_{{view}}/"
                   "Image_0_0_{frame}_{view}.exr",
        "views": {"left": 0, "right": 1},
        "depth": f"{root}/ig/seed_0/frames/Depth/camera_0/Depth_0_0_{{frame}}_0.npy",
        "segmentation": f"{root}/ig/seed_0/frames/ObjectSegmentation/camera_0/"
                        "ObjectSegmentation_0_0_{frame}_0.npy",
        "glass_ids": [7],
    }
    return settings, f, z, d, seg


def test_infinigen_depth_is_brought_to_the_image_size_as_infinigens_own_tool_does():
    rng = np.random.default_rng(1)
    big = rng.uniform(1.0, 5.0, (12, 16))
    # rigid_warp.py: cv2.resize(depth, dsize=(W, H), interpolation=cv2.INTER_LINEAR)
    ours = downsample_2x(big)
    theirs = cv2.resize(big, dsize=(8, 6), interpolation=cv2.INTER_LINEAR)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12)
    big[0, 0] = NO_HIT
    assert np.isnan(downsample_2x(big)[0, 0]) and np.isfinite(downsample_2x(big)[0, 1])


def test_infinigen_round_trip_and_the_same_import_as_exr(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, f, z, d, seg = infinigen_audit(tmp_path)
    report = import_audit(settings)  # no focal_px, no baseline_m: the camviews give them
    assert report.discovery.summary() == "1 frame × 2 views × 4 seeds"
    got = stores("ig", "0048")
    for view in VIEWS:
        np.testing.assert_array_equal(got[view]["radiance"].values, f.renders[view])
    gt = got["ground_truth"]
    assert gt.attrs["focal_px"] == FOCAL_PX
    assert gt.attrs["baseline_m"] == pytest.approx(BASELINE_M, rel=1e-12)
    assert sum("camview" in p for p in gt.attrs["source_files"]) == 2
    left = gt.sel(view="left")
    hit = np.broadcast_to(np.arange(z.shape[0])[:, None] >= 2, z.shape)
    np.testing.assert_array_equal(left["valid"].values, f.valid & hit)
    np.testing.assert_allclose(left["depth"].values[hit], z[hit], rtol=1e-7)
    np.testing.assert_allclose(left["disparity"].values, np.where(f.valid & hit, d, 0),
                               rtol=1e-6)
    np.testing.assert_array_equal(left["glass"].values, seg == 7)
    # the same frames as EXR renders and an EXR planar depth (NaN where nothing is hit)
    no_hit = np.where(hit, z, np.nan).astype(np.float32)
    reference = write_exr_reference(tmp_path / "exr", f.renders, no_hit, frame_name="0048")
    np.save(tmp_path / "exr/seg_0048.npy", seg)
    import_audit({**reference, "segmentation": f"{tmp_path}/exr/seg_{{frame}}.npy",
                  "glass_ids": [7]})
    assert_same_import(got, stores("exr", "0048"))


def test_the_camera_poses_decide_the_convention_and_a_pair_that_is_not_rectified_is_refused(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, *_ = infinigen_audit(tmp_path / "a")
    views = [f"{tmp_path}/a/ig/seed_0/frames/camview/camera_{k}/camview_0_0_0048_{k}.npz"
             for k in (0, 1)]
    with pytest.raises(AuditError) as err:
        import_audit({**settings, "convention": "paper"})
    assert one_line(err) == (
        f"frame 0048: the camera poses of {views[0]} and {views[1]} put the right view's camera "
        "0.1 m to the right of the left one (x_R = x_L - d) but audit.convention is paper "
        "(x_R = x_L + d); set audit.convention: conventional, or swap audit.views if the views "
        "are the other way round"
    )
    with pytest.raises(AuditError) as err:
        import_audit({**settings, "baseline_m": 0.12})
    assert one_line(err) == (
        f"audit.baseline_m is 0.12 m but {views[0]} and {views[1]} gives 0.1 m; remove "
        "audit.baseline_m to use the generator's camera, or set it to 0.1"
    )
    settings, *_ = infinigen_audit(tmp_path / "b", right_yaw=0.05)
    with pytest.raises(AuditError, match=r"the cameras are not a rectified pair \(turned "
                                          r"0\.05 rad apart"):
        import_audit(settings)
    settings, *_ = infinigen_audit(tmp_path / "c", right_offset=(BASELINE_M, 0.01, 0.0))
    with pytest.raises(AuditError, match="the second offset 0.1 of the baseline"):
        import_audit(settings)
    assert not Path("results/audit/ig/ground_truth").exists()


def test_infinigen_instance_segmentation_and_a_depth_of_another_size_are_refused(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, *_ = infinigen_audit(tmp_path)
    frames = tmp_path / "ig/seed_0/frames"
    instance = frames / "InstanceSegmentation/camera_0/InstanceSegmentation_0_0_0048_0.npy"
    instance.parent.mkdir(parents=True)
    np.save(instance, np.zeros((32, 48, 3), np.int32))
    with pytest.raises(ImageError) as err:
        import_audit({**settings, "segmentation": str(instance).replace("0048", "{frame}")})
    assert one_line(err) == (
        f"{instance}: a segmentation of shape (32, 48, 3), 3 values per pixel, and which one "
        "is the segment id is not for the reader to guess; give one id per pixel, (H, W) "
        "(Infinigen: ObjectSegmentation_*.npy, not InstanceSegmentation)"
    )
    depth = frames / "Depth/camera_0/Depth_0_0_0048_0.npy"
    np.save(depth, np.ones((96, 144)))  # three times the image size
    with pytest.raises(AuditError, match=r"Depth_0_0_0048_0\.npy is 144x96 px but"):
        import_audit(settings)
