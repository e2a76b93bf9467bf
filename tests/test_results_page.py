"""The main run's results page, results/index.html (stereovar.pages.results): built from
synthetic results, then on the tiny run, and in headless Chromium."""

from __future__ import annotations

import base64
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from stereovar import layout
from stereovar.io.tables import read_rows, write_tables
from stereovar.jobs.claims import results_page_job
from stereovar.pages.controls import CONTROL_GROUPS, INTERVAL_NOTE, REGIONS
from stereovar.pages.headline import interval_keys
from stereovar.pages.names import claim_name
from stereovar.statistics.claims import CLAIMS_COLUMNS, load_claims

from .test_page_captions import REPOSITORY_PATHS

VERDICTS = ("holds", "does not hold", "explained by a control", "not testable at this scale")
METHODS = ("warp", *(m for _, _, methods in CONTROL_GROUPS for m, _ in methods))
RUN_FIGURES = ("fig1_teaser", "rho_vs_seeds")
CAPTIONS = {
    "fig1_teaser": "**Fig. 1.** The teaser of ``scene_000``: :math:`\\sigma^2_L` against "
    ":math:`\\hat\\sigma^2_{R\\to L}`.",
    "rho_vs_seeds": "rho against the number of seeds N'.",
    "mitigations": "**Mitigation trade-off.** The cue each mitigation leaves.",
    "probe": "**Learned probe.** Accuracy per test input.",
    "claims": "The paper's claims on this run. Read this first.",
    "workflow": "**stereovar** on a synthetic run.",
}


# ----------------------------------------------------------------------------- helpers


class Page(HTMLParser):
    """The parts of a page the tests read: every element's text by id, the claims table's
    rows by claim, the headline table's rows by statistic, images and links."""

    def __init__(self, text: str):
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, dict]] = []
        self.text_by_id: dict[str, str] = {}
        self.claims: dict[str, list[str]] = {}
        self.controls: dict[str, list[str]] = {}
        self.images: list[dict] = []
        self.links: list[str] = []
        self.scripts = 0
        self._open_ids: list[str] = []
        self._row: dict = {}
        self._cells: list[str] | None = None
        self._cell: list[str] | None = None
        self.feed(text)

    BLOCKS = {"p", "div", "td", "th", "tr", "li", "h1", "h2", "h3", "caption", "figcaption"}

    def _space(self, tag):
        """Block elements' texts are apart, as a browser shows them."""
        if tag in self.BLOCKS:
            for ident in self._open_ids:
                self.text_by_id[ident] += " "

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self._space(tag)
        if tag in ("img", "meta", "br", "hr", "link", "input"):
            if tag == "img":
                self.images.append(a)
            return
        self.stack.append((tag, a))
        if "id" in a:
            self._open_ids.append(a["id"])
            self.text_by_id.setdefault(a["id"], "")
        if tag == "a" and "href" in a:
            self.links.append(a["href"])
        if tag == "script":
            self.scripts += 1
        if tag == "tr":
            self._row = a
            self._cells = []
        if tag == "td" and self._cells is not None:
            self._cell = []

    def handle_endtag(self, tag):
        self._space(tag)
        while self.stack:
            t, a = self.stack.pop()
            if "id" in a:
                self._open_ids.remove(a["id"])
            if t == tag:
                break
        if tag == "td" and self._cell is not None:
            self._cells.append(" ".join("".join(self._cell).split()))
            self._cell = None
        elif tag == "tr" and self._cells is not None:
            if "data-claim" in self._row:
                self.claims[self._row["data-claim"]] = self._cells
            elif "data-method" in self._row:
                self.controls[self._row["data-method"]] = self._cells
            self._cells, self._row = None, {}

    def handle_data(self, data):
        for ident in self._open_ids:
            self.text_by_id[ident] += data
        if self._cell is not None:
            self._cell.append(data)


NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?")


def numbers(text: str) -> list[float]:
    """Every number in ``text``, in order."""
    return [float(x) for x in NUMBER.findall(text)]


def shown_interval(value, low, high) -> list[float]:
    """The numbers a value with its interval should show: none for a missing value, the
    value alone when either end is missing, else all three."""

    def finite(x):
        return x not in (None, "") and math.isfinite(float(x))

    if not finite(value):
        return []
    return [float(value)] if not (finite(low) and finite(high)) else [
        float(value), float(low), float(high)]


def close(shown: float, value: float, digits: int = 3) -> bool:
    """Whether ``shown`` is ``value`` to ``digits`` significant digits or decimals."""
    return math.isclose(shown, value, rel_tol=10 ** (1 - digits), abs_tol=10**-digits)


def formats(paths: list[str]) -> dict:
    """A table's paths by format (:func:`stereovar.io.tables.write_tables`)."""
    return dict(zip(layout.TABLE_FORMATS, paths, strict=True))


SCENES = ["scene_000", "scene_001", "scene_002"]


