"""The audit's decision page: seeding checks, flags on its own numbers, every import warning
on the page, and the traffic light."""

import json
import os
from html import unescape

import cv2
import numpy as np
import pytest

from stereovar.audit.decision import decision
from stereovar.audit.flags import EDGE, NULL_OFF, control_flags
from stereovar.audit.importer import CLIPPED_WARNING, import_audit, import_record
from stereovar.audit.page import import_flags, page_sections, to_html_page, to_markdown_page
from stereovar.audit.seeding import seeding_finding
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.errors import AuditError
from stereovar.io.images import read_image
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field, write_image
from stereovar.jobs.audit import seeding_job
from stereovar.statistics.residuals import SHARED_STREAMS

SMALL = {"width": 64, "height": 40, "n_seeds": 6}
LEFT = "results/audit/synthetic/renders/{frame}/left/spp0/seeds0-5.zarr"
RIGHT = "results/audit/synthetic/renders/{frame}/right/spp0/seeds0-5.zarr"
GT = "results/audit/synthetic/ground_truth/{frame}.zarr"


def render_path(settings, frame, letter, seed):
    return settings["renders"].format(frame=frame, view=letter, seed=f"{seed:03d}")


# -- seeding ---------------------------------------------------------------------------------


def test_renders_identical_across_seeds_are_one_line_naming_the_seed_setting(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    first = read_image(render_path(settings, "f00", "R", 0))
    for s in range(1, SMALL["n_seeds"]):
        write_image(render_path(settings, "f00", "R", s), first)
    with pytest.raises(AuditError) as err:
        import_audit(settings)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(
        f"frame f00, view right: all {SMALL['n_seeds']} renders are identical: the renderer "
        "was given the same seed"
    )
    assert "scene.cycles.seed" in message and "seed=" in message
    assert not os.path.exists(GT.format(frame="f00"))


def test_two_copied_renders_are_named(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    copy = read_image(render_path(settings, "f00", "L", 1))
    write_image(render_path(settings, "f00", "L", 4), copy)
    with pytest.raises(AuditError) as err:
        import_audit(settings)
    assert str(err.value).startswith(
        "frame f00, view left: 2 of its 6 renders are copies of one another (e.g. "
        "seed_001.exr and seed_004.exr)"
    )


def pooled_zero_disparity_rho(left, right, mask):
    """Pearson of the channel-mean per-seed residuals of the two views at the same pixel,
    each pixel's standardised over its seeds, pooled over seeds and the pixels of ``mask``
    (a plain loop over seeds)."""
    a, b = [], []
    for stack, out in ((left, a), (right, b)):
        grey = stack.astype(np.float64).mean(axis=-1)
        residual = (grey - grey.mean(axis=0)) / grey.std(axis=0, ddof=1)
        for n in range(stack.shape[0]):
            out.append(residual[n][mask])
    return float(np.corrcoef(np.concatenate(a), np.concatenate(b))[0, 1])


@pytest.mark.parametrize("shared", [True, False])
def test_views_that_share_their_random_streams_are_found(tmp_path, monkeypatch, shared):
    # shared: the right view's noise draws are the left view's at the same pixel (one
    # sampler seed in both views); independent: the synthetic renders as they are
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=2, **SMALL)
    for k, frame in enumerate(frames):
        if not shared:
            continue
        noise = (frame.renders["left"] - frame.clean["left"][None]) / np.sqrt(
            frame.variance["left"]
        )[None, ..., None]
        right = frame.clean["right"][None] + np.sqrt(frame.variance["right"])[
            None, ..., None
        ] * noise
        frame.renders["right"] = right.astype(np.float32)
        for s, image in enumerate(frame.renders["right"]):
            write_image(render_path(settings, f"f{k:02d}", "R", s), image)
    import_audit(settings)
    rows = []
    for k, frame in enumerate(frames):
        name = f"f{k:02d}"
        out = tmp_path / f"seeding_{name}.csv"
        frame_rows = seeding_job(
            [LEFT.format(frame=name)], [RIGHT.format(frame=name)], GT.format(frame=name), out
        )
        zero = next(r for r in frame_rows if r["alignment"] == "zero")
        mask = frame.valid  # every valid left pixel: no glass mask, no occlusion
        expected = pooled_zero_disparity_rho(frame.renders["left"], frame.renders["right"], mask)
        assert zero["rho"] == pytest.approx(expected, rel=1e-9, abs=1e-12)
        assert zero["n_pixels"] == int(mask.sum())
        rows += frame_rows
    finding = seeding_finding(rows)
    value, low, high = finding["zero"]
    assert finding["shared"] is shared
    if shared:
        assert low > SHARED_STREAMS and value > 0.5
        assert finding["text"].startswith("The two views share their random streams")
    else:
        assert abs(value) < 0.05 and low < SHARED_STREAMS
        assert finding["text"].startswith("The two views' random streams are independent")


# -- flags on the verdict's numbers ----------------------------------------------------------


def row(quantity, value, low, high, region="all"):
    return {"quantity": quantity, "region": region, "value": value, "low": low, "high": high,
            "note": ""}


def test_control_flags_against_their_rules():
    rows = [
        row("Pearson rho after the warp", 0.5, 0.4, 0.6),
        row("null: disparity shifted", 0.368, 0.185, 0.551),  # the 8-bit PNG case
        row("null: right field flipped", 0.02, -0.05, 0.09),  # about 0
        row("null: right field flipped", NULL_OFF / 2, 0.01, 0.09, "glass"),  # small: kept
        row("null: no warp", 0.3, 0.2, 0.4),  # below the warp: smooth fields, kept
        row("null: no warp", 0.6, 0.5, 0.7, "glass"),  # no warp in glass, warp absent: kept
        row("attenuation-corrected rho", 1.019, 0.9, 1.1, "glass"),
        row("attenuation-corrected rho", 0.9, 0.8, 1.0),
    ]
    frames = [
        {"scene": "f001", "region": "non_glass", "method": "warp", "rho": 0.851,
         "boot_low": 0.403, "boot_high": 0.852},  # at the edge: a few tiles decide it
        {"scene": "f000", "region": "all", "method": "warp", "rho": 0.6, "boot_low": 0.5,
         "boot_high": 0.7},
        {"scene": "f000", "region": "all", "method": "spearman", "rho": 0.7, "boot_low": 0.5,
         "boot_high": 0.7},  # not a flagged statistic
    ]
    flags = control_flags(rows, frames)
    assert [f["kind"] for f in flags] == ["control", "corrected_above_1", "edge_of_interval"]
    assert "null: disparity shifted (all) is 0.368 [0.185, 0.551], not about 0" in flags[0]["text"]
    assert "1.019, above 1" in flags[1]["text"]
    assert flags[2]["frame"] == "f001" and "[0.403, 0.852]" in flags[2]["text"]
    # the edge rule by brute force over positions inside one interval
    for value in np.linspace(0.0, 1.0, 101):
        one = [{"scene": "f", "region": "all", "method": "partial", "rho": value,
                "boot_low": 0.0, "boot_high": 1.0}]
        at_edge = min(value, 1.0 - value) < EDGE
        assert bool(control_flags([], one)) == at_edge, value
    # no warp correlating as much as the warp is flagged
    same = [row("Pearson rho after the warp", 0.5, 0.4, 0.6),
            row("null: no warp", 0.55, 0.45, 0.65)]
    assert [f["kind"] for f in control_flags(same, [])] == ["control"]


def verdict_result(mc, word="strong", matching=None):
    return {"mc_specific": mc, "strength": word, "matching_cue": matching, "text": "t"}


@pytest.mark.parametrize(
    "mc, word, shared, flags, light",
    [
        (True, "strong", False, [], "red"),
        (True, "moderate", False, [], "red"),
        (True, "weak", False, [], "amber"),
        (None, "not testable", False, [], "amber"),
        (False, "none detected", False, [{"kind": "clipped", "text": "x"}], "amber"),
        (False, "none detected", True, [], "red"),
        (False, "none detected", False, [], "green"),
    ],
)
def test_traffic_light(mc, word, shared, flags, light):
    opening = decision(verdict_result(mc, word), {"shared": shared}, flags, [])
    assert opening["light"] == light
    assert 2 <= len(opening["sentences"]) <= 3
    if mc or shared:
        assert "audit.mitigations" in opening["sentences"][-1]
    if shared:
        assert "share their random streams" in opening["headline"]
        assert "scene.cycles.seed" in opening["sentences"][-1]


def test_what_to_do_comes_from_the_measured_mitigation_table():
    findings = ["none: ...", "sensor_only: ...", "Removes the Monte Carlo-specific part: "
                "sensor_only (PSNR 28.00 dB [27.00, 29.00] against 30.00 dB as rendered)."]
    opening = decision(verdict_result(True), {"shared": False}, [], findings)
    assert opening["sentences"][-1] == "Measured on these renders (audit.mitigations): " + (
        findings[-1])


def test_where_no_mitigation_removes_it_the_advice_names_a_budget_or_the_probe():
    """No mitigation removes the cue at the audit's budget: the advice is the dose-response's
    budget and camera where one removes it, else the probe of the team's own network, never
    a dead end."""
    from stereovar.statistics.dose_response import dose_findings

    none = ["none: ...", "No mitigation removes the Monte Carlo-specific part."]
    row = {"transform": "sensor_only", "gain": 30.0, "read_noise": 2.0, "multiple": 4,
           "shipped_spp": 256, "render_cost": 8.0, "mc_specific": 0.03,
           "mc_specific_low": 0.01, "mc_specific_high": 0.05, "psnr": 18.3, "margin": 0.1,
           "margin_strength": 0.5}
    removing = dose_findings([{**row, "kind": "predicted", "mc_cue": "removed"}])
    opening = decision(verdict_result(True), {"shared": False}, [], none, dose=removing)
    advice = opening["sentences"][-1]
    assert "To remove it: sensor_only with a camera of gain 30" in advice
    assert "256 SPP per image" in advice and "stereovar probe" not in advice
    stays = dose_findings([{**row, "kind": "predicted", "mc_specific": 0.3,
                            "mc_specific_low": 0.25, "mc_specific_high": 0.35,
                            "mc_cue": "remains"}])
    advice = decision(verdict_result(True), {"shared": False}, [], none, dose=stays)[
        "sentences"][-1]
    assert "no budget up to 256 SPP per image removes it" in advice
    assert "stereovar probe --model" in advice and "--config audit.yaml" in advice
    # without the dose-response, the advice names it and the probe: never a dead end
    advice = decision(verdict_result(True), {"shared": False}, [], none)["sentences"][-1]
    assert "add sensor_only to audit.mitigations" in advice and "stereovar probe" in advice


# -- every import warning reaches the page ---------------------------------------------------


def png8(stack, divisor):
    """Linear 8-bit codes of renders at 1/``divisor`` of full scale."""
    return [np.round(np.clip(r / divisor, 0.0, 1.0) * 255).astype(np.uint8) for r in stack]


def png_audit(tmp_path, *, divisor, transfer, **extra):
    """One synthetic frame written as 8-bit PNG renders at 1/``divisor`` of full scale."""
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    codes = {}
    for view, letter in (("left", "L"), ("right", "R")):
        codes[view] = png8(frames[0].renders[view], divisor)
        for s, c in enumerate(codes[view]):
            exr = render_path(settings, "f00", letter, s)
            assert cv2.imwrite(exr.replace(".exr", ".png"), c[..., ::-1])
            os.remove(exr)
    settings = {**settings, "renders": settings["renders"].replace(".exr", ".png"), **extra}
    if transfer:
        settings.update(transfer="linear", scale=float(divisor))
    return settings, frames, codes


def page_of(records, flags=()):
    sections = page_sections(
        name="t", found="1 frame", decision=decision(verdict_result(False), {}, [], []),
        result=verdict_result(False), seeding={"text": "s"}, records=records,
        flags=import_flags(records) + list(flags), table=[], caption="c", mitigations=[],
        thumbnails=[], figures=[],
    )
    return to_html_page(sections), to_markdown_page(sections)


def record_of(frame="f00", name="synthetic"):
    return json.loads(open(import_record(name, frame)).read())


def assert_on_page(record, kind):
    flags = [f for f in record["found"]["warnings"] if f["kind"] == kind]
    assert flags, record["found"]["warnings"]
    html, md = page_of([record])
    for f in flags:
        text = f["text"]
        assert text in unescape(html)
        assert text in md
    return flags


def test_the_png_transfer_assumption_reaches_the_page(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, _, _ = png_audit(tmp_path, divisor=2.0, transfer=False)
    import_audit({**settings, "sign_check": "warn"})
    (flag,) = assert_on_page(record_of(), "transfer")
    assert flag["text"].startswith("PNG renders without audit.transfer are decoded as sRGB")


def test_variance_quantisation_reaches_the_page(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # dark: noise below one 8-bit step at many pixels (the sign check may not tell then)
    settings, frames, codes = png_audit(tmp_path, divisor=30.0, transfer=True)
    import_audit({**settings, "sign_check": "warn"})
    flags = assert_on_page(record_of(), "quantisation")
    # the share against a count: valid left pixels whose 8-bit codes agree in every seed
    valid = frames[0].valid
    same = np.array([
        [all(np.array_equal(codes["left"][0][y, x], c[y, x]) for c in codes["left"])
         for x in range(valid.shape[1])]
        for y in range(valid.shape[0])
    ])
    expected = (same & valid).sum() / valid.sum()
    assert record_of()["found"]["floored"]["left"] == pytest.approx(expected, abs=1e-12)
    assert any(f"{100 * expected:.1f}% of the valid pixels" in f["text"] for f in flags)


def test_clipped_png_pixels_reach_the_page(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # full scale at 0.8: the brightest texture blocks clip in some render
    settings, frames, codes = png_audit(tmp_path, divisor=0.8, transfer=True)
    import_audit(settings)
    valid = frames[0].valid
    clipped = np.zeros_like(valid)
    for c in codes["right"]:
        clipped |= (c == 255).any(axis=-1)
    record = record_of()
    gt = open_dataset(GT.format(frame="f00"))  # the right view's own valid pixels
    right_valid = gt["valid"].sel(view="right").transpose("y", "x").values
    expected = (clipped & right_valid).sum() / right_valid.sum()
    assert expected > CLIPPED_WARNING
    assert record["found"]["clipped"]["right"] == pytest.approx(expected, abs=1e-12)
    flags = assert_on_page(record, "clipped")
    assert any(f"right: {100 * expected:.1f}% of the valid pixels" in f["text"] for f in flags)
    html, _ = page_of([record])
    assert f"right {100 * expected:.2f}%" in html  # the import-facts column


def test_glass_ids_that_match_nothing_reach_the_page(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    seg = np.zeros((SMALL["height"], SMALL["width"]), np.float32)
    seg[10:20, 10:30] = 3
    write_field(tmp_path / "seg_f00.npy", seg)
    template = str(tmp_path / "seg_{frame}.npy")
    import_audit({**settings, "segmentation": template, "glass_ids": [3, 7]})
    (flag,) = assert_on_page(record_of(), "glass_ids")
    assert flag["text"] == (
        f"frame f00: audit.glass_ids [7] match no pixel of {tmp_path / 'seg_f00.npy'}; the ids it "
        "holds, largest first: 0 (2360 px), 3 (200 px); fix audit.glass_ids"
    )


def test_an_inconclusive_sign_check_is_a_banner(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # a disparity that is none: the sign cannot be settled; stops unless sign_check: warn
    settings, frames = write_synthetic_audit(tmp_path / "d", n_frames=1, **SMALL)
    rng = np.random.default_rng(0)
    write_field(settings["disparity"].format(frame="f00"),
                rng.uniform(20.0, 40.0, frames[0].disparity.shape).astype(np.float32))
    with pytest.raises(AuditError, match="sign check is inconclusive"):
        import_audit(settings)
    import_audit({**settings, "sign_check": "warn"})
    record = record_of()
    (flag,) = assert_on_page(record, "sign_check")
    html, md = page_of([record])
    assert html.index('class="banner"') < html.index('id="decision"')
    assert md.index("> **Warning.**") < md.index("**GREEN")
    assert "(inconclusive)" in html  # the facts' sign-check column


def test_control_flags_reach_the_page():
    flags = control_flags([row("null: disparity shifted", 0.368, 0.185, 0.551)], [])
    html, md = page_of([], flags)
    assert "control off its expected value" in html and flags[0]["text"] in md


def test_the_opening_quotes_its_numbers_with_intervals_and_controls():
    rows = [
        row("intensity-controlled rho", 0.6128, 0.5666, 0.6589),
        row("Pearson rho after the warp", 0.5501, 0.4843, 0.6158),
        row("camera baseline: simulated sensor, same N", 0.6905, 0.6798, 0.7012),
    ]
    seeding = {"shared": True, "zero": (0.3, 0.2, 0.4)}
    sure = decision(verdict_result(True), seeding, [], [], rows)["sentences"][0]
    assert "intensity-controlled rho is 0.613 [0.567, 0.659]" in sure
    assert "0.550 [0.484, 0.616] is beside 0.691 [0.680, 0.701] for a simulated camera" in sure
    assert "zero disparity is 0.300 [0.200, 0.400], where independent seeds give 0" in sure
