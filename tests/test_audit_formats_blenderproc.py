"""BlenderProc's HDF5 output read by meaning.

Files: ``tests/fixtures/generators/blenderproc/*.hdf5`` were written by BlenderProc 2.8.0's
own ``bproc.writer.write_hdf5`` (``tests/fixtures/generators/make_blenderproc.py``; the
package installs here only as its writer module, not as its command-line tool, so the
fixtures are committed). The larger frames below are written in-test to the same
specification, checked against those fixtures: one file per frame, one gzip-compressed
dataset per output key (``colors``, ``depth``, ``*_segmaps``, ``normals``), a stereo render
stacking the views on a leading axis of 2 (``[0]`` left), or ``<key>_0``/``<key>_1`` with
``stereo_separate_keys`` (``blenderproc/python/writer/WriterUtility.py``, ``write_hdf5``
lines 25-93, ``write_to_hdf_file`` lines 344-365).
"""

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from stereovar.audit.importer import import_audit, import_record
from stereovar.errors import AuditError, ImageError
from stereovar.io import hdf5
from stereovar.io.headers import image_size
from stereovar.io.images import read_field, read_image, read_labels
from stereovar.io.transfer import srgb_to_linear
from stereovar.rig import VIEWS

from .audit_formats import (
    BASELINE_M,
    FOCAL_PX,
    assert_same_import,
    frame,
    stores,
    write_exr_reference,
)