def scene_partials(seed: int = 0) -> tuple[list[dict], list[dict]]:
    """Each synthetic scene's intensity-controlled rho with its bootstrap interval (the
    correlation rows' columns), and its matched null through ``none`` (the calibration's
    ``calibration_nulls.csv`` columns)."""
    rng = np.random.default_rng(1000 + seed)
    corr, nulls = [], []
    for scene in SCENES:
        rho, half = float(rng.uniform(0.2, 0.7)), float(rng.uniform(0.02, 0.08))
        corr.append({"scene": scene, "region": "all", "method": "partial", "rho": rho,
                     "boot_low": rho - half, "boot_high": rho + 0.8 * half})
        nulls.append({"scene": scene, "transform": "none", "region": "all",
                      "method": "partial", "null_rho": float(rng.uniform(-0.02, 0.05)),
                      "null_se": float(rng.uniform(0.001, 0.01)), "n": 16,
                      "chance_sd": float(rng.uniform(0.01, 0.05)), "margin": 0.08})
    return corr, nulls


def synthetic_results(
    root: Path,
    *,
    mitigations: bool = False,
    probe: bool = False,
    generators: bool = False,
    nulls: bool = True,
    seed: int = 0,
) -> dict:
    """Write a run's results under ``root/results`` as the workflow would (claims table,
    summary.json, figures and tables of every format) and return the job's arguments,
    paths relative to ``root``."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    run = "results/mitsuba/seeds"
    claims = []
    for i, claim in enumerate(load_claims().claims):
        ours = float(rng.uniform(-1, 1))
        claims.append({
            "id": claim["id"], "claim": claim["text"], "section": claim["section"],
            "kind": claim["kind"], "paper": claim["paper"], "null": 0.0,
            "ours": ours, "ours_low": ours - 0.1, "ours_high": ours + 0.07,
            "control": "sensor_sim rho" if i % 3 else "",
            "control_value": float(rng.uniform(-0.2, 0.2)) if i % 3 else math.nan,
            "control_low": -0.3 if i % 3 else math.nan,
            "control_high": 0.3 if i % 3 else math.nan,
            "verdict": VERDICTS[i % len(VERDICTS)], "note": f"note {i}",
        })
    (root / "results/tables").mkdir(parents=True)
    tables = layout.claims_tables()
    write_tables(claims, CLAIMS_COLUMNS, formats(tables), caption="c")
    stats = layout.run_tables("mitsuba", "seeds", "statistics")
    (root / run / "tables").mkdir(parents=True)
    write_tables([{"a": 1}], ["a"], formats(stats))
    tables = [*tables, *stats]
    statistics = []
    for region in REGIONS:
        for method in METHODS:
            rho = float(rng.uniform(-0.5, 0.95))
            statistics.append({
                "region": region, "method": method, "mean_rho": rho,
                "boot_low": rho - float(rng.uniform(0.01, 0.1)),
                "boot_high": rho + float(rng.uniform(0.01, 0.1)),
                "scenes_low": max(rho - float(rng.uniform(0.1, 0.3)), -1.0),
                "scenes_high": min(rho + float(rng.uniform(0.1, 0.3)), 1.0),
                "std_rho": 0.1, "n_scenes": 3, "mean_rho_corrected": rho,
            })
    # the intensity-controlled rho over all pixels as the statistics table makes it from the
    # scenes' rows: the mean with their bootstrap intervals combined
    from stereovar.statistics.across import combined_interval

    corr, null_rows = scene_partials(seed)
    mean, low, high = combined_interval(*([r[k] for r in corr] for k in ("rho", "boot_low",
                                                                           "boot_high")))
    for row in statistics:
        if (row["region"], row["method"]) == ("all", "partial"):
            row |= {"mean_rho": mean, "boot_low": low, "boot_high": high}
    if nulls:
        from stereovar.calibration.summary import NULL_COLUMNS

        path = layout.calibration_nulls()
        write_tables(null_rows, NULL_COLUMNS, {"csv": path})
        tables = [*tables, path]
    summary = {
        "config_digest": "ab" * 32, "renderer": "mitsuba", "estimator": "seeds", "spp": 2,
        "n_seeds": 4, "scenes": SCENES,
        "interval": "95% spatial block bootstrap (scenes combined)",
        "statistics": statistics,
    }
    layout_summary = root / layout.summary_json()
    layout_summary.write_text(json.dumps(summary))
    (root / run / "figures").mkdir(parents=True)
    figures = []
    for i, name in enumerate(RUN_FIGURES):  # the first wider than the page, as real ones are
        path = layout.run_figure("mitsuba", "seeds", name)
        Image.new("RGB", (1600 if i == 0 else 320, 160), (40 * i, 90, 160)).save(root / path)
        figures.append(path)
    kwargs = {
        "claims": tables[0],
        "summary": layout.summary_json(),
        "figures": figures,
        "tables": tables,
        "captions": CAPTIONS,
        "out": layout.results_page(),
    }
    (root / "results/figures").mkdir()
    if mitigations:
        rows = [
            {"mitigation": m, "kind": kind, "region": region, "spp": 32, "render_spp": 32,
             "partial": p, "partial_low": p - 0.1, "partial_high": p + 0.1,
             "null_partial": null, "mc_specific": p - null, "mc_specific_low": p - null - 0.03,
             "mc_specific_high": p - null + 0.02, "margin": 0.05, "mc_cue": cue,
             "residual_rho_zero": 0.0, "residual_rho_zero_low": -0.1,
             "residual_rho_zero_high": 0.1, "psnr": q, "psnr_low": q - 1, "psnr_high": q + 1}
            for m, kind, p, null, cue, q in (
                ("none", "baseline", 0.5, 0.001, "remains", 30.0),
                ("denoise", "transform", 0.81, 0.8, "removed", 33.0),
            )
            for region in ("all", "glass")
        ]
        paths = layout.mitigation_tables()
        write_tables(rows, list(rows[0]), formats(paths))
        Image.new("RGB", (200, 100), (10, 120, 40)).save(root / layout.mitigation_figure())
        kwargs |= {"mitigations": paths[0], "mitigation_figure": layout.mitigation_figure()}
        kwargs["tables"] = [*kwargs["tables"], *paths]
    if probe:
        paths = layout.probe_tables()
        write_tables([{"training": "none"}], ["training"], formats(paths))
        verdict = {"uses_cue": True, "paragraph": "The trained matcher uses the cue (synthetic)."}
        (root / layout.probe_verdict()).write_text(json.dumps(verdict))
        Image.new("RGB", (200, 100), (160, 40, 40)).save(root / layout.probe_figure())
        kwargs |= {"probe": layout.probe_verdict(), "probe_figure": layout.probe_figure()}
        kwargs["tables"] = [*kwargs["tables"], *paths]
    if generators:
        from stereovar.statistics.generators import GENERATOR_COLUMNS

        rows = []
        for profile, value, own in (("paper", 0.466, 64), ("kubric", 0.026, 128)):
            row = dict.fromkeys(GENERATOR_COLUMNS, math.nan)
            row |= {"profile": profile, "region": "all", "spp": 64, "generator_spp": own,
                    "adaptive": "off", "denoiser": "off", "seed_rule": "per_view",
                    "mc_specific": value, "mc_specific_low": value - 0.07,
                    "mc_specific_high": value + 0.07, "null_partial": 0.819,
                    "mc_cue": "remains", "probe": "not run"}
            rows.append(row)
        paths = layout.generator_tables()
        write_tables(rows, GENERATOR_COLUMNS, formats(paths))
        Image.new("RGB", (200, 100), (40, 40, 160)).save(root / layout.generator_figure())
        kwargs |= {"generators": paths, "generators_figure": layout.generator_figure()}
    return kwargs


def build_page(root: Path, kwargs: dict) -> tuple[str, Page]:
    """Build the page of the results under ``root`` (the working directory)."""
    results_page_job(**kwargs)
    text = (root / layout.results_page()).read_text(encoding="utf-8")
    return text, Page(text)


@pytest.fixture
def synthetic(tmp_path, monkeypatch):
    """A function: write synthetic results in a new folder of ``tmp_path`` (made the working
    directory) and build their page; returns (folder, job arguments, page text, page)."""

    def build(name: str = "run", **options):
        root = tmp_path / name
        root.mkdir()
        monkeypatch.chdir(root)
        kwargs = synthetic_results(root, **options)
        return root, kwargs, *build_page(root, kwargs)

    return build


OWN_SCALE = {c["id"] for c in load_claims().claims if c.get("paper_scale") == "own"}
"""Claims whose paper value is in the paper's own units: the page gives its sign."""


