"""The audit's matched null passes through the data's own encoding: the import records how
each frame's renders were stored (``bit_depth``, ``transfer``, ``full_scale``,
``file_format``), the variance store carries it, the calibration draws the null through it
(stereovar.jobs.calibration.scene_frames) and the verdict page says which encoding that was
(stereovar.audit.verdict.null_encoding)."""

from __future__ import annotations

import json
import os
from glob import glob
from pathlib import Path

import cv2
import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from stereovar import layout
from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.audit.verdict import HALF_FLOAT_NULL, null_encoding
from stereovar.calibration.pipelines import dn_law, exposure_for, integer_roundtrip
from stereovar.calibration.replicates import scene_calibration
from stereovar.calibration.scene_frames import SceneFrames
from stereovar.calibration.synthesis import draw_frames
from stereovar.calibration.view_statistics import statistic_rows
from stereovar.errors import AuditError
from stereovar.estimators.seeds import variance_field
from stereovar.io.images import read_image
from stereovar.io.store import open_dataset
from stereovar.io.tables import write_tables
from stereovar.io.transfer import linear_to_srgb
from stereovar.io.writers import write_image
from stereovar.jobs.calibration import scene_frames
from stereovar.jobs.variance import variance_job
from stereovar.rig import VIEWS
from stereovar.statistics.fields import AnalysisSettings

SMALL = {"width": 64, "height": 40, "n_seeds": 4}
SCALE = 2.0


def png_audit(root: Path, *, depths=None, **settings):
    """One synthetic frame written as PNG renders (8-bit sRGB of ``value / SCALE``; ``depths``:
    ``(letter, seed)`` to 16 for a 16-bit file among them) and the settings that read them
    (``audit.scale`` = ``SCALE``, ``audit.transfer`` not set unless given)."""
    base, _ = write_synthetic_audit(root, n_frames=1, render_format="npy", **SMALL)
    for letter in "LR":
        for s in range(SMALL["n_seeds"]):
            npy = base["renders"].format(frame="f00", view=letter, seed=f"{s:03d}")
            v = linear_to_srgb(np.clip(np.load(npy) / SCALE, 0.0, 1.0))
            bits = (depths or {}).get((letter, s), 8)
            q = np.round(v * (2**bits - 1)).astype(np.uint8 if bits == 8 else np.uint16)
            assert cv2.imwrite(npy.replace(".npy", ".png"), q[..., ::-1])
            os.remove(npy)
    return {**base, "renders": base["renders"].replace(".npy", ".png"), "scale": SCALE,
            **settings}


def render_attrs(name: str) -> dict:
    return {
        view: open_dataset(glob(f"results/audit/{name}/renders/f00/{view}/spp*/*.zarr")[0]).attrs
        for view in VIEWS
    }


def variance_of(name: str) -> tuple[str, str]:
    """The frame's seeds variance store (written here) and its ground-truth store."""
    source = layout.audit_source(name)
    stores = {v: glob(f"results/audit/{name}/renders/f00/{v}/spp*/*.zarr") for v in VIEWS}
    out = layout.variance_store(source, "seeds", "f00", 0)
    variance_job(stores["left"], stores["right"], out)
    return out, layout.ground_truth_store(source, "f00")


STORED = ("bit_depth", "transfer", "full_scale", "file_format")


