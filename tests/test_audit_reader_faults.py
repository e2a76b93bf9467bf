"""Outside files the audit's readers must name in one line, before any job where the headers
tell: a BlenderProc HDF5 render cut short or not HDF5 at all (in the stereo and the one-view
layout, as a truncated depth file already was), an Infinigen camview with a non-finite pose,
an Infinigen frame whose camview files are missing, a render that is NaN everywhere (a few
NaN pixels still import), and a field given as an RGB image whose channels differ (a grey
image saved as RGB still reads).

Each audit is a tiny synthetic one; ``stereovar audit`` runs with Snakemake replaced by a
stub that fails the test if it is started (the checks before it are under test)."""

from pathlib import Path

import cv2
import h5py
import numpy as np
import pytest
import yaml

from stereovar import cli
from stereovar.audit.importer import import_audit, import_frame
from stereovar.audit.synthetic import synthetic_frame, write_synthetic_audit
from stereovar.errors import AuditError, ImageError
from stereovar.io.images import read_field, read_labels
from stereovar.rig import VIEWS

from .test_audit_formats_infinigen import infinigen_audit

SMALL = {"width": 32, "height": 16, "n_seeds": 4}


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


@pytest.fixture
def audit_before_snakemake(tmp_path, monkeypatch, capsys):
    """``run(settings)``: ``stereovar audit`` of a config holding ``settings`` in
    ``tmp_path``, Snakemake replaced by a stub that fails the test; returns its one
    ``stereovar: error:`` line (exit status 2, nothing on stdout)."""

    def never(args, root):
        raise AssertionError(f"snakemake started: {args}")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "_snakemake", never)

    def run(settings: dict) -> str:
        (tmp_path / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))
        rc = cli.main(["audit", "audit.yaml"])
        captured = capsys.readouterr()
        err = captured.err.splitlines()
        assert rc == 2 and captured.out == "" and len(err) == 1, captured
        assert err[0].startswith("stereovar: error: "), err
        return err[0].removeprefix("stereovar: error: ")

    return run


# -- 1. a BlenderProc HDF5 file that cannot be opened ------------------------------------------


def write_hdf5(path: Path, outputs: dict) -> None:
    """A BlenderProc frame file: each output one gzip-compressed dataset."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with h5py.File(path, "w") as f:
        for key, data in outputs.items():
            f.create_dataset(key, data=data, compression="gzip")


def blenderproc_audit(root: Path, layout: str) -> dict:
    """One frame of 3 seeds as BlenderProc writes it: ``bp/seed_<s>/0.hdf5`` holding both
    views (``stereo``: colors (2, H, W, 3)) or ``0.hdf5`` and ``1.hdf5`` one view each
    (``one-view``), and the left depth in ``d/0.hdf5``; the settings (relative paths)."""
    f = synthetic_frame(width=16, height=8, n_seeds=3, sign=-1, seed=0)
    depth = (10.0 / f.disparity).astype(np.float32)
    for s in range(3):
        if layout == "stereo":
            write_hdf5(root / f"bp/seed_{s}/0.hdf5",
                       {"colors": np.stack([f.renders[v][s] for v in VIEWS])})
        else:
            for k, view in enumerate(VIEWS):
                write_hdf5(root / f"bp/seed_{s}/{k}.hdf5", {"colors": f.renders[view][s]})
    write_hdf5(root / "d/0.hdf5", {"depth": depth})
    settings = {"name": "bp", "depth": "d/0.hdf5", "focal_px": 10.0, "baseline_m": 1.0}
    if layout == "stereo":
        return {**settings, "renders": "bp/seed_{seed}/0.hdf5"}
    return {**settings, "renders": "bp/seed_{seed}/{view}.hdf5",
            "views": {"left": 0, "right": 1}}


def h5py_words(path: Path) -> str:
    """What h5py says opening ``path``, on one line and cut as the audit's line cuts it."""
    with pytest.raises(OSError) as err:
        h5py.File(path, "r")
    return " ".join(str(err.value).split())[:160]


