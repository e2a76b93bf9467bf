"""The audit's import: discovery, ground truth, sign check, provenance, reimports, bad input,
and the verdict's rules, on synthetic renders with a known answer."""

import json
import os

import numpy as np
import pytest

from stereovar.audit.ground_truth import (
    disparity_from_depth,
    forward_warp,
    imported_ground_truth,
    left_right_occlusion,
)
from stereovar.audit.importer import QUANTISED_WARNING, import_audit, import_record, sha256
from stereovar.audit.layout import discover
from stereovar.audit.sign import sign_check
from stereovar.audit.synthetic import shift_rows, synthetic_frame, write_synthetic_audit
from stereovar.audit.verdict import verdict, verdict_rows
from stereovar.errors import AuditError, ImageError
from stereovar.io.images import read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field, write_image

SMALL = {"width": 64, "height": 40, "n_seeds": 4}


@pytest.fixture
def audit(tmp_path, monkeypatch):
    """Two synthetic frames as EXR + PFM, imported once, in a fresh working directory."""
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "data", **SMALL)
    report = import_audit(settings)
    return settings, frames, report


def stores(name="synthetic"):
    return sorted((p for p in os.scandir(f"results/audit/{name}/renders")), key=lambda p: p.name)


def test_discovery_reports_frames_views_and_seeds(audit):
    settings, _, report = audit
    assert report.discovery.summary() == "2 frames × 2 views × 4 seeds"
    assert report.lines()[0].startswith("audit synthetic: 2 frames × 2 views × 4 seeds")
    found = discover(settings)
    assert [f.name for f in found.frames] == ["f00", "f01"]
    assert list(found.frames[0].renders["right"]) == ["000", "001", "002", "003"]


def test_stores_hold_the_files_with_their_sha256(audit):
    settings, frames, _ = audit
    ds = open_dataset("results/audit/synthetic/renders/f01/right/spp0/seeds0-3.zarr")
    files = ds.attrs["source_files"]
    assert len(files) == 4 and files[2].endswith("f01/R/seed_002.exr")
    assert ds.attrs["source_sha256"] == [sha256(f) for f in files]
    for k, f in enumerate(files):
        np.testing.assert_array_equal(ds["radiance"].values[k], read_image(f))
    np.testing.assert_array_equal(ds["radiance"].values, frames[1].renders["right"])
    gt = open_dataset("results/audit/synthetic/ground_truth/f01.zarr")
    assert gt.attrs["source_sha256"] == [sha256(f) for f in gt.attrs["source_files"]]
    assert gt.attrs["convention"] == "conventional" and gt.attrs["disparity_sign"] == -1
    assert gt.attrs["material_mask"] == "none"
    left = gt.sel(view="left")
    np.testing.assert_array_equal(left["valid"].values, frames[1].valid)
    np.testing.assert_array_equal(
        left["disparity"].values, np.where(frames[1].valid, frames[1].disparity, 0)
    )


def test_reimport_does_nothing_until_a_file_changes(audit):
    settings, frames, _ = audit
    before = {
        p: os.stat(p).st_mtime_ns
        for p in (
            "results/audit/synthetic/ground_truth/f00.zarr",
            "results/audit/synthetic/ground_truth/f01.zarr",
        )
    }
    again = import_audit(settings)
    assert not any(f.imported for f in again.frames)
    # touched but unchanged: hashed again, not imported
    path = settings["renders"].format(frame="f01", view="R", seed="001")
    os.utime(path)
    assert not any(f.imported for f in import_audit(settings).frames)
    # one changed file re-imports only its frame
    image = read_image(path)
    write_image(path, image * 1.01)  # another render of the same scene
    third = import_audit(settings)
    assert [f.name for f in third.frames if f.imported] == ["f01"]
    assert (
        os.stat("results/audit/synthetic/ground_truth/f00.zarr").st_mtime_ns
        == before["results/audit/synthetic/ground_truth/f00.zarr"]
    )
    ds = open_dataset("results/audit/synthetic/renders/f01/right/spp0/seeds0-3.zarr")
    np.testing.assert_array_equal(ds["radiance"].values[1], (image * 1.01).astype(np.float32))
    record = json.loads(open(import_record("synthetic", "f01")).read())
    assert record["frame"] == "f01" and record["files"][path]["sha256"] == sha256(path)


def test_sign_check_stops_the_wrong_convention_with_one_line(audit):
    settings, _, _ = audit
    before = open_dataset("results/audit/synthetic/ground_truth/f00.zarr").attrs["scene_digest"]
    with pytest.raises(AuditError) as err:
        import_audit({**settings, "convention": "paper"})
    message = str(err.value)
    assert "\n" not in message and message.endswith("set audit.convention: conventional")
    # nothing already imported was touched
    assert (
        open_dataset("results/audit/synthetic/ground_truth/f00.zarr").attrs["scene_digest"]
        == before
    )