def check_claims(page: Page, claims: list[dict]) -> None:
    """Every claims-table row is on the page: its claim by name, paper value, our value with
    its interval, its control and its verdict."""
    assert list(page.claims) == [str(c["id"]) for c in claims]
    for c in claims:
        claim, paper, ours, control, verdict = page.claims[str(c["id"])]
        assert claim.startswith(claim_name(str(c["id"]), str(c["claim"])))
        assert verdict == c["verdict"]
        expected = shown_interval(c["ours"], c["ours_low"], c["ours_high"])
        if not expected:
            assert ours == "n/a"
        else:
            shown = numbers(ours)
            assert len(shown) == len(expected), ours
            assert all(close(s, v) for s, v in zip(shown, expected, strict=True)), ours
        if str(c["id"]) in OWN_SCALE:  # the paper's own units: its sign, the value named
            sign = "> 0" if c["paper"] > 0 else "< 0"
            assert paper.startswith(sign) and "own units" in paper, paper
            assert close(numbers(paper.split("paper's", 1)[1])[0], c["paper"])
        elif isinstance(c["paper"], (int, float)) and math.isfinite(c["paper"]):
            assert close(numbers(paper)[0], c["paper"])
        if c["control"] and math.isfinite(float(c["control_value"] or math.nan)):
            name, _, value = control.rpartition(":")
            assert name and "_" not in name, control  # the control in words
            assert close(numbers(value)[0], float(c["control_value"]))


