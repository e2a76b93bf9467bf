"""The offset check (:mod:`stereovar.audit.offset`) on frames whose disparity is known.

Two kinds of in-memory frames: :func:`stereovar.audit.synthetic.synthetic_frame` (block
texture, an integer disparity per row, Gaussian noise in every seed) and
:func:`fractional_frame` below (a smooth texture seen through a slanted plane whose
disparity is fractional everywhere, so the warp interpolates, plus noise in the seed means).
A disparity declared with a planted offset :math:`k` (``d + k``) is expected to fire with an
estimated offset within half a pixel of :math:`k`; the right disparity never fires. One
import of a tiny frame checks that the finding reaches the import record, the ``warning:``
line and the verdict page.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.offset import offset_check, shifted_errors, vertex
from stereovar.audit.synthetic import (
    slanted_texture_means,
    synthetic_frame,
    write_synthetic_audit,
)
from stereovar.io.writers import write_field
from stereovar.jobs.audit import verdict_job

SIGN = -1
"""The conventional rig, x_R = x_L - d, of every frame here."""


def fractional_frame(seed: int, *, noise: float = 0.02, width: int = 96, height: int = 64):
    """Seed means and the known fractional disparity of a smooth texture behind a slanted
    plane (:func:`stereovar.audit.synthetic.slanted_texture_means`)."""
    return slanted_texture_means(seed, noise=noise, width=width, height=height)


def block_frame(seed: int, **options):
    """Seed means and left disparity of :func:`synthetic_frame` (conventional rig)."""
    frame = synthetic_frame(sign=SIGN, seed=seed, n_seeds=8, **options)
    left, right = (frame.renders[v].mean(axis=0, dtype=np.float64) for v in ("left", "right"))
    return left, right, frame.disparity.astype(np.float64)


FRAMES = [("block", s) for s in range(10)] + [("fractional", s) for s in range(10)]
"""20 frames with the right disparity known."""


def frame_of(kind: str, seed: int):
    return block_frame(seed) if kind == "block" else fractional_frame(seed)


def test_the_right_disparity_never_fires_and_is_a_local_minimum():
    false_alarms = 0
    for kind, seed in FRAMES:
        left, right, d = frame_of(kind, seed)
        check = offset_check(left, right, d, sign=SIGN)
        false_alarms += check.fires
        # a correct disparity is a local minimum of the warp's error, interpolated or not
        assert check.error_at(0) < min(check.error_at(1), check.error_at(-1)), (kind, seed)
        assert abs(check.offset) < 0.5, (kind, seed)
    assert false_alarms == 0, f"{false_alarms} of {len(FRAMES)} correct frames fired"


def test_flat_noisy_frames_never_fire():
    # nothing to match: every shift's error is noise alone, whatever the frame's size
    fired = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        height, width = [(16, 24), (24, 40), (40, 64), (64, 96)][seed % 4]
        left, right = 0.5 + 0.05 * rng.standard_normal((2, height, width, 3))
        fired += offset_check(left, right, np.full((height, width), 5.0), sign=SIGN).fires
    assert fired == 0


@pytest.mark.parametrize("planted", [2.0, -2.0])
def test_a_constant_offset_fires_and_is_estimated_within_half_a_pixel(planted):
    for kind, seed in FRAMES[:5] + FRAMES[10:15]:
        left, right, d = frame_of(kind, seed)
        check = offset_check(left, right, d + planted, sign=SIGN)
        assert check.fires and not check.varies, (kind, seed)
        assert abs(check.offset - planted) <= 0.5, (kind, seed, check.offset)
        # the warp's error falls towards the truth: one pixel that way matches better
        towards = -int(np.sign(planted))
        assert check.error_at(towards) < check.error_at(0)
        text = check.finding()
        assert text.startswith(f"the disparity seems offset by about {planted:+.0f}.")
        assert f"matches better at d{towards:+d} (error " in text


def test_a_fractional_offset_is_estimated_below_a_pixel():
    for seed in range(5):
        left, right, d = fractional_frame(seed, noise=0.01)
        check = offset_check(left, right, d + 1.5, sign=SIGN)
        assert check.fires and abs(check.offset - 1.5) <= 0.5, (seed, check.offset)


def test_a_disparity_replaced_by_its_mean_fires_as_an_offset_that_varies():
    for seed in range(5):
        left, right, d = block_frame(seed)
        mean = np.full_like(d, d.mean())
        check = offset_check(left, right, mean, sign=SIGN)
        assert check.fires and check.varies, seed
        assert check.finding().startswith("the disparity seems off by an amount that varies")
        # rows whose true disparity lies 1.5 px or more below the mean match better one pixel
        # lower, those 1.5 px or more above it one pixel higher
        shifts, errors, pixels = shifted_errors(left, right, mean, sign=SIGN)
        truth = d.reshape(-1)[pixels] - mean.reshape(-1)[pixels]
        at = list(shifts).index
        for rows, towards in ((truth <= -1.5, -1), (truth >= 1.5, 1)):
            assert rows.sum() > 100
            assert np.median(errors[at(towards), rows]) < np.median(errors[at(0), rows])


def test_an_offset_under_half_a_pixel_is_not_seen():
    # the documented limit: d + 0.3 is nearer the truth than d - 0.7 or d + 1.3
    for seed in range(3):
        left, right, d = block_frame(seed)
        assert not offset_check(left, right, d + 0.3, sign=SIGN).fires


def test_shifted_errors_match_a_brute_force_warp():
    left, right, d = fractional_frame(3, width=40, height=12)
    valid = np.ones(d.shape, bool)
    valid[5, 10:20] = False
    shifts, errors, pixels = shifted_errors(left, right, d, sign=SIGN, valid=valid, max_shift=2)
    lum_left, lum_right = left.mean(axis=-1), right.mean(axis=-1)
    expected_pixels, expected = [], []
    for y in range(d.shape[0]):
        for x in range(d.shape[1]):
            matches = [x + SIGN * (d[y, x] + k) for k in (-2, -1, 0, 1, 2)]
            if not valid[y, x] or min(matches) < 0 or max(matches) > d.shape[1] - 1:
                continue
            expected_pixels.append(y * d.shape[1] + x)
            warped = np.interp(matches, np.arange(d.shape[1]), lum_right[y])
            expected.append(np.abs(warped - lum_left[y, x]) / lum_left[y, x])
    assert shifts.tolist() == [-2, -1, 0, 1, 2]
    assert pixels.tolist() == expected_pixels
    np.testing.assert_allclose(errors, np.array(expected).T, rtol=1e-9, atol=1e-12)


def test_vertex_finds_the_minimum_of_a_sampled_parabola():
    shifts = np.arange(-4, 5)
    for true_min in (-2.3, 0.0, 0.4, 1.5):
        assert vertex(shifts, (shifts - true_min) ** 2 + 1.0) == pytest.approx(true_min)


def test_an_offset_disparity_is_a_warning_a_record_field_and_a_banner(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(
        tmp_path / "d", n_frames=1, width=64, height=40, n_seeds=4
    )
    report = import_audit(settings)
    assert not [f for f in report.flags if f["kind"] == "disparity_offset"]
    planted = 2.0
    write_field(settings["disparity"].format(frame="f00"), frames[0].disparity + planted)
    report = import_audit(settings)
    (flag,) = [f for f in report.flags if f["kind"] == "disparity_offset"]
    record = json.loads(Path(import_record("synthetic", "f00")).read_text())
    found = record["found"]["offset"]
    assert found["fires"] is True and abs(found["offset"] - planted) <= 0.5
    assert found["minus_error"] < found["error"] < found["plus_error"]
    assert flag in record["found"]["warnings"] and flag["frame"] == "f00"
    assert flag["text"].startswith(
        f"frame f00: the disparity seems offset by about +{found['offset']:.1f} px: the warp "
        f"matches better at d-1 (error {100 * found['minus_error']:.1f}%) than at d "
        f"({100 * found['error']:.1f}%)"
    )
    assert flag["text"].endswith(
        "check the disparity's units, offset and convention (e.g. a crop or a principal-point "
        "shift, audit.disparity_scale): the cross-view cue measured with this disparity is "
        "unreliable"
    )
    assert f"  warning: {flag['text']}" in report.lines()
    # the sign check alone lets it through: the declared sign wins under its 15% flag
    assert record["found"]["sign"]["conclusive"] and not record["found"]["sign"]["high_error"]
    base = Path("results/audit/synthetic")
    outputs = {"md": base / "verdict.md", "html": base / "verdict.html",
               "summary": base / "summary.json"}
    summary = verdict_job([], [], [], outputs, name="synthetic", found="1 frame",
                          imports=[import_record("synthetic", "f00")])
    md, page = outputs["md"].read_text(), outputs["html"].read_text()
    assert flag in summary["flags"] and f"  flag: {flag['text']}" in summary["summary"]
    assert f"> **Warning.** {flag['text']}" in md
    assert md.index("> **Warning.**") < md.index(f"**{summary['light'].upper()}")
    assert f"(disparity offset about +{found['offset']:.1f} px)" in md
    assert "disparity offset" in page
    assert math.isfinite(found["share"])