FIXTURES = Path(__file__).parent / "fixtures" / "generators" / "blenderproc"


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def write_blenderproc(path: Path, outputs: dict) -> Path:
    """One frame's file as ``write_hdf5`` writes it: each output a gzip-compressed dataset,
    the version as bytes."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as f:
        for key, data in outputs.items():
            f.create_dataset(key, data=data, compression="gzip")
        f.create_dataset("blender_proc_version", data=np.bytes_("2.8.0"))
    return path


def stereo_audit(root: Path, colors=None, **extra) -> tuple:
    """The synthetic frame as one stereo HDF5 file per seed (``bp/seed_<s>/0.hdf5``: colors
    (2, H, W, 3), planar depth (2, H, W), segmentation, normals)."""
    f, depth, d = frame()
    seg = np.where(np.arange(f.disparity.shape[1])[None, :] < 10, 3, 1).astype(np.int32)
    seg = np.broadcast_to(seg, f.disparity.shape)
    for s in range(f.renders["left"].shape[0]):
        pair = np.stack([f.renders[v][s] for v in VIEWS])
        write_blenderproc(root / f"bp/seed_{s:03d}/0.hdf5", {
            "colors": pair if colors is None else colors(pair),
            "depth": np.stack([depth, depth]),
            "instance_segmaps": np.stack([seg, seg]),
            "normals": np.zeros((2, *depth.shape, 3), np.float32),
        })
    settings = {
        "name": "bp",
        "renders": f"{root}/bp/seed_{{seed}}/{{frame}}.hdf5",
        "depth": f"{root}/bp/seed_000/{{frame}}.hdf5",
        "focal_px": FOCAL_PX,
        "baseline_m": BASELINE_M,
        **extra,
    }
    return settings, f, depth, d


# -- the generator's own files ---------------------------------------------------------------


def test_files_written_by_blenderproc_are_read_by_meaning():
    expected = np.load(FIXTURES / "expected.npz")
    stereo = FIXTURES / "stereo_0.hdf5"
    assert image_size(stereo) == (6, 8)
    assert hdf5.render_views(stereo) == 2 and hdf5.render_dtype(stereo) == np.uint8
    for k in range(2):  # [0] left, [1] right; 8-bit colors are sRGB-decoded
        np.testing.assert_allclose(
            read_image(stereo, view=k), srgb_to_linear(expected["colors"][k] / 255.0), rtol=1e-6
        )
        np.testing.assert_array_equal(read_field(stereo, role="depth", view=k),
                                      expected["depth"][k])
    # two segmaps: which one is the segmentation is not guessed
    with pytest.raises(ImageError) as err:
        read_labels(stereo)
    assert one_line(err) == (
        f"{stereo}: several segmentation channels (class_segmaps, instance_segmaps); "
        "set audit.channels: {segmentation: <one of them>}"
    )
    np.testing.assert_array_equal(read_labels(stereo, channel="instance_segmaps", view=1),
                                  expected["inst"][1])
    # stereo_separate_keys: colors_0, colors_1 are the same two views
    separate = FIXTURES / "separate_0.hdf5"
    assert hdf5.render_views(separate) == 2
    for k in range(2):
        np.testing.assert_array_equal(read_image(separate, view=k), read_image(stereo, view=k))
        np.testing.assert_array_equal(read_field(separate, role="depth", view=k),
                                      expected["depth"][k])
    # float colors are linear; distance is ray distance, and the file holds no camera
    mono = FIXTURES / "mono_float_0.hdf5"
    assert hdf5.render_views(mono) == 1 and hdf5.render_dtype(mono) == np.float32
    np.testing.assert_allclose(read_image(mono), expected["colors"][0] / 255.0, rtol=1e-6)
    with pytest.raises(ImageError) as err:
        read_field(mono, role="depth")
    assert one_line(err) == (
        f"{mono}: channel 'distance' is ray distance (BlenderProc's distance output), not "
        "planar depth, and d = f B / z needs planar depth; export depth "
        "(bproc.renderer.enable_depth_output) or give audit.disparity"
    )


# -- round trip and the same numbers as EXR ------------------------------------------------------


def test_stereo_hdf5_round_trip_and_the_same_import_as_exr(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, f, depth, d = stereo_audit(
        tmp_path, segmentation=f"{tmp_path}/bp/seed_000/{{frame}}.hdf5", glass_ids=[3],
        channels={"segmentation": "instance_segmaps"},
    )
    report = import_audit(settings)
    assert report.discovery.summary() == "1 frame × 2 views × 4 seeds"
    assert not report.warnings  # float colors: linear, no transfer assumed
    got = stores("bp", "0")
    for view in VIEWS:  # the files' renders, bit for bit, each view from its own slice
        np.testing.assert_array_equal(got[view]["radiance"].values, f.renders[view])
    left = got["ground_truth"].sel(view="left")
    np.testing.assert_allclose(left["disparity"].values,
                               np.where(f.valid, d, 0), rtol=1e-5)
    np.testing.assert_allclose(left["depth"].values, depth, rtol=1e-7)
    glass = np.broadcast_to(np.arange(f.disparity.shape[1])[None, :] < 10, f.disparity.shape)
    np.testing.assert_array_equal(left["glass"].values, glass)
    assert got["ground_truth"].attrs["focal_px"] == FOCAL_PX
    # the same frame as EXR renders and an EXR depth: the same stores and numbers
    reference = write_exr_reference(tmp_path / "exr", f.renders, depth, frame_name="0")
    np.save(tmp_path / "exr" / "seg_0.npy", np.where(glass, 3, 1).astype(np.int32))
    import_audit({**reference, "segmentation": f"{tmp_path}/exr/seg_{{frame}}.npy",
                  "glass_ids": [3]})
    assert_same_import(got, stores("exr", "0"))


def test_eight_bit_colors_are_decoded_as_srgb_with_the_warnings_of_8_bit_png(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)

    def to_8bit(pair):  # BlenderProc's default: the render through a transfer into uint8
        v = np.clip(pair, 0, 1) ** (1 / 2.2)
        return np.round(v * 255).astype(np.uint8)

    settings, f, _, _ = stereo_audit(tmp_path, colors=to_8bit, sign_check="warn")
    report = import_audit(settings)
    got = stores("bp", "0")
    with h5py.File(tmp_path / "bp/seed_002/0.hdf5") as h:
        stored = h["colors"][1]
    np.testing.assert_allclose(got["right"]["radiance"].values[2],
                               srgb_to_linear(stored / 255.0), rtol=1e-6)
    kinds = [flag["kind"] for flag in report.flags]
    assert kinds.count("transfer") == 1
    (transfer,) = [w for w in report.warnings if "BlenderProc" in w]
    assert transfer.startswith("BlenderProc 8-bit colors without audit.transfer are decoded as "
                               "sRGB, which does not undo Blender's view transform")
    record = Path(import_record("bp", "0")).read_text()
    assert '"floored"' in record
    same = (got["left"]["radiance"].values == got["left"]["radiance"].values[:1]).all(axis=(0, 3))
    valid = got["ground_truth"].sel(view="left")["valid"].values
    found = json.loads(record)["found"]
    assert found["floored"]["left"] == pytest.approx((same & valid).sum() / valid.sum())


def test_one_view_per_file_with_view_in_the_path_and_refusals(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f, depth, d = frame()
    for s in range(4):  # BlenderProc without stereo: two camera poses, 0.hdf5 and 1.hdf5
        for k, view in enumerate(VIEWS):
            write_blenderproc(tmp_path / f"mono/seed_{s}/{k}.hdf5",
                              {"colors": f.renders[view][s], "depth": depth})
    settings = {"name": "mono", "renders": f"{tmp_path}/mono/seed_{{seed}}/{{view}}.hdf5",
                "views": {"left": 0, "right": 1}, "depth": f"{tmp_path}/mono/seed_0/0.hdf5",
                "focal_px": FOCAL_PX, "baseline_m": BASELINE_M}
    import_audit(settings)
    got = stores("mono", "frame")
    for view in VIEWS:
        np.testing.assert_array_equal(got[view]["radiance"].values, f.renders[view])
    # a template without {view} needs files that hold both views
    with pytest.raises(AuditError) as err:
        import_audit({**settings, "renders": f"{tmp_path}/mono/seed_{{seed}}/0.hdf5"})
    assert one_line(err).startswith(
        f"{tmp_path}/mono/seed_0/0.hdf5: its render holds one view, and audit.renders "
    )
    # ray distance only: refused, the file stating no camera to convert it
    write_blenderproc(tmp_path / "dist/0.hdf5", {"colors": f.renders["left"][0],
                                                 "distance": depth})
    with pytest.raises(ImageError, match="is ray distance .* not planar depth"):
        import_audit({**settings, "depth": f"{tmp_path}/dist/0.hdf5"})
    assert not Path("results/audit/mono/ground_truth/frame.zarr").with_suffix(".tmp").exists()