def test_an_8bit_png_import_records_its_encoding_in_the_render_and_variance_stores(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings = png_audit(tmp_path / "d")
    import_audit(settings)  # audit.transfer not set: decoded as sRGB, and recorded so
    expected = {"bit_depth": 8, "transfer": "srgb", "full_scale": SCALE, "file_format": "PNG"}
    for view, attrs in render_attrs("synthetic").items():
        assert {k: attrs[k] for k in STORED} == expected, view
    variance, _ = variance_of("synthetic")
    assert {k: open_dataset(variance).attrs[k] for k in STORED} == expected
    # the transfer actually used: audit.transfer when it is set
    import_audit({**settings, "name": "lin", "transfer": "linear"})
    assert {a["transfer"] for a in render_attrs("lin").values()} == {"linear"}


def test_scene_frames_takes_the_encoding_of_integer_renders_and_none_for_float(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    import_audit(png_audit(tmp_path / "png"))
    scene = scene_frames(*variance_of("synthetic"))
    assert scene.encoding == {"bits": 8, "transfer": "srgb", "scale": SCALE}
    exr, _ = write_synthetic_audit(tmp_path / "exr", name="exr", n_frames=1, **SMALL)
    import_audit(exr)
    for attrs in render_attrs("exr").values():
        assert {k: attrs[k] for k in STORED} == {
            "bit_depth": 0, "transfer": "linear", "full_scale": 0.0, "file_format": "EXR"}
    assert scene_frames(*variance_of("exr")).encoding is None


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def test_renders_stored_at_different_depths_are_refused(tmp_path, monkeypatch):
    """One encoding draws the matched null of a frame: a view whose files mix depths, or
    two views stored differently, stop the import with one line naming the files."""
    monkeypatch.chdir(tmp_path)
    mixed = png_audit(tmp_path / "view", depths={("L", 1): 16})
    with pytest.raises(AuditError) as err:
        import_audit(mixed)
    text = one_line(err)
    assert text.startswith("frame f00, view left: its renders are stored at different depths")
    assert "8-bit integer" in text and "16-bit integer" in text and "L/seed_001.png" in text
    right16 = png_audit(tmp_path / "frame", depths={("R", s): 16 for s in range(4)})
    with pytest.raises(AuditError) as err:
        import_audit({**right16, "name": "views"})
    assert one_line(err).startswith(
        "frame f00: its left renders are 8-bit integer (") and "right renders 16-bit" in str(
        err.value)


# -- the page's sentence -------------------------------------------------------------------


def test_the_sentence_names_the_encoding_of_each_kind_of_renders():
    png = {"scene": "f00", "bit_depth": 8, "transfer": "srgb", "file_format": "PNG"}
    exr = {"scene": "f01", "bit_depth": 0, "transfer": "linear", "file_format": "EXR"}
    assert null_encoding([png]) == (
        "The matched null was drawn in 8-bit sRGB, as the PNG files were.")
    assert null_encoding([{**png, "bit_depth": 16, "transfer": "linear",
                           "file_format": "HDF5"}]) == (
        "The matched null was drawn in 16-bit linear, as the HDF5 files were.")
    assert null_encoding([exr]) == "The matched null was drawn in float, as the EXR files were."
    half = [{"frame": "f01", "found": {"half": {"left": 0.3, "right": 0.2}}}]
    assert null_encoding([exr], half) == f"The matched null was drawn in {HALF_FLOAT_NULL}."
    assert HALF_FLOAT_NULL == (
        "float: the renders' half-float storage is not reproduced by the null")
    assert null_encoding([png, exr]) == (
        "The matched null was drawn in each frame's own encoding: 8-bit sRGB, as the PNG files "
        "were (f00); float, as the EXR files were (f01).")
    # stores imported before the import recorded the encoding: the null was drawn in float
    assert "import the frames again" in null_encoding([{"scene": "f00"}])
    assert null_encoding([]) == ""


def test_a_half_float_import_says_its_storage_is_not_reproduced(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    for path in glob(str(tmp_path / "d/renders/f00/*/seed_*.exr")):
        write_image(path, read_image(path), half=True)
    import_audit(settings)
    assert {a["bit_depth"] for a in render_attrs("synthetic").values()} == {0}
    variance, ground_truth = variance_of("synthetic")
    assert scene_frames(variance, ground_truth).encoding is None
    record = json.loads(Path(import_record("synthetic", "f00")).read_text())
    assert null_encoding([open_dataset(variance).attrs], [record]) == (
        f"The matched null was drawn in {HALF_FLOAT_NULL}.")


@pytest.mark.filterwarnings("ignore:All-NaN slice")  # a frame too small for many tiles
def test_the_verdict_page_says_what_the_matched_null_was_drawn_through(tmp_path, monkeypatch):
    from stereovar.calibration.summary import NULL_COLUMNS
    from stereovar.jobs.audit import verdict_job
    from stereovar.jobs.correlation import correlation_job, warp_job

    monkeypatch.chdir(tmp_path)
    import_audit(png_audit(tmp_path / "d"))
    variance, ground_truth = variance_of("synthetic")
    source = layout.audit_source("synthetic")
    warped = layout.warped_store(source, "seeds", "f00", 0)
    corr = layout.correlation_rows(source, "seeds", "f00", 0)
    warp_job(variance, ground_truth, warped)
    correlation_job(variance, warped, ground_truth, corr,
                    analysis={"bootstrap": {"reps": 20, "tile": 16}})
    nulls = tmp_path / "nulls.csv"
    write_tables([{"scene": "f00", "transform": "none", "region": "all", "method": "partial",
                   "null_rho": 0.0, "null_se": 0.01, "n": 4, "chance_sd": 0.02,
                   "margin": 0.05}], NULL_COLUMNS, {"csv": nulls})
    base = tmp_path / "results/audit/synthetic"
    outputs = {k: base / f"verdict.{k}" for k in ("md", "html")}
    outputs.update(summary=base / "summary.json", strongest=base / "strongest.png")
    summary = verdict_job([corr], [], [], outputs, name="synthetic", found="1 frame",
                          imports=[import_record("synthetic", "f00")], nulls=nulls,
                          variance=[variance], warped=[warped], ground_truth=[ground_truth])
    sentence = "The matched null was drawn in 8-bit sRGB, as the PNG files were."
    assert summary["matched_null"] and sentence in summary["text"]
    assert f"  calibration: {sentence}" in summary["summary"]
    assert sentence in outputs["md"].read_text()
    assert sentence.replace("'", "&#39;") in outputs["html"].read_text()


# -- the null through the encoding against quantisation -----------------------------------

H, W, D, N, DN = 48, 64, 2, 8, 0.2


@pytest.fixture(scope="module")
def quantised():
    """A smooth clean scene (the right view the left 2 px further left: x_R = x_L - d), 8
    frames per view at 0.2 DN of camera noise written as 8-bit sRGB, the data's own
    intensity-controlled rho, and the camera null's mean rho from ``scene_calibration``
    with the data's encoding and without it."""
    rng = np.random.default_rng(0)
    texture = gaussian_filter(rng.normal(0.0, 1.0, (H, W + D)), 2.0)
    wide = np.exp(0.8 * texture / texture.std() - 1.5)[..., None] * np.array([1.0, 0.8, 0.6])
    clean = {"left": wide[:, :W], "right": wide[:, D:D + W]}
    exposure = exposure_for(clean["left"])
    encoding = {"bits": 8, "transfer": "srgb", "scale": 1.0 / exposure}
    a, b = dn_law((1.0, 0.0), exposure, DN)
    frames = {v: integer_roundtrip(draw_frames(c, a * c.mean(axis=-1) + b, N, rng), **encoding)
              for v, c in clean.items()}
    means, fields = {}, {}
    for v, stack in frames.items():
        means[v], fields[v] = variance_field(stack)
    x = np.arange(W)[None, :].repeat(H, axis=0)
    truth = {"left": {"disparity": np.full((H, W), float(D)), "valid": x >= D},
             "right": {"disparity": np.full((H, W), float(D)), "valid": x < W - D}}
    settings = AnalysisSettings()
    out = {}
    for key, enc in (("encoded", encoding), ("float", None)):
        scene = SceneFrames(means, fields, truth, np.zeros((H, W), bool), -1, N,
                            "quantised|spp8", encoding=enc)
        rows, _ = scene_calibration(scene, transforms=["none"], settings=settings,
                                    replicates=4, strength_factors=[1.0],
                                    expensive_replicates=0)
        out[key] = float(np.mean([r["rho"] for r in rows if (r["kind"], r["transform"],
                                  r["region"], r["method"]) == ("camera", "none", "all",
                                                                "partial")]))
        (data,) = statistic_rows(frames, scene, settings, "data", methods=("partial",))
        out[f"data_{key}"] = data["rho"]
    return out


def test_quantisation_gives_the_data_a_partial_rho_the_float_null_does_not_have(quantised):
    """At 0.2 DN the 8-bit code grid gives both views the same variance pattern, which
    brightness, colour and position do not explain: read as float frames, the data's
    intensity-controlled rho is well above 0 and the camera null drawn in float about 0.
    Read knowing their encoding, the data's variance is the encoding's at nearly every pixel,
    and the statistic is undefined rather than a cue."""
    assert quantised["data_float"] > 0.3
    assert abs(quantised["float"]) < 0.05
    assert np.isnan(quantised["data_encoded"])