def expected_matched(corr: list[dict], nulls: list[dict]) -> tuple[float, float, float, float]:
    """The Monte Carlo-specific rho over all pixels as the mitigation table computes it
    (scene by scene, then combined): (null, difference, low, high)."""
    from stereovar.statistics.matched_null import matched_difference

    return matched_difference(corr, nulls, transform="none", region="all")


def check_headline(page: Page, summary: dict, matched=None) -> None:
    """The headline with its interval and its control: the Monte Carlo-specific rho beside
    its matched null when the run has one (``matched``: :func:`expected_matched`), else rho
    after the warp; and each control of the summary by region with its interval."""
    stats = {(r["region"], r["method"]): r for r in summary["statistics"]}
    main = stats[("all", "warp")]
    text = " ".join(page.text_by_id["headline"].split())
    value = re.search(r"ρ = (\S+)", page.text_by_id["headline-value"])
    interval = re.search(r"95% interval \[(\S+), (\S+)\]", text)
    control = " ".join(page.text_by_id["headline-control"].split())
    if matched is not None:
        null, diff, low, high = matched
        assert value and close(float(value.group(1)), diff)
        assert interval and close(float(interval.group(1)), low)
        assert close(float(interval.group(2)), high)
        assert "matched null" in control and close(numbers(control)[0], null)
        warp = " ".join(page.text_by_id["headline-warp"].split())
        assert close(numbers(warp.split(":", 1)[1])[0], main["mean_rho"])
    else:
        assert value and close(float(value.group(1)), main["mean_rho"])
        assert interval and close(float(interval.group(1)), main["scenes_low"])
        assert close(float(interval.group(2)), main["scenes_high"])
    # one row per statistic: its label, then a cell per region
    controls = {m for _, _, methods in CONTROL_GROUPS for m, _ in methods}
    expected_controls = controls & {m for _, m in stats}
    shown = {m: cells[1:] for m, cells in page.controls.items()}
    own = {"mc_specific", "matched_null"} if matched is not None else set()
    assert set(shown) == {"warp", *own, *expected_controls}
    assert {"sensor_sim", "partial", "null_shift"} <= expected_controls  # baseline, intensity, null
    for method, cells in shown.items():
        assert len(cells) == len(REGIONS)
        if method in own:
            null, diff, low, high = matched
            want = [diff, low, high] if method == "mc_specific" else [null]
            assert all(close(g, v) for g, v in zip(numbers(cells[0]), want, strict=True))
            continue
        for region, cell in zip(REGIONS, cells, strict=True):
            row = stats.get((region, method)) or {}
            expected = shown_interval(*(row.get(k) for k in ("mean_rho", *interval_keys(method))))
            if not expected:
                assert cell == "n/a", (method, region, cell)
                continue
            got = numbers(cell)
            assert len(got) == len(expected), (method, region, cell)
            assert all(close(g, v) for g, v in zip(got, expected, strict=True)), (method, cell)


def check_links(page: Page, results: Path) -> None:
    """Every link is relative and resolves to a file under ``results``; nothing is loaded
    from elsewhere and the page runs no script."""
    from stereovar.links import docs_base

    assert page.scripts == 0
    for href in page.links:
        if href.startswith("#"):
            assert href[1:] in page.text_by_id, href
            continue
        if href.startswith(docs_base()):  # the documentation (stereovar.links), never a path
            continue
        assert "://" not in href and not href.startswith("/"), href
        target = (results / href).resolve()
        assert target.is_file(), href
        assert target.is_relative_to(results.resolve()), href
    for image in page.images:
        assert image["src"].startswith("data:image/png;base64,"), image["src"][:40]


# ----------------------------------------------------------------------------- unit tests


def test_page_shows_every_claim_with_its_interval_control_and_verdict(synthetic):
    _, kwargs, _, page = synthetic()
    claims = read_rows(kwargs["claims"])
    check_claims(page, claims)
    assert {c["verdict"] for c in claims} == set(VERDICTS)


def test_headline_is_the_monte_carlo_specific_rho_beside_its_matched_null(synthetic):
    _, kwargs, text, page = synthetic()
    summary = json.loads(Path(kwargs["summary"]).read_text())
    check_headline(page, summary, expected_matched(*scene_partials()))
    assert INTERVAL_NOTE in " ".join(page.text_by_id["headline"].split())
    # the conclusion, the headline and the claims come before the figures
    assert text.index('id="conclusion"') < text.index('id="headline"')
    assert text.index('id="headline"') < text.index('id="claims"') < text.index('id="figures"')


def test_without_a_matched_null_the_headline_is_rho_after_the_warp_not_called_specific(
    synthetic,
):
    _, kwargs, _, page = synthetic(nulls=False)
    check_headline(page, json.loads(Path(kwargs["summary"]).read_text()))
    shown = " ".join((page.text_by_id["conclusion"] + page.text_by_id["headline"]).split())
    assert "Not calibrated" in shown and "Monte Carlo-specific ρ =" not in shown