@pytest.mark.parametrize("layout", ["stereo", "one-view"])
@pytest.mark.parametrize("damage", ["truncated", "not HDF5"])
@pytest.mark.parametrize("which", ["render", "depth"])
def test_an_hdf5_file_that_cannot_be_opened_stops_the_audit_before_snakemake(
    tmp_path, audit_before_snakemake, layout, damage, which
):
    settings = blenderproc_audit(tmp_path, layout)
    path = "bp/seed_1/0.hdf5" if which == "render" else "d/0.hdf5"
    data = (tmp_path / path).read_bytes()
    (tmp_path / path).write_bytes(
        data[: len(data) // 2] if damage == "truncated" else b"P6 16 8 255\n" + data[:64]
    )
    expected = (
        f"{path}: cannot read the header ({h5py_words(tmp_path / path)}); it is truncated or "
        "not a valid HDF5 file: write it again"
    )
    assert audit_before_snakemake(settings) == expected
    assert not (tmp_path / "logs").exists() and not (tmp_path / "results").exists()
    if layout == "one-view":  # the import job itself (run without the command) says the same
        with pytest.raises(ImageError) as err:
            import_frame(settings, "frame")
        assert one_line(err) == expected


# -- 2, 3. Infinigen's camview files -----------------------------------------------------------


def test_a_camview_with_a_non_finite_pose_is_named_before_snakemake(
    tmp_path, audit_before_snakemake
):
    settings, *_ = infinigen_audit(tmp_path)
    camview = tmp_path / "ig/seed_0/frames/camview/camera_1/camview_0_0_0048_1.npz"
    stored = dict(np.load(camview))
    stored["T"][0, 3] = np.nan  # the right camera's x
    np.savez(camview, **stored)
    expected = (
        f"{camview}: Infinigen's camview holds a non-finite pose T (1 of its 16 values NaN or "
        "Inf), so it places no camera; export the frame's camview files again "
        "(infinigen.core.placement.camera.save_camera_parameters)"
    )
    assert audit_before_snakemake(settings) == expected
    with pytest.raises(ImageError) as err:  # the import job
        import_audit(settings)
    assert one_line(err) == expected


def test_an_infinigen_depth_without_its_camview_files_names_them_before_snakemake(
    tmp_path, audit_before_snakemake
):
    settings, _, z, _, _ = infinigen_audit(tmp_path)
    frames = tmp_path / "ig/seed_0/frames"
    camviews = [frames / f"camview/camera_{k}/camview_0_0_0048_{k}.npz" for k in (0, 1)]
    for path in camviews:
        path.unlink()
    depth = frames / "Depth/camera_0/Depth_0_0_0048_0.npy"
    big = np.load(depth).shape  # Infinigen's depth: twice the image size
    assert big == (2 * z.shape[0], 2 * z.shape[1])
    expected = (
        f"{depth} is {big[1]}x{big[0]} px, twice the renders' {z.shape[1]}x{z.shape[0]}: "
        "Infinigen's depth, which is read with the frame's camview files, but the camview "
        f"files {camviews[0]} and {camviews[1]} are missing (Infinigen writes them to "
        "frames/camview/camera_<subcam>/ beside frames/Depth/); copy the scene's "
        "frames/camview folder along with the frame"
    )
    assert audit_before_snakemake(settings) == expected
    with pytest.raises(AuditError) as err:  # the import job, focal length and baseline given
        import_audit({**settings, "focal_px": 120.0, "baseline_m": 0.1})
    assert one_line(err) == expected


# -- 4. renders that are NaN everywhere ----------------------------------------------------------


def test_a_render_without_finite_pixels_is_refused_and_a_few_nan_pixels_import(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, render_format="npy",
                                        **SMALL)
    render = Path(settings["renders"].format(frame="f00", view="L", seed="001"))
    image = np.load(render)
    pixels = image.shape[0] * image.shape[1]
    for finite in (0, 1):  # NaN everywhere, or but one pixel
        broken = np.full_like(image, np.nan)
        broken.reshape(-1, 3)[:finite] = 0.5
        np.save(render, broken)
        with pytest.raises(AuditError) as err:
            import_audit(settings)
        assert one_line(err) == (
            f"{render}: {finite} of its {pixels} pixels are finite (the others hold NaN or "
            "Inf), and a render needs at least 2 for any variance to be measured; render this "
            "seed again (a render that is NaN almost everywhere failed: check the renderer's "
            "output)"
        )
    assert not Path("results/audit/synthetic/ground_truth/f00.zarr").exists()
    # two renders NaN in complementary halves: no pixel is finite in all four
    other = Path(settings["renders"].format(frame="f00", view="L", seed="002"))
    kept = np.load(other)
    halves = {render: np.s_[:, : image.shape[1] // 2], other: np.s_[:, image.shape[1] // 2 :]}
    for path, half in halves.items():
        a = kept.copy() if path == other else image.copy()
        a[half] = np.nan
        np.save(path, a)
    with pytest.raises(AuditError) as err:
        import_audit(settings)
    assert one_line(err) == (
        f"frame f00, view left: 0 of the {pixels} pixels are finite in all 4 renders (a pixel "
        "with a NaN or Inf in one render has no variance), and the audit needs at least 2; "
        f"render again the seeds whose renders hold NaN or Inf (e.g. {render}, "
        f"{pixels // 2} pixels)"
    )
    # a few NaN pixels import, counted
    np.save(other, kept)
    a = image.copy()
    a[0, :3] = np.nan
    np.save(render, a)
    report = import_audit({**settings, "sign_check": "warn"})
    assert [f.imported for f in report.frames] == [True]
    assert report.frames[0].nonfinite_pixels == {"left": 3, "right": 0}


# -- 5. a field given as an RGB image -----------------------------------------------------------


@pytest.mark.parametrize(
    ("ext", "role", "words"),
    [("png", "disparity", ("disparity", "disparity")),
     ("tiff", "depth", ("depth", "depth")),
     ("png", "glass_mask", ("a glass mask", "glass mask")),
     ("png", None, ("a field", "field"))],
)
def test_a_field_in_an_rgb_file_is_refused_unless_its_channels_are_equal(
    tmp_path, ext, role, words
):
    rng = np.random.default_rng(5)
    grey = rng.integers(1, 4000, (6, 9)).astype(np.uint16 if ext == "png" else np.float32)
    path = tmp_path / f"field.{ext}"
    # uncompressed: OpenCV's default for a float RGB TIFF, SGILOG, is lossy
    options = [cv2.IMWRITE_TIFF_COMPRESSION, 1] if ext == "tiff" else []
    # a grey image saved as RGB: its one channel is read
    assert cv2.imwrite(str(path), np.stack([grey] * 3, axis=-1), options)
    np.testing.assert_array_equal(read_field(path, role=role), grey.astype(np.float32))
    # channels that differ (a colour-mapped picture, or a field in one of them): refused
    assert cv2.imwrite(str(path), np.stack([grey, grey // 2, grey], axis=-1), options)
    with pytest.raises(ImageError) as err:
        read_field(path, role=role)
    what, plain = words
    assert one_line(err) == (
        f"{path}: {what} given as 3 channels (R, G, B) that differ, so which of them holds "
        f"the {plain}, or whether the file is a colour-mapped picture of it, is not for the "
        f"reader to guess; write the {plain} as one channel (a grey PNG or TIFF, or EXR, PFM "
        "or NPY)"
    )


def test_an_rgb_disparity_png_stops_the_import_and_rgb_segment_ids_are_refused(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, disparity_format="png",
                                        **SMALL)
    png = Path(settings["disparity"].format(frame="f00"))
    codes = cv2.imread(str(png), cv2.IMREAD_UNCHANGED)
    assert codes.ndim == 2  # KITTI's encoding: one 16-bit channel
    assert cv2.imwrite(str(png), np.stack([codes, np.zeros_like(codes), codes], axis=-1))
    with pytest.raises(ImageError) as err:
        import_audit({**settings, "sign_check": "warn"})
    assert one_line(err).startswith(f"{png}: disparity given as 3 channels (R, G, B) that "
                                    "differ, so which of them holds the disparity")
    assert not Path("results").exists()
    seg = tmp_path / "seg.png"
    ids = np.arange(54, dtype=np.uint8).reshape(6, 9)
    assert cv2.imwrite(str(seg), np.stack([ids, ids, ids + 1], axis=-1))
    with pytest.raises(ImageError, match=r"a segmentation given as 3 channels \(R, G, B\)"):
        read_labels(seg)
    assert cv2.imwrite(str(seg), np.stack([ids] * 3, axis=-1))
    np.testing.assert_array_equal(read_labels(seg), ids)
