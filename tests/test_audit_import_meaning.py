"""The audit reads its inputs by what they mean: a one-channel file named for another role
(a depth pass given as disparity) is refused, a sign check won with a high error and a
disparity whose matches mostly fall outside the other view are flagged, half-float renders
whose noise is near the half-float step are flagged, segment ids stay integers, user text is
escaped on the Markdown verdict page, and Snakemake path variables in audit paths are
refused before any file is read; the functions these rest on document their parameters and
what they return.

Each frame is a tiny synthetic one (:func:`stereovar.audit.synthetic.write_synthetic_audit`,
64 x 40 px, 4 or 8 seeds) in a fresh working directory.
"""

import html
import importlib
import inspect
import json
import math
import re
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.run import discover_audit
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.errors import AuditError, ImageError
from stereovar.io.images import read_field, read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field, write_image
from stereovar.jobs.audit import verdict_job

SMALL = {"width": 64, "height": 40, "n_seeds": 4}


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text


def write_exr(path, channels: dict) -> Path:
    """A one-part EXR with these channels (name to pixels, dtype kept)."""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {k: np.ascontiguousarray(v) for k, v in channels.items()}) as f:
        f.write(str(path))
    return Path(path)


def record_of(name="synthetic", frame="f00") -> dict:
    return json.loads(Path(import_record(name, frame)).read_text())


def flags_of(record: dict, kind: str) -> list:
    return [f for f in record["found"]["warnings"] if f["kind"] == kind]


def verdict_of(records: list) -> tuple:
    """``summary.json``, ``verdict.md`` and ``verdict.html`` of an audit whose statistics are
    not computed yet (the import's records only)."""
    base = Path("results/audit/synthetic")
    outputs = {"md": base / "verdict.md", "html": base / "verdict.html",
               "summary": base / "summary.json"}
    imports = [import_record("synthetic", r["frame"]) for r in records]
    summary = verdict_job([], [], [], outputs, name="synthetic", found="1 frame",
                          imports=imports)
    return summary, outputs["md"].read_text(), outputs["html"].read_text()


def warp_error(left_mean, right_mean, disparity, valid, sign) -> float:
    """Median relative luminance error of the right seed mean warped into the left, pixel by
    pixel: left pixel x reads the right luminance at x + sign * d, linearly interpolated,
    where d is finite and positive, the pixel is valid and x + sign * d lies in [0, W - 1]."""
    lum_left, lum_right = left_mean.mean(axis=-1), right_mean.mean(axis=-1)
    height, width = disparity.shape
    errors = []
    for y in range(height):
        for x in range(width):
            d = float(disparity[y, x])
            if not (valid[y, x] and math.isfinite(d) and d > 0):
                continue
            at = x + sign * d
            if not 0 <= at <= width - 1:
                continue
            x0 = min(math.floor(at), width - 2)
            warped = (1 - (at - x0)) * lum_right[y, x0] + (at - x0) * lum_right[y, x0 + 1]
            errors.append(abs(warped - lum_left[y, x]) / max(lum_left[y, x], 1e-6))
    return float(np.median(errors))


# -- A: a depth map given as disparity ---------------------------------------------------------