def test_a_headline_without_its_interval_says_so(synthetic):
    root, kwargs, _, _ = synthetic(nulls=False)
    summary = json.loads(Path(kwargs["summary"]).read_text())
    for row in summary["statistics"]:
        if (row["region"], row["method"]) == ("all", "warp"):
            row["boot_low"] = row["boot_high"] = row["scenes_low"] = row["scenes_high"] = None
    Path(kwargs["summary"]).write_text(json.dumps(summary))
    _, page = build_page(root, kwargs)
    text = " ".join(page.text_by_id["headline"].split())
    assert "no interval" in text and "95% interval [" not in text


@pytest.mark.parametrize("nulls", [True, False], ids=["matched null", "no null"])
def test_a_number_explained_by_a_control_says_so_beside_it(synthetic, nulls):
    root, kwargs, _, _ = synthetic(nulls=nulls)
    claims = read_rows(kwargs["claims"])
    for c in claims:  # rho over all pixels explained, the rest not
        c["verdict"] = "explained by a control" if c["id"] == "rho_all" else "holds"
    write_tables(claims, CLAIMS_COLUMNS, formats(layout.claims_tables()), caption="c")
    _, page = build_page(root, kwargs)
    warp = page.controls["warp"]
    assert "explained by a control" in warp[1]  # all valid pixels
    assert "explained by a control" not in " ".join(warp[2:])
    beside = page.text_by_id["headline-warp" if nulls else "headline-control"]
    assert "explained by a control" in beside.lower()
    if nulls:  # the big number is then the Monte Carlo-specific one, not the explained one
        assert "matched null" in page.text_by_id["headline-control"]


def test_the_page_opens_with_a_one_line_conclusion(synthetic):
    _, kwargs, text, page = synthetic()
    body = text[text.index("<body>"):]
    assert re.match(r"<body>\s*<h1>[^<]*</h1>\s*<p class=\"conclusion\" id=\"conclusion\"", body)
    conclusion = " ".join(page.text_by_id["conclusion"].split())
    null, diff, low, high = expected_matched(*scene_partials())
    word = {"remains": "Cue present", "removed": "No cue"}.get(
        "remains" if low > 0 else "removed" if -0.08 < low and high < 0.08 else "", "Undecided")
    assert conclusion.startswith(word)
    got = numbers(conclusion.split("ρ =", 1)[1])
    assert all(close(g, v) for g, v in zip(got, (diff, low, high, null), strict=False))
    assert "matched null" in conclusion and len(got) >= 4


def test_figures_are_embedded_with_their_captions(synthetic):
    _, kwargs, _, page = synthetic()
    assert len(page.images) == len(kwargs["figures"])
    for image, path in zip(page.images, kwargs["figures"], strict=True):
        assert base64.b64decode(image["src"].split(",", 1)[1]) == Path(path).read_bytes()
        name = Path(path).stem
        caption = " ".join(page.text_by_id[f"figure-{name}"].split())
        if ":math:" in CAPTIONS[name]:  # typeset as MathML: σ, its sub- and superscript
            assert caption.startswith("Fig. 1. The teaser of scene_000: σ L 2 against σ")
        else:
            assert caption == re.sub(r"\*\*|``", "", CAPTIONS[name])


def test_links_resolve_relative_to_results_and_cover_every_table(synthetic):
    root, kwargs, _, page = synthetic(mitigations=True, probe=True)
    results = root / "results"
    check_links(page, results)
    linked = {(results / h).resolve() for h in page.links if not h.startswith("#")}
    assert {(root / t).resolve() for t in kwargs["tables"]} <= linked
    assert [h for h in page.links if "://" in h]  # the documentation is linked


def test_snakemake_report_is_linked_once_it_exists(synthetic):
    root, kwargs, text, page = synthetic()
    assert "<code>stereovar report</code>" in text and "snakemake --report" not in text
    assert "report.html" not in page.links
    (root / layout.snakemake_report()).write_text("<html></html>")
    _, page = build_page(root, kwargs)
    assert "report.html" in page.links
    check_links(page, root / "results")


def test_mitigations_and_probe_sections_appear_when_they_have_run(synthetic):
    _, _, text, _ = synthetic()
    assert 'id="mitigations"' not in text and 'id="probe"' not in text
    _, kwargs, text, page = synthetic("with", mitigations=True, probe=True)
    mitigations = " ".join(page.text_by_id["mitigations"].split())
    assert "denoise" in mitigations and "Removes the Monte Carlo-specific part" in mitigations
    assert "The trained matcher uses the cue (synthetic)." in page.text_by_id["probe"]
    embedded = [base64.b64decode(i["src"].split(",", 1)[1]) for i in page.images]
    for key in ("mitigation_figure", "probe_figure"):
        assert Path(kwargs[key]).read_bytes() in embedded
    assert "tables/mitigations.csv" in page.links and "tables/probe.csv" in page.links
    assert text.index('id="figures"') < text.index('id="mitigations"') < text.index('id="probe"')