def test_paper_convention_data_passes_with_paper(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", convention="paper", n_frames=1, **SMALL)
    report = import_audit(settings)
    f = report.frames[0]
    assert f.sign["error"] < 0.5 * f.sign["opposite_error"]
    with pytest.raises(AuditError, match="set audit.convention: paper$"):
        import_audit({**settings, "convention": "conventional", "name": "other"})


def test_bad_input_is_one_line_naming_the_file_and_the_fix(audit, tmp_path):
    settings, _, _ = audit
    digest = open_dataset("results/audit/synthetic/ground_truth/f01.zarr").attrs["scene_digest"]
    seed3 = settings["renders"].format(frame="f01", view="L", seed="003")
    # truncated render
    data = open(seed3, "rb").read()
    open(seed3, "wb").write(data[: len(data) // 3])
    with pytest.raises(ImageError, match=r"seed_003\.exr: cannot read"):
        import_audit(settings)
    open(seed3, "wb").write(data)
    assert (
        open_dataset("results/audit/synthetic/ground_truth/f01.zarr").attrs["scene_digest"]
        == digest
    )
    # a size that differs
    write_image(seed3, np.zeros((10, 10, 3), np.float32))
    with pytest.raises(AuditError, match=r"seed_003\.exr is 10x10 px but .* same size"):
        import_audit(settings)
    os.remove(seed3)
    # a seed with one view only
    with pytest.raises(AuditError, match="seed 003 has a right render .* but no left one"):
        import_audit(settings)
    # fewer than 2 seeds
    open(seed3, "wb").write(data)
    for s in ("000", "001", "002"):
        for v in "LR":
            os.remove(settings["renders"].format(frame="f01", view=v, seed=s))
    with pytest.raises(AuditError, match=r"view left \(L\): 1 render \(.*\) match .* N >= 2"):
        import_audit(settings)
    # a template or view value that matches nothing
    with pytest.raises(AuditError, match="matches no file"):
        import_audit({**settings, "renders": settings["renders"].replace("seed_", "sample_")})
    with pytest.raises(AuditError, match="their view is none of"):
        import_audit({**settings, "views": {"left": "A", "right": "B"}})
    with pytest.raises(AuditError, match="has no {seed} field"):
        import_audit({**settings, "renders": "x/{frame}/{view}.exr"})


def test_nonfinite_renders_and_invalid_disparity_are_counted(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    path = settings["renders"].format(frame="f00", view="L", seed="001")
    image = read_image(path)
    image[3, 4] = np.nan
    image[5, 6, 1] = np.inf
    write_image(path, image)
    disparity = frames[0].disparity.copy()
    disparity[0, :5] = [np.nan, 0.0, -1.0, np.inf, 2.0]
    write_field(settings["disparity"].format(frame="f00"), disparity)
    f = import_audit(settings).frames[0]
    assert f.nonfinite_pixels == {"left": 2, "right": 0}
    assert f.invalid_disparity == 4
    expected = frames[0].valid.copy()
    expected[0, :4] = False
    expected[0, 4] = 0 - 2.0 + 4 >= 0  # x + s d inside the image
    assert f.valid == int(expected.sum())
    ds = open_dataset("results/audit/synthetic/renders/f00/left/spp0/seeds0-3.zarr")
    assert ds["n_nonfinite_pixels"].values.tolist() == [0, 2, 0, 0]


def test_png8_warns_and_reports_the_floored_fraction(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(
        tmp_path / "d", n_frames=1, render_format="npy", **SMALL
    )
    import cv2

    stacks = {}
    for view, letter in (("left", "L"), ("right", "R")):
        codes = []
        for s in range(4):
            npy = settings["renders"].format(frame="f00", view=letter, seed=f"{s:03d}")
            v = np.clip(np.load(npy) / 2.0, 0, 1)
            q = np.round(v * 255).astype(np.uint8)
            codes.append(q)
            cv2.imwrite(npy.replace(".npy", ".png"), q[..., ::-1])
            os.remove(npy)
        stacks[view] = np.stack(codes)
    png = {**settings, "renders": settings["renders"].replace(".npy", ".png"), "scale": 2.0}
    report = import_audit(png)
    text = " ".join(report.warnings)
    assert "decoded as sRGB" in text
    same = (stacks["left"] == stacks["left"][:1]).all(axis=(0, 3))
    valid = frames[0].valid
    fraction = (same & valid).sum() / valid.sum()
    assert report.frames[0].floored["left"] == pytest.approx(fraction, abs=1e-12)
    warned = f"floors the variance to 0 at {100 * fraction:.1f}% of the valid pixels" in text
    assert warned == (fraction >= QUANTISED_WARNING)
    again = import_audit({**png, "transfer": "srgb", "name": "explicit"})
    assert not any("decoded as sRGB" in w for w in again.warnings)


def test_disparity_from_depth_and_forward_warp_against_brute_force():
    z = np.array([[2.0, 4.0, 0.0, np.nan]])
    np.testing.assert_allclose(
        disparity_from_depth(z, focal_px=100.0, baseline_m=0.1), [[5.0, 2.5, np.nan, np.nan]]
    )
    rng = np.random.default_rng(0)
    d = rng.integers(1, 6, (5, 30)).astype(float)
    d[:, 10:14] = 9.0  # a near object occludes what lands beside it
    for sign in (1, -1):
        valid = np.zeros_like(d, bool)
        for y in range(5):
            for x in range(30):
                valid[y, x] = 0 <= x + sign * d[y, x] <= 29
        other, occluded = forward_warp(d, valid, sign=sign)
        brute_other = np.zeros_like(d)
        for y in range(5):
            for x in range(30):
                if valid[y, x]:
                    t = int(np.rint(x + sign * d[y, x]))
                    brute_other[y, t] = max(brute_other[y, t], d[y, x])
        np.testing.assert_array_equal(other, brute_other)
        for y, x in zip(*np.nonzero(valid), strict=True):
            t = int(np.rint(x + sign * d[y, x]))
            assert occluded[y, x] == (d[y, x] < brute_other[y, t] - 1)
        # the consistent right view: nothing but the occluded pixels fails left-right
        lr = left_right_occlusion(d, other, valid, sign=sign)
        np.testing.assert_array_equal(lr, occluded)


def test_sign_check_errors_against_a_brute_force_warp():
    rng = np.random.default_rng(5)
    height, width = 6, 40
    left = rng.uniform(0.5, 2.0, (height, width, 3))
    right = rng.uniform(0.5, 2.0, (height, width, 3))
    right[2, 7, 1] = np.nan  # a NaN right pixel spoils the left pixels that sample it
    d = rng.uniform(1.0, 6.0, (height, width))
    valid = rng.random((height, width)) > 0.2
    check = sign_check(left, right, d, sign=-1, valid=valid)
    for s, error, n in (
        (-1, check.error, check.n_pixels),
        (1, check.opposite_error, check.opposite_n_pixels),
    ):
        ratios = []
        for y in range(height):
            for x in range(width):
                xs = x + s * d[y, x]
                if not (valid[y, x] and 0 <= xs <= width - 1):
                    continue
                x0 = min(int(np.floor(xs)), width - 2)
                t = xs - x0
                warped = (1 - t) * right[y, x0] + t * right[y, x0 + 1]
                if np.isfinite(warped).all():
                    lum = left[y, x].mean()
                    ratios.append(abs(warped.mean() - lum) / max(lum, 1e-6))
        assert n == len(ratios)
        assert error == pytest.approx(np.median(ratios), rel=1e-12)


def test_ground_truth_without_a_mask_has_no_glass_and_says_so():
    d = np.full((4, 12), 2.0)
    gt, counts = imported_ground_truth(d, sign=1)
    assert gt.attrs["material_mask"] == "none" and not gt["glass"].values.any()
    assert counts == {"invalid_disparity": 0, "outside": 8, "valid": 40}
    mask = np.zeros((4, 12), bool)
    mask[1] = True
    gt, _ = imported_ground_truth(d, sign=1, glass=mask, material_source="m.png")
    assert gt.attrs["material_mask"] == "m.png"
    np.testing.assert_array_equal(gt["glass"].sel(view="left").values, mask)


def test_synthetic_frame_has_the_stated_correlation_after_the_warp():
    f = synthetic_frame(width=80, height=48, n_seeds=64, sign=-1)
    d = f.disparity.astype(int)
    # the right variance field moved back by the disparity is the left-coordinate field
    back = shift_rows(f.variance["right"], d[:, 0])  # sign -1: move right by +d
    v_rl = np.where(f.valid, back, np.nan)
    rho = np.corrcoef(f.variance["left"][f.valid], v_rl[f.valid])[0, 1]
    assert rho == pytest.approx(f.rho, abs=1e-12)
    # renders are clean image plus noise with the stated variance
    var = f.renders["left"].astype(np.float64).var(axis=0, ddof=1).mean(axis=-1)
    ratio = var[f.valid] / f.variance["left"][f.valid]
    assert abs(np.mean(ratio) - 1) < 0.05


def row(method, rho, low, high, region="all"):
    return {
        "region": region,
        "method": method,
        "rho": rho,
        "boot_low": low,
        "boot_high": high,
        "reliability_left": 0.81,
        "reliability_right": 0.81,
        "rho_corrected": rho / 0.81,
        "reason": "",
    }


def lift(source, value, chance, scene, half=0.02):
    """A frame's C_sigma accuracy row with its tile-bootstrap interval (+/- ``half``)."""
    return {
        "cost": "variance_cost",
        "metric": "wta_accuracy",
        "condition": "normal",
        "region": "all",
        "source": source,
        "value": value,
        "low": value - half,
        "high": value + half,
        "chance": chance,
        "n_pixels": 1000,
        "scene": scene,
    }


def null(method, scene, value, se):
    return {"scene": scene, "transform": "none", "region": "all", "method": method,
            "null_rho": value, "null_se": se}


def test_verdict_rules_on_known_rows():
    methods = [
        "warp",
        "spearman",
        "log",
        "trimmed",
        "relative",
        "sensor_sim",
        "sensor",
        "no_warp",
        "null_shift",
        "null_flip",
    ]
    corr = [{**row(m, 0.5, 0.4, 0.6), "scene": "a"} for m in methods]
    strong = corr + [{**row("partial", 0.55, 0.52, 0.58), "scene": "a"}]
    iv = [
        lift("render", 0.5, 0.2, "a"),
        lift("sensor", 0.22, 0.2, "a"),
    ]
    # the matched null of each frame: partial rho 0.01, C_sigma lift 0.10 (+/- se 0.01)
    nulls = [null("partial", "a", 0.01, 0.0), null("c_sigma_lift", "a", 0.10, 0.01)]
    rows = verdict_rows(strong, iv, nulls)
    corrected = next(r for r in rows if r["quantity"] == "attenuation-corrected rho")
    assert corrected["value"] == pytest.approx(0.5 / 0.81)
    assert corrected["low"] == pytest.approx(0.4 / 0.81, rel=1e-9)  # one-frame interval
    result = verdict(rows)
    assert result["mc_specific"] and result["strength"] == "strong"
    # the lift 0.30 +/- 0.02 (bootstrap) against its null 0.10 +/- 0.01 (se): the difference
    # 0.20 with the two standard errors in quadrature
    beyond = next(r for r in rows if r["quantity"] == "C_sigma WTA lift beyond its matched null")
    se = np.hypot(0.02 / 1.959963984540054, 0.01)
    assert beyond["value"] == pytest.approx(0.20)
    assert beyond["low"] == pytest.approx(0.20 - 1.959963984540054 * se)
    assert beyond["null"] == pytest.approx(0.10)
    assert result["matching_cue"] is True
    # a lift no larger than its matched null's (a camera pipeline the null reproduces) is no
    # matching cue, however far above chance and above a plain camera's
    same = [lift("render", 0.31, 0.2, "a"), lift("sensor", 0.22, 0.2, "a")]
    assert verdict(verdict_rows(strong, same, nulls))["matching_cue"] is False
    # nor is a lift above its null where the cue is not Monte Carlo-specific
    flat = corr + [{**row("partial", 0.03, 0.0, 0.06), "scene": "a"}]
    plain = verdict(verdict_rows(flat, iv, nulls))
    assert plain["mc_specific"] is False and plain["matching_cue"] is False
    # without a matched null the lift is reported, never read as a matching cue
    alone = verdict(verdict_rows(strong, iv))
    assert alone["matching_cue"] is None and "without a matched null" in alone["text"]
    # two frames' lifts: mean 0.31, their bootstrap intervals combined
    two = [lift("render", 0.5, 0.2, "a"), lift("render", 0.52, 0.2, "b", half=0.04)]
    lifts = next(r for r in verdict_rows(strong, two) if r["quantity"].endswith("renders"))
    half = np.hypot(0.02, 0.04) / 2
    assert lifts["value"] == pytest.approx(0.31)
    assert lifts["low"] == pytest.approx(0.31 - half)
    assert lifts["high"] == pytest.approx(0.31 + half)
    none = verdict(verdict_rows(corr + [row("partial", 0.05, -0.02, 0.12)], iv))
    assert none["mc_specific"] is False and "does not clear 0.05" in none["text"]
    # above 0 but not above the smallest cue called (what camera pipelines leave)
    slight = verdict(verdict_rows(corr + [row("partial", 0.05, 0.01, 0.09)], iv))
    assert slight["mc_specific"] is False
    weak = verdict(verdict_rows(corr + [row("partial", 0.2, 0.1, 0.3)], iv))
    assert weak["strength"] == "weak"