def test_a_depth_pass_given_as_disparity_is_refused_before_anything_is_written(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    depth = write_exr(tmp_path / "d" / "disparity" / "f00.exr",
                      {"ViewLayer.Depth.Z": (100.0 / frames[0].disparity).astype(np.float32)})
    settings = {**settings, "disparity": str(tmp_path / "d/disparity/{frame}.exr"),
                "sign_check": "warn"}
    with pytest.raises(ImageError) as err:
        import_audit(settings)
    assert one_line(err) == (
        f"{depth}: its one channel 'ViewLayer.Depth.Z' holds depth by its name, not "
        "disparity; give it as audit.depth (with audit.focal_px and audit.baseline_m: "
        "d = f B / z) and leave audit.disparity out, or give the disparity in px"
    )
    assert not Path("results").exists()


def test_one_channel_named_for_another_role_is_refused_and_a_plain_one_is_read(tmp_path):
    field = np.linspace(1.0, 9.0, 35, dtype=np.float32).reshape(5, 7)
    refused = [  # channel, role, what its name says, the role in words
        ("disparity", "depth", "disparity", "depth"),  # vice versa
        ("ViewLayer.Normal.X", "disparity", "surface normals", "disparity"),
        ("ViewLayer.Mist.Z", "depth", "mist (a 0-1 distance ramp)", "depth"),
        ("ViewLayer.Object Index.X", "glass_mask", "a segmentation", "a glass mask"),
        ("ViewLayer.Depth.Z", "segmentation", "depth", "a segmentation"),
    ]
    for k, (channel, role, holds, wanted) in enumerate(refused):
        path = write_exr(tmp_path / f"f{k}.exr", {channel: field})
        with pytest.raises(ImageError) as err:
            read_field(path, role=role)
        assert one_line(err) == (
            f"{path}: its one channel {channel!r} holds {holds} by its name, not {wanted}; "
            f"give a file that holds {wanted}, or set audit.channels: {{{role}: {channel}}} "
            f"if it does hold {wanted}"
        )
        # named in audit.channels, it is read as that role
        np.testing.assert_array_equal(read_field(path, role=role, channel=channel), field)
    depth = write_exr(tmp_path / "depth.exr", {"ViewLayer.Depth.Z": field})
    with pytest.raises(ImageError, match="holds depth by its name, not a render"):
        read_image(depth)
    # names that say nothing (our own writer's Z, Blender's BW V) are read as any field
    write_field(tmp_path / "plain.exr", field)
    np.testing.assert_array_equal(read_field(tmp_path / "plain.exr", role="disparity"), field)
    grey = write_exr(tmp_path / "grey.exr", {"V": field})
    np.testing.assert_array_equal(read_field(grey, role="depth"), field)


def test_a_sign_check_won_with_a_high_error_is_flagged_on_the_summary_and_page(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    # noisy seed means: the declared sign wins, but its median error is above 15%
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, level=0.1, **SMALL)
    frame = frames[0]
    means = [frame.renders[view].mean(axis=0, dtype=np.float64) for view in ("left", "right")]
    error, opposite = (warp_error(*means, frame.disparity, frame.valid, s) for s in (-1, 1))
    assert 0.15 < error < 0.5 * opposite  # the declared sign wins, with a high error
    report = import_audit(settings)
    record = record_of()
    assert record["found"]["sign"]["error"] == pytest.approx(error, abs=1e-6)
    assert record["found"]["sign"]["opposite_error"] == pytest.approx(opposite, abs=1e-6)
    (flag,) = flags_of(record, "sign_check_error")
    assert flag["text"].startswith(
        f"frame f00: the declared convention wins the sign check but matches poorly (median "
        f"error {100 * error:.1f}% declared, {100 * opposite:.1f}% opposite; above 15%"
    )
    assert f"  warning: {flag['text']}" in report.lines()
    summary, md, html = verdict_of([record])
    assert flag in summary["flags"] and f"  flag: {flag['text']}" in summary["summary"]
    assert summary["light"] == "amber"
    assert f"> **Warning.** {flag['text']}" in md  # a banner above the decision
    assert md.index("> **Warning.**") < md.index("**AMBER")
    assert "(error high)" in md and "sign check error high" in html


def test_a_low_sign_check_error_raises_no_flag(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    import_audit(settings)
    record = record_of()
    assert record["found"]["sign"]["error"] < 0.15
    assert record["found"]["sign"]["high_error"] is False
    assert not flags_of(record, "sign_check_error") and not flags_of(record, "outside")


def test_most_matches_outside_the_other_view_are_flagged(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    # eight times the disparity (24-64 px on a 64 px wide image), as a depth map in the
    # wrong unit would give
    disparity = 8 * frames[0].disparity
    write_field(settings["disparity"].format(frame="f00"), disparity)
    report = import_audit({**settings, "sign_check": "warn"})
    # conventional x_R = x_L - d: a left pixel x matches inside the right image iff x >= d
    height, width = disparity.shape
    outside = int((np.arange(width)[None, :] < disparity).sum())
    assert outside > 0.5 * height * width
    record = record_of()
    assert record["found"]["outside"] == outside
    (flag,) = flags_of(record, "outside")
    assert flag["text"].startswith(
        f"frame f00: {outside} of the {height * width} left pixels "
        f"({100 * outside / (height * width):.1f}%) have a disparity whose match falls "
        "outside the right image (64 px wide, x_R = x_L - d)"
    )
    assert f"  warning: {flag['text']}" in report.lines()
    summary, md, html = verdict_of([record])
    assert flag in summary["flags"] and flag["text"] in md
    assert "matches outside the other view" in html


# -- B: half-float renders -----------------------------------------------------------------


def half_audit(root, *, level, half=True):
    """One synthetic frame of 8 seeds whose renders are written as half-float EXR."""
    settings, frames = write_synthetic_audit(root, n_frames=1, level=level,
                                             width=64, height=40, n_seeds=8)
    for letter, view in (("L", "left"), ("R", "right")):
        for s, image in enumerate(frames[0].renders[view]):
            write_image(root / f"renders/f00/{letter}/seed_{s:03d}.exr", image, half=half)
    return settings, frames[0]


def coarse_share(renders, valid) -> float:
    """Share of ``valid`` pixels whose half-float values spread by less than two half-float
    steps (the spacing of half floats at the pixel's mean) in every channel."""
    values = renders.astype(np.float16).astype(np.float64)
    mean = values.mean(axis=0)
    spread = values.std(axis=0, ddof=1)
    exponent = np.vectorize(lambda m: math.frexp(float(np.float16(m)))[1])(np.abs(mean))
    step = np.exp2(exponent - 11.0)  # 10 mantissa bits: the spacing in [2^(e-1), 2^e)
    coarse = (spread < 2 * step).all(axis=-1)
    return float((coarse & valid).sum() / valid.sum())


def test_half_float_renders_with_noise_near_the_half_step_are_flagged(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # a per-pixel spread of about one half-float step: 3 distinct values in 8 seeds
    settings, frame = half_audit(tmp_path / "d", level=1e-7)
    report = import_audit(settings)
    record = record_of()
    expected = coarse_share(frame.renders["left"], frame.valid)
    assert expected > 0.5
    assert record["found"]["half"]["left"] == pytest.approx(expected, abs=1e-12)
    flags = flags_of(record, "quantisation")
    assert [f["text"].split(":")[0] for f in flags] == ["frame f00, left", "frame f00, right"]
    assert flags[0]["text"].startswith(
        f"frame f00, left: the renders hold half-float (16-bit) values, and at "
        f"{100 * expected:.1f}% of the valid pixels their spread across the 8 renders is "
        "below 2 half-float steps"
    )
    assert f"  warning: {flags[0]['text']}" in report.lines()
    summary, md, _ = verdict_of([record])
    assert flags[0] in summary["flags"] and flags[0]["text"] in md
    assert f"left {100 * expected:.2f}% (half float)" in md  # the facts' quantised column


def test_half_float_with_ample_noise_and_float_renders_are_not_flagged(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frame = half_audit(tmp_path / "a", level=0.004)  # spread >> the half step
    import_audit(settings)
    record = record_of()
    assert coarse_share(frame.renders["left"], frame.valid) == 0.0
    assert record["found"]["half"] == {"left": 0.0, "right": 0.0}
    assert not flags_of(record, "quantisation")
    settings, _ = half_audit(tmp_path / "b", level=1e-7, half=False)  # 32-bit float EXR
    import_audit({**settings, "name": "float"})
    record = record_of("float")
    assert record["found"]["half"] == {} and not flags_of(record, "quantisation")


def test_float32_renders_whose_values_are_all_half_floats_are_not_taken_for_half(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    root = tmp_path / "d"
    settings, frames = write_synthetic_audit(root, n_frames=1, level=1e-7, width=64, height=40,
                                             n_seeds=8)
    for letter, view in (("L", "left"), ("R", "right")):
        for s, image in enumerate(frames[0].renders[view]):
            values = image.astype(np.float16).astype(np.float32)  # every value a half float
            write_image(root / f"renders/f00/{letter}/seed_{s:03d}.exr", values, half=False)
    exr = root / "renders/f00/L/seed_000.exr"
    with OpenEXR.File(str(exr), separate_channels=True) as f:  # the file says float32
        assert {c.pixels.dtype for c in f.channels().values()} == {np.dtype(np.float32)}
    import_audit(settings)
    record = record_of()
    assert record["found"]["half"] == {} and not flags_of(record, "quantisation")
    # the same values as PFM, whose header cannot say: every value a half float is half
    pfm = {**settings, "name": "pfm", "renders": str(root / "pfm/{frame}/{view}/seed_{seed}.pfm")}
    for letter, view in (("L", "left"), ("R", "right")):
        (root / f"pfm/f00/{letter}").mkdir(parents=True)
        for s, image in enumerate(frames[0].renders[view]):
            write_image(root / f"pfm/f00/{letter}/seed_{s:03d}.pfm",
                        image.astype(np.float16).astype(np.float32))
    import_audit(pfm)
    assert set(record_of("pfm")["found"]["half"]) == {"left", "right"}


def test_the_header_says_whether_a_render_is_stored_as_half(tmp_path):
    from stereovar.io.headers import stored_as_half

    pixels = {np.float16: np.full((4, 6), 0.5, np.float16),
              np.float32: np.full((4, 6), 0.5, np.float32)}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    blender = tmp_path / "blender.exr"  # Blender 5: a half Combined part, a float Depth part
    combined = {f"ViewLayer.Combined.{c}": pixels[np.float16] for c in "RGBA"}
    noisy = {f"ViewLayer.Noisy Image.{c}": pixels[np.float32] for c in "RGB"}
    parts = [
        OpenEXR.Part(dict(header), {"ViewLayer.Depth.Z": pixels[np.float32]}, "ViewLayer.Depth"),
        OpenEXR.Part(dict(header), combined, "ViewLayer.Combined"),
        OpenEXR.Part(dict(header), noisy, "ViewLayer.Noisy Image"),
    ]
    with OpenEXR.File(parts) as f:
        f.write(str(blender))
    assert stored_as_half(blender) is True  # the render layer, Combined
    assert stored_as_half(blender, channel="ViewLayer.Noisy Image") is False
    assert stored_as_half(write_exr(tmp_path / "f.exr", {c: pixels[np.float32] for c in "RGB"})) \
        is False
    for dtype, expected in ((np.float16, True), (np.float32, False)):
        image = np.zeros((4, 6, 3), dtype)
        np.save(tmp_path / "r.npy", image)
        np.savez(tmp_path / "r.npz", image)
        assert stored_as_half(tmp_path / "r.npy") is expected
        assert stored_as_half(tmp_path / "r.npz") is expected
    write_image(tmp_path / "r.pfm", np.zeros((4, 6, 3), np.float32))
    assert stored_as_half(tmp_path / "r.pfm") is None  # PFM's header cannot say


def test_the_half_float_share_uses_the_import_seed_mean_and_skips_non_finite_pixels():
    from stereovar.audit.decoding import half_quantised_fraction, seed_mean

    rng = np.random.default_rng(4)
    # 6 seeds of 5x4 px: half-float values around 1 spread by about one half-float step
    stack = (1.0 + rng.integers(-1, 2, (6, 5, 4, 3)) / 1024).astype(np.float32)
    stack[:, 2:] += rng.normal(0.0, 0.05, (6, 3, 4, 3)).astype(np.float32)  # rows 2-4: noisy
    stack[3, 0, 0, 1] = np.nan  # a NaN render pixel, and an Inf one
    stack[1, 0, 1, 2] = np.inf
    valid = np.ones((5, 4), bool)
    valid[1, 3] = False
    n_bad = (~np.isfinite(stack)).any(axis=-1).sum(axis=(1, 2))
    mean = seed_mean(stack, n_bad)
    # brute force: a pixel counts when all its values are finite and, in every channel, the
    # sample sd over the 6 seeds is below 2 spacings of half floats at the seed mean
    count = 0
    for y, x in zip(*np.nonzero(valid), strict=True):
        values = stack[:, y, x].astype(np.float64)
        if not np.isfinite(values).all():
            continue
        sd = values.std(axis=0, ddof=1)
        m = values.mean(axis=0)
        step = [np.spacing(np.float16(abs(c))).astype(np.float64) for c in m]
        count += all(sd[c] < 2 * step[c] for c in range(3))
    expected = count / valid.sum()
    assert 0 < expected < 1
    assert half_quantised_fraction(stack, valid, mean) == pytest.approx(expected, abs=1e-12)


# -- C: segment ids above 2**24 ---------------------------------------------------------------


def segmentation_audit(tmp_path, seg, fmt, glass_ids):
    """One synthetic frame with the segmentation ``seg`` written as ``fmt``, imported."""
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    path = tmp_path / f"seg_f00.{fmt}"
    if fmt == "npy":
        np.save(path, seg)
    else:
        write_exr(path, {"ViewLayer.Object Index.X": seg})
    template = str(tmp_path / f"seg_{{frame}}.{fmt}")
    return import_audit({**settings, "segmentation": template, "glass_ids": glass_ids}), path


@pytest.mark.parametrize("fmt", ["npy", "exr"])  # integer NPY, EXR UINT channel
def test_segment_ids_above_two_to_the_24_stay_apart(tmp_path, monkeypatch, fmt):
    monkeypatch.chdir(tmp_path)
    seg = np.zeros((SMALL["height"], SMALL["width"]), np.uint32)
    seg[5:15, 10:30] = 16777217  # glass
    seg[20:30, 10:30] = 16777216  # another segment: through float32 both are 16777216
    assert np.float32(16777217) == np.float32(16777216)
    segmentation_audit(tmp_path, seg, fmt, [16777217])
    gt = open_dataset("results/audit/synthetic/ground_truth/f00.zarr")
    glass = gt["glass"].sel(view="left").transpose("y", "x").values
    np.testing.assert_array_equal(glass, seg == 16777217)
    assert not flags_of(record_of(), "glass_ids")


@pytest.mark.parametrize(
    "dtype, written, stored, exact",
    [
        ("float32", 16777218, 16777218, 2**24),  # a float32 that 16777217 can round to
        ("float32", 16777217, 16777216, 2**24),  # 2**24 + 1 is stored as 2**24
        ("float16", 2049, 2048, 2**11),  # half: 10 mantissa bits
    ],
)
def test_float_segment_ids_past_the_float_precision_are_refused(
    tmp_path, monkeypatch, dtype, written, stored, exact
):
    monkeypatch.chdir(tmp_path)
    seg = np.zeros((SMALL["height"], SMALL["width"]), dtype)
    seg[5:15, 10:30] = written
    assert seg.max() == stored  # what the file holds
    with pytest.raises(ImageError) as err:
        segmentation_audit(tmp_path, seg, "npy", [written])
    assert one_line(err) == (
        f"{tmp_path / 'seg_f00.npy'}: segment ids up to {stored} stored as {dtype}, which "
        f"tells whole numbers apart only below {exact} ({exact + 1} is stored as {exact}), so "
        "two ids there can read as one; write the segmentation as integers (EXR UINT, 16-bit "
        "PNG or an integer .npy)"
    )
    assert not Path("results/audit/synthetic/ground_truth").exists()


# -- D: user text on the Markdown verdict page ------------------------------------------------


def test_user_text_is_escaped_on_the_markdown_verdict_page(tmp_path, monkeypatch):
    markdown_it = pytest.importorskip("markdown_it")  # the docs extra
    monkeypatch.chdir(tmp_path)
    root = tmp_path / "d<img src=x onerror=alert(1)>"
    settings, _ = write_synthetic_audit(root, n_frames=1, **SMALL)
    seg = np.zeros((SMALL["height"], SMALL["width"]), np.uint8)
    seg[5:15, 10:30] = 3
    np.save(root / "seg_f00.npy", seg)
    import_audit({**settings, "segmentation": str(root / "seg_{frame}.npy"), "glass_ids": [7]})
    record = record_of()
    (flag,) = flags_of(record, "glass_ids")  # names the segmentation's path
    assert "<img src=x onerror=alert(1)>" in flag["text"]
    base = Path("results/audit/synthetic")
    outputs = {"md": base / "verdict.md", "html": base / "verdict.html",
               "summary": base / "summary.json"}
    found = "1 frame [from](javascript:alert(2)) <b>here</b>"
    verdict_job([], [], [], outputs, name="synthetic", found=found,
                imports=[import_record("synthetic", "f00")])
    md = outputs["md"].read_text()
    rendered = markdown_it.MarkdownIt("commonmark", {"html": True}).enable("table").render(md)
    assert "<img" not in rendered and "<b>" not in rendered and "<a " not in rendered
    # shown as text, once rendered
    shown = html.unescape(re.sub(r"<[^>]+>", "", rendered))
    assert flag["text"] in shown and f"{found}." in shown
    assert "<img" not in outputs["html"].read_text()  # the HTML page escapes it too


def test_user_text_opening_a_line_or_in_alt_text_opens_no_markdown_block_or_link():
    markdown_it = pytest.importorskip("markdown_it")  # the docs extra
    from stereovar.audit.page import to_markdown_page

    sections = {
        "title": "Audit a: verdict",
        "banners": [],
        "decision": {"light": "green", "headline": "h", "sentences": ["s."]},
        "found": "[shot]: https://evil.example/a",  # a link reference definition
        "facts": [],
        "flags": [],
        "thumbnails": ["thumbs/shot]x.png"],  # a ] in the alt text
        "verdict": "v",
        "seeding": "s",
        "table": [],
        "caption": "    # not a heading",
        "mitigations": ["1. not a list", "[fig]: https://evil.example/b"],
        "probe": "- not a list",
        "figures": ["fig[1].png"],
    }
    md = to_markdown_page(sections)
    rendered = markdown_it.MarkdownIt("commonmark").enable("table").render(md)
    assert '"https://evil' not in rendered and "<a " not in rendered  # no link defined
    assert rendered.count("<h1>") == 1 and rendered.count("<pre>") == 0
    for text in ("<p>[shot]: https://evil.example/a.</p>", "<p># not a heading</p>",
                 "<li>1. not a list</li>", "<li>[fig]: https://evil.example/b</li>",
                 "<p>- not a list</p>"):
        assert text in rendered
    # each image is one image of its own path (markdown-it drops escapes from alt text)
    images = re.findall(r'<img src="([^"]*)" alt="([^"]*)"', rendered)
    assert [src for src, _ in images] == ["thumbs/shot%5Dx.png", "fig%5B1%5D.png"]
    assert [alt[:3] for _, alt in images] == ["sho", "fig"]


# -- E: Snakemake path variables in audit paths ------------------------------------------------


def snakemake_changes(path: str) -> bool:
    """Whether Snakemake's default path variables change ``path`` or stop on it."""
    from snakemake.exceptions import UndefinedPathvarException
    from snakemake.pathvars import Pathvars

    try:
        return Pathvars.with_defaults().apply(path) != path
    except UndefinedPathvarException:
        return True


PLAIN_AUDIT = {
    "name": "a",
    "renders": "data/{frame}/{view}/seed_{seed}.exr",
    "views": {"left": "L", "right": "R"},
    "disparity": "data/{frame}.pfm",
}


@pytest.mark.parametrize(
    "key, value",
    [
        ("root", "/data/<b>"),
        ("renders", "data/<b>/{frame}/{view}/seed_{seed}.exr"),
        ("disparity", "data/<results>/{frame}.pfm"),
        ("depth", "data/<logs>/{frame}.exr"),
        ("segmentation", "seg/<b>{frame}.png"),
        ("glass_mask", "masks/<mask_1>/{frame}.png"),
        ("views.right", "R<b>"),
    ],
)
def test_snakemake_path_variables_in_audit_paths_are_refused_in_one_line(key, value):
    assert snakemake_changes(value)
    settings = {**PLAIN_AUDIT, "views": dict(PLAIN_AUDIT["views"])}
    if key.startswith("views."):
        settings["views"]["right"] = value
    else:
        settings[key] = value
    word = re.search(r"<[^>]*>", value).group()
    with pytest.raises(AuditError) as err:
        discover_audit(settings)
    assert one_line(err) == (
        f"audit.{key} {value!r} holds {word}, which Snakemake reads as a path variable (an "
        "unknown one stops the workflow, a known one such as <results> is replaced by its "
        "folder); rename the folder or file so that no <word> is in the path, and set "
        f"audit.{key} to the new path"
    )


def test_an_audit_in_a_folder_named_like_a_path_variable_is_refused(tmp_path):
    settings, _ = write_synthetic_audit(tmp_path / "<results>", n_frames=1, **SMALL)
    assert snakemake_changes(settings["renders"])  # Snakemake would read results/...
    with pytest.raises(AuditError, match=r"^audit.renders .* holds <results>, which Snakemake"):
        discover_audit(settings)
    # what Snakemake leaves as it is is read
    for name in ("<img src=x>", "<B>", "a<1>"):
        assert not snakemake_changes(name)
        settings, _ = write_synthetic_audit(tmp_path / name, n_frames=1, **SMALL)
        assert discover_audit(settings).summary() == "1 frame × 2 views × 4 seeds"


# -- F: numpydoc sections of the functions these rest on -------------------------------------


def numpydoc_sections(func) -> dict:
    """Section title to its lines in a numpydoc docstring (a title underlined by dashes)."""
    lines = inspect.getdoc(func).splitlines()
    sections, current = {}, None
    for k, line in enumerate(lines):
        if line.strip() and k + 1 < len(lines) and set(lines[k + 1].strip()) == {"-"}:
            current = sections.setdefault(line.strip(), [])
        elif current is not None and set(line.strip()) != {"-"}:
            current.append(line)
    return sections


@pytest.mark.parametrize(
    "dotted",
    [
        "stereovar.io.channels.named_as",
        "stereovar.io.images.read_labels",
        "stereovar.io.headers.stored_as_half",
        "stereovar.audit.page.markdown_text",
        "stereovar.audit.page.markdown_line",
        "stereovar.controls.sensor.normal_counts",
        "stereovar.probe.training.nonfinite_weights",
    ],
)
def test_the_functions_document_each_parameter_and_what_they_return(dotted):
    module, _, name = dotted.rpartition(".")
    if module.startswith("stereovar.probe"):
        pytest.importorskip("torch", reason="the probe extra (PyTorch) is not installed")
    func = getattr(importlib.import_module(module), name)
    sections = numpydoc_sections(func)
    listed = {
        word.strip()
        for line in sections.get("Parameters", [])
        if line and not line[0].isspace()  # "name : type" lines, not their descriptions
        for word in line.split(" : ")[0].split(",")
    }
    assert set(inspect.signature(func).parameters) <= listed, sorted(listed)
    assert any(line.strip() for line in sections.get("Returns", [])), "no Returns section"