def test_one_compact_mitigation_table_with_the_full_table_linked(synthetic):
    _, kwargs, text, page = synthetic(mitigations=True)
    section = text[text.index('<section id="mitigations">'):]
    section = section[: section.index("</section>")]
    assert section.count("<table") == 1  # once, not twice
    header = re.findall(r"<th>(.*?)</th>", section)
    assert len(header) <= 8 and "matched null" in header and "verdict" in header
    body = section[section.index("<tbody>"): section.index("</tbody>")]
    cells = [[" ".join(re.sub(r"<[^>]+>", " ", c).split()) for c in re.findall(
        r"<td[^>]*>(.*?)</td>", row)] for row in re.findall(r"<tr>(.*?)</tr>", body, re.S)]
    rows = [r for r in read_rows(kwargs["mitigations"]) if r["region"] == "all"]
    assert len(cells) == len(rows)  # one row per mitigation, all valid pixels
    column = {name: header.index(name) for name in header}
    for shown, row in zip(cells, rows, strict=True):
        assert shown[column["mitigation"]] == row["mitigation"]
        specific = numbers(shown[column["Monte Carlo-specific ρ of its renders [95%]"]])
        assert all(close(g, v) for g, v in zip(specific, [row["mc_specific"],
                   row["mc_specific_low"], row["mc_specific_high"]], strict=True))
        assert close(numbers(shown[column["matched null"]])[0], row["null_partial"])
        assert shown[column["verdict"]] == row["mc_cue"]
        assert close(numbers(shown[column["PSNR, dB [95%]"]])[0], row["psnr"])
    assert "tables/mitigations.csv" in re.findall(r'href="([^"]+)"', section)


def test_claims_read_by_name_and_section_name_not_by_identifier(synthetic):
    _, kwargs, _, page = synthetic()
    for claim in read_rows(kwargs["claims"]):
        name_and_section = page.claims[str(claim["id"])][0]
        assert not re.search(r"_|\b(sec|tab|fig):|decorr\.", name_and_section), name_and_section
    assert "Sec. 3.4, causal evidence" in " ".join(c[0] for c in page.claims.values())


def test_the_generator_section_appears_once_the_generators_have_run(synthetic):
    _, _, text, _ = synthetic()
    assert 'id="generators"' not in text
    _, kwargs, text, page = synthetic("with", generators=True)
    shown = " ".join(page.text_by_id["generators"].split())
    # each profile's Monte Carlo-specific rho with its interval, beside its matched null
    assert "kubric 64 of 128 (x1/2)" in shown
    assert "0.026 [-0.044, 0.096] 0.819 remains" in shown
    assert "0.466 [0.396, 0.536]" in shown
    embedded = [base64.b64decode(i["src"].split(",", 1)[1]) for i in page.images]
    assert Path(kwargs["generators_figure"]).read_bytes() in embedded
    assert "tables/generators.csv" in page.links and '<a href="#generators">' in text


# ----------------------------------------------------------------------------- in a browser

VIEWPORT = (1280, 900)
"""The browser window the page is checked in (a laptop's)."""

CLAIMS_PROBE = """JSON.stringify((() => {
  const table = document.getElementById("claims-table");
  const r = table ? table.getBoundingClientRect() : {left: 0, top: 0, right: 0, bottom: 0};
  const box = (id) => {
    const e = document.getElementById(id);
    if (!e) return null;
    const b = e.getBoundingClientRect();
    return [b.top, b.bottom];
  };
  const scrolls = (e) => ["auto", "scroll"].includes(getComputedStyle(e).overflowX);
  const overflow = [...document.querySelectorAll("body *")]
    .filter(e => e.clientWidth > 0 && !scrolls(e) && e.scrollWidth > e.clientWidth + 1)
    .map(e => `${e.tagName}#${e.id}.${e.className}: ${e.textContent.slice(0, 80)}`);
  return {rect: [r.left, r.top, r.right, r.bottom],
          ids: [...document.querySelectorAll("#claims-table tr[data-claim]")]
                 .map(row => row.dataset.claim),
          overflow: overflow,
          page_width: document.documentElement.scrollWidth,
          text: document.body.innerText,
          images: [...document.images].map(i => [i.alt, i.complete, i.naturalWidth]),
          math: document.querySelectorAll("math").length,
          conclusion: box("conclusion"), headline: box("headline-value")};
})())"""
"""What the page shows: the claims table's box in the viewport and its rows' claims; every
element whose text overflows its box (scroll containers aside), the page's width, the
visible text, each image's load, the MathML elements, and the boxes of the conclusion and
the headline number."""

TEX_MARKERS = ("_{", "^{", "\\", "$")
"""What TeX leaves in text that was not typeset."""


def browser_problems(shown: dict) -> list[str]:
    """What the page fails of the checks in a 1280 px window, by name: text overflowing its
    box (scroll containers aside), a page wider than the window, TeX in the visible text, an
    image not loaded, the conclusion or the headline number off the first screen, a path of
    the source repository (the documentation is linked by address)."""
    problems = [f"overflow: {e}" for e in shown["overflow"]]
    if shown["page_width"] > VIEWPORT[0]:
        problems.append(f"page width {shown['page_width']}")
    problems += [f"tex: {m}" for m in TEX_MARKERS if m in shown["text"]]
    problems += [f"repository path: {m.group(0)}"
                 for m in REPOSITORY_PATHS.finditer(shown["text"])]
    if not shown["images"] or not all(done and width > 0 for _, done, width in shown["images"]):
        problems.append(f"images: {shown['images']}")
    for key in ("conclusion", "headline"):
        if not (shown[key] and 0 <= shown[key][0] < shown[key][1] <= VIEWPORT[1]):
            problems.append(f"{key} off the first screen: {shown[key]}")
    return problems


def check_in_browser(shown: dict, screenshot_path=None) -> None:
    """The page passes :func:`browser_problems`'s checks."""
    where = f" (screenshot {screenshot_path})" if screenshot_path else ""
    assert browser_problems(shown) == [], where


HIDDEN = {
    "display none": "table.claims { display: none; }",
    "visibility hidden": "table.claims { visibility: hidden; }",
    "below the fold": "#claims { margin-top: 2000px; }",
    "covered": "body::after { content: ''; position: fixed; inset: 0; background: #fff; }",
}
"""Ways to hide the claims table, each of which the visibility check must catch."""


def band_share(screenshot: bytes, rect, *, min_height: int = 120) -> float:
    """The share of the claims table's box, as the DOM places it in the viewport, that the
    screenshot paints in the claims band's colour (0 when less than ``min_height`` pixels
    of the box are on screen)."""
    import io

    from PIL import Image

    from stereovar.pages.claims_table import CLAIMS_BAND

    image = np.asarray(Image.open(io.BytesIO(screenshot)).convert("RGB")).astype(int)
    height, width = image.shape[:2]
    left, top, right, bottom = (int(round(v)) for v in rect)
    left, right = max(left, 0), min(right, width)
    top, bottom = max(top, 0), min(bottom, height)
    if bottom - top < min_height or right - left < 1:
        return 0.0
    band = np.array([int(CLAIMS_BAND[i : i + 2], 16) for i in (1, 3, 5)])
    box = image[top:bottom, left:right]
    return float((np.abs(box - band).max(axis=-1) <= 3).mean())


def claims_visibility(headless_chromium, page: Path) -> tuple[float, list[str], object]:
    """Open ``page`` in Chromium: (band share of the claims table in the first viewport,
    the claims its rows name, the load, with ``shown``: what :data:`CLAIMS_PROBE` found)."""
    load = headless_chromium(page, width=VIEWPORT[0], height=VIEWPORT[1], expression=CLAIMS_PROBE)
    shown = json.loads(load.value)
    load.shown = shown
    return band_share(load.screenshot, shown["rect"]), shown["ids"], load


VISIBLE = 0.4
"""The least share of the claims table's box in the band colour for it to count as visible
(the rest is text, rules and verdict badges)."""


@pytest.fixture
def synthetic_page(synthetic):
    """The synthetic results' page with the mitigations, the probe and the generator profiles
    (a path)."""
    root, _, _, _ = synthetic(mitigations=True, probe=True, generators=True)
    return root / layout.results_page()


def test_synthetic_page_loads_in_chromium_with_the_claims_table_visible(
    headless_chromium, synthetic_page, tmp_path
):
    share, ids, load = claims_visibility(headless_chromium, synthetic_page)
    (tmp_path / "first_screen.png").write_bytes(load.screenshot)
    assert load.errors == []
    check_in_browser(load.shown, tmp_path / "first_screen.png")
    assert load.shown["math"] >= 2  # the caption's equations typeset
    assert share >= VISIBLE, share
    assert ids == [str(r["id"]) for r in read_rows(synthetic_page.parent / "tables/claims.csv")]


@pytest.mark.parametrize("how", sorted(HIDDEN))
def test_the_visibility_check_fails_when_the_claims_table_is_hidden(
    headless_chromium, synthetic_page, how
):
    text = synthetic_page.read_text(encoding="utf-8")
    hidden = synthetic_page.with_name("hidden.html")
    hidden.write_text(text.replace("</style>", HIDDEN[how] + "\n</style>", 1), encoding="utf-8")
    share, _, load = claims_visibility(headless_chromium, hidden)
    assert load.errors == []
    assert share < VISIBLE, (how, share)


BROKEN = {
    "overflow": ("</body>", '<p style="width: 8em; white-space: nowrap">a line that cannot wrap '
                 "and runs out of its box</p></body>"),
    "tex": ("</body>", "<p>σ̂²_{R→L}</p></body>"),
    "repository path": ("</body>", "<p>see docs/outputs.md</p></body>"),
    "conclusion off": ('id="conclusion"', 'style="margin-top: 1200px" id="conclusion"'),
    "images": ("</body>", '<img src="missing.png" alt="missing"></body>'),
}
"""Ways to break the page, each of which the browser checks must catch."""


def test_the_browser_checks_fail_on_a_broken_page(headless_chromium, synthetic_page):
    text = synthetic_page.read_text(encoding="utf-8")
    for old, new in BROKEN.values():
        text = text.replace(old, new, 1)
    broken = synthetic_page.with_name("broken.html")
    broken.write_text(text, encoding="utf-8")
    _, _, load = claims_visibility(headless_chromium, broken)
    found = {p.split(":")[0].split(" off")[0] for p in browser_problems(load.shown)}
    assert {"overflow", "tex", "conclusion", "headline", "images", "repository path"} <= found
    assert any("missing.png" in e for e in load.errors)


# ----------------------------------------------------------------------------- the tiny run


@pytest.mark.workflow
def test_tiny_run_writes_its_results_page(tiny_run):
    results = tiny_run / "results"
    page = Page((tiny_run / layout.results_page()).read_text(encoding="utf-8"))
    check_claims(page, read_rows(results / "tables/claims.csv"))
    summary = json.loads((tiny_run / layout.summary_json()).read_text())
    # the calibration's matched nulls make the headline the Monte Carlo-specific rho, which
    # the mitigation table would compute scene by scene from the correlation rows
    nulls = tiny_run / layout.calibration_nulls()
    rows = sorted(results.glob(f"mitsuba/seeds/correlation/*/spp{summary['spp']}.csv"))
    corr = [r for path in rows for r in read_rows(path)]
    assert nulls.is_file() and corr
    check_headline(page, summary, expected_matched(corr, read_rows(nulls)))
    check_links(page, results)
    figures = sorted(results.rglob("figures/*.png"))
    assert figures and len(page.images) == len(figures)
    embedded = {base64.b64decode(i["src"].split(",", 1)[1]) for i in page.images}
    assert {f.read_bytes() for f in figures} == embedded
    tables = {p.resolve() for p in results.rglob("tables/*")
              if p.suffix[1:] in layout.TABLE_FORMATS}
    linked = {(results / h).resolve() for h in page.links if not h.startswith("#")}
    assert tables and tables <= linked
    assert (tiny_run / "logs/results_page.log").is_file()


@pytest.mark.workflow
def test_tiny_run_results_page_in_chromium(headless_chromium, tiny_run, tmp_path,
                                           interval_problems):
    share, ids, load = claims_visibility(headless_chromium, tiny_run / layout.results_page())
    (tmp_path / "index.png").write_bytes(load.screenshot)
    assert load.errors == []
    check_in_browser(load.shown, tmp_path / "index.png")
    assert share >= VISIBLE, f"claims table not visible ({share:.2f}): {tmp_path / 'index.png'}"
    claims = read_rows(tiny_run / layout.claims_tables()[0])
    assert ids == [str(r["id"]) for r in claims]
    # one interval per quantity, none of a correlation outside [-1, 1]; where it came from
    import stereovar

    summary = json.loads((tiny_run / layout.summary_json()).read_text())
    quantities = [(r["mean_rho"], *(r[k] for k in interval_keys(r["method"])))
                  for r in summary["statistics"]
                  if None not in (r["mean_rho"], *(r[k] for k in interval_keys(r["method"])))]
    assert quantities
    text = load.shown["text"]
    assert interval_problems(text, quantities) == []
    origin = summary["provenance"]
    assert f"stereovar {stereovar.__version__}" in text
    assert origin["inputs_sha256"][:12] in text and origin["config_sha256"][:12] in text


def page_job_inputs(root: Path) -> str:
    """The input line of the results_page job in a dry run of ``results/index.html``."""
    from .test_workflow import snakemake

    out = snakemake(root, "-n", "-p", layout.results_page()).stdout
    block = out.split("rule results_page:", 1)[1]
    return next(line for line in block.splitlines() if line.strip().startswith("input:"))


@pytest.mark.workflow
def test_the_page_takes_the_mitigations_and_the_probe_once_they_exist(tmp_path):
    from .test_workflow import TINY, copy_workflow

    # 4 renders per view: the probe's jobs are planned once its outputs exist, and it needs 4
    render = {**TINY["render"], "n_seeds": 4, "seeds_per_job": 4}
    root = copy_workflow(
        tmp_path / "wf", {**TINY, "render": render, "mitigations": {"names": ["equalise"]}}
    )
    inputs = page_job_inputs(root)
    assert layout.mitigation_tables()[0] in inputs and layout.mitigation_figure() in inputs
    assert layout.probe_verdict() not in inputs and layout.probe_figure() not in inputs
    # the probe's outputs, as `snakemake probe` leaves them
    for path in (
        *layout.probe_tables(),
        *layout.probe_training_tables(),
        layout.probe_figure(),
        layout.probe_verdict(),
    ):
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text("{}")
    inputs = page_job_inputs(root)
    assert layout.probe_verdict() in inputs and layout.probe_figure() in inputs
    # the generator table and figure, as `snakemake generators` leaves them
    assert layout.generator_figure() not in inputs
    for path in (*layout.generator_tables(), layout.generator_figure()):
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text("{}")
    inputs = page_job_inputs(root)
    assert layout.generator_tables()[0] in inputs and layout.generator_figure() in inputs
