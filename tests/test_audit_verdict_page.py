"""The verdict page as a reader sees it, and summary.json as a script reads it: built by the
verdict job from a synthetic audit's stores (import, Eq. 1, Eq. 2 and the correlation rows,
no workflow), checked in the HTML, the Markdown and headless Chromium at 1280 px."""

import json
import os
import re
from html import unescape
from pathlib import Path

import pytest

from stereovar import layout
from stereovar.audit.importer import import_audit, import_record
from stereovar.audit.page import caption
from stereovar.audit.strongest import TILE_COLUMNS
from stereovar.audit.summary_schema import (
    SCHEMA_PATH,
    SUMMARY_SCHEMA_VERSION,
    summary_schema,
    validate_summary,
)
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.jobs.audit import verdict_job
from stereovar.jobs.common import save_figure

NAME = "synthetic"
SOURCE = layout.audit_source(NAME)
FRAMES = ("f00", "f01")
TEX = re.compile(r"\\[A-Za-z]+|[_^]\{|\$|:math:")
"""What raw TeX or reStructuredText math leaks as: a backslash command, ``_{``/``^{``, a
dollar sign or a ``:math:`` role."""


def render_stores(frame):
    return {
        view: [f"results/audit/{NAME}/renders/{frame}/{view}/spp0/seeds0-7.zarr"]
        for view in ("left", "right")
    }


def placeholder(path, size=(480, 160)):
    """A small PNG standing in for a figure another module draws."""
    import numpy as np
    from PIL import Image

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    ramp = np.linspace(60, 200, size[0], dtype=np.uint8)[None, :, None]
    Image.fromarray(np.broadcast_to(ramp, (size[1], size[0], 3)).copy()).save(path)


@pytest.fixture(scope="module")
def audited(tmp_path_factory):
    """A two-frame synthetic audit with its verdict page (a dict of paths and the summary)."""
    from stereovar.figures.uncertainty import statistics_dot_figure
    from stereovar.io.tables import read_rows
    from stereovar.jobs.correlation import correlation_job, warp_job
    from stereovar.jobs.variance import variance_job

    root = tmp_path_factory.mktemp("audit")
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(root)
        settings, _ = write_synthetic_audit(
            root / "d", name=NAME, n_frames=2, width=160, height=96, n_seeds=8
        )
        import_audit(settings)
        paths = {k: [] for k in ("variance", "warped", "gt", "corr", "thumb", "teaser")}
        analysis = {"bootstrap": {"reps": 40, "tile": 16}}
        for frame in FRAMES:
            stores = render_stores(frame)
            gt = layout.ground_truth_store(SOURCE, frame)
            variance = layout.variance_store(SOURCE, "seeds", frame, 0)
            warped = layout.warped_store(SOURCE, "seeds", frame, 0)
            corr = layout.correlation_rows(SOURCE, "seeds", frame, 0)
            variance_job(stores["left"], stores["right"], variance)
            warp_job(variance, gt, warped)
            correlation_job(variance, warped, gt, corr, analysis=analysis)
            thumb = layout.audit_thumbnail(NAME, frame)
            teaser = layout.audit_teaser(NAME, frame)
            for figure in (thumb, teaser):  # the figures' own tests draw them
                placeholder(figure)
            for key, p in zip(paths, (variance, warped, gt, corr, thumb, teaser), strict=True):
                paths[key].append(p)
        dots = layout.run_figure(SOURCE, "seeds", "statistics_dots")
        rows = [r for p in paths["corr"] for r in read_rows(p)]
        save_figure(statistics_dot_figure(rows, title="statistics"), dots)
        base = Path(layout.audit_verdict(NAME, "md")).parent
        outputs = {
            "md": base / "verdict.md",
            "html": base / "verdict.html",
            "summary": base / "summary.json",
            "strongest": Path(layout.audit_strongest(NAME)),
        }
        summary = verdict_job(
            paths["corr"], [], paths["teaser"], outputs, name=NAME,
            found="2 frames × 2 views × 8 seeds", thumbnails=paths["thumb"],
            imports=[import_record(NAME, f) for f in FRAMES], statistics_figure=dots,
            variance=paths["variance"], warped=paths["warped"], ground_truth=paths["gt"],
        )
    return {"root": root, "written": summary, **{k: root / v for k, v in outputs.items()}}


# -- summary.json --------------------------------------------------------------------------


def test_the_written_summary_validates_against_its_schema(audited):
    written = json.loads(audited["summary"].read_text())
    assert written["schema_version"] == SUMMARY_SCHEMA_VERSION
    validate_summary(written)
    assert written["light"] in ("red", "amber", "green")
    assert written["summary"][0].startswith(written["light"].upper() + ": ")
    tiles = written["strongest"]["tiles"]
    assert tiles and set(tiles[0]) == set(TILE_COLUMNS)
    assert [f["frame"] for f in written["strongest"]["frames"]] != []


def schema_keys(schema, node, prefix=""):
    """Every key path an object of ``node`` documents (``a``, ``a/b``, ``a/[]/c``)."""
    if "$ref" in node:
        node = schema["$defs"][node["$ref"].rsplit("/", 1)[1]]
    out = set()
    for key, sub in node.get("properties", {}).items():
        assert sub.get("description"), f"{prefix}{key} has no description"
        out.add(prefix + key)
        out |= schema_keys(schema, sub, f"{prefix}{key}/")
        if "items" in sub:
            out |= schema_keys(schema, sub["items"], f"{prefix}{key}/[]/")
    return out


def written_keys(value, prefix=""):
    """Every key path of a JSON value, as :func:`schema_keys` writes them."""
    out = set()
    if isinstance(value, dict):
        for key, sub in value.items():
            out.add(prefix + key)
            out |= written_keys(sub, f"{prefix}{key}/")
    elif isinstance(value, list):
        for item in value:
            out |= written_keys(item, f"{prefix}[]/")
    return out


def test_the_schema_documents_every_key_written(audited):
    written = json.loads(audited["summary"].read_text())
    documented = schema_keys(summary_schema(), summary_schema())
    # the probe's verdict is its own document, kept as the probe job writes it
    undocumented = {k for k in written_keys(written) - documented if not k.startswith("probe/")}
    assert not undocumented
    assert set(summary_schema()["required"]) == set(written)


def test_a_summary_that_breaks_the_schema_is_refused(audited):
    written = json.loads(audited["summary"].read_text())
    for broken in ({**written, "light": "purple"}, {**written, "schema_version": "2.0"},
                   {k: v for k, v in written.items() if k != "summary"},
                   {**written, "extra": 1}):
        with pytest.raises(ValueError, match="breaks its schema"):
            validate_summary(broken)


def test_the_schema_ships_in_the_package():
    import stereovar

    assert SCHEMA_PATH.parent.parent == Path(stereovar.__file__).parent
    assert json.loads(SCHEMA_PATH.read_text())["$schema"].endswith("2020-12/schema")


# -- the page --------------------------------------------------------------------------------


def test_the_light_carries_its_word(audited):
    html = audited["html"].read_text()
    light = audited["written"]["light"]
    word = re.search(r'<div class="lamp"[^>]*>([A-Z]+)</div>', html)
    assert word and word.group(1) == light.upper()
    assert f"**{light.upper()}: " in audited["md"].read_text()


def test_captions_describe_the_figures(audited):
    html = audited["html"].read_text()
    captions = [unescape(re.sub("<[^>]+>", "", c))
                for c in re.findall(r"<figcaption>(.*?)</figcaption>", html, re.S)]
    images = re.findall(r'<img src="([^"]+)"', html)
    assert len(captions) == len(images) == 2 + 2 + 1 + 1  # thumbnails, teasers, dots, tiles
    for c in captions:
        assert not re.fullmatch(r"\w+", c) and len(c.split()) >= 12, c
        assert not TEX.search(c), c
    assert sum(c.startswith("Frame f00") for c in captions) == 2
    assert any(c.startswith("Every statistic against its controls") for c in captions)
    md = audited["md"].read_text()
    assert md.count("![") == len(images)
    assert "*" + "**Frame f00.** The left view's first render" in md
    assert "statistics_dots.png" in md and "strongest.png" in md


def test_the_markdown_page_reads_as_plain_text(audited):
    """verdict.md reads in a text editor as it renders: math as characters, code spans in
    single backticks, no TeX or reStructuredText left; the opening says what to do first."""
    md = audited["md"].read_text()
    assert not TEX.search(md.replace("\\]", "")), TEX.search(md)
    assert "``" not in md and ":math:" not in md
    assert "σ²" in md and "ρ" in md
    opening = md.split("## What was imported")[0]
    assert "**What to do.**" in opening and "### What these numbers mean" in opening
    assert opening.index("**What to do.**") < opening.index("How sure:")


def test_the_rules_are_a_short_list_with_math(audited):
    html = audited["html"].read_text()
    rules = re.search(r'<ul class="rules">(.*?)</ul>', html, re.S).group(1)
    items = re.findall(r"<li>(.*?)</li>", rules, re.S)
    assert 4 <= len(items) <= 7
    assert all(len(re.sub("<[^>]+>", "", i).split()) <= 45 for i in items)
    assert "<math" in rules
    assert "ln sigma^2" not in html.split('<ul class="rules">')[1].split("</ul>")[0]


def test_the_strongest_section_quotes_intervals_and_controls(audited):
    html = unescape(audited["html"].read_text())
    section = html.split('id="strongest"')[1]
    tiles = audited["written"]["strongest"]["tiles"]
    top = tiles[0]
    assert f"{top['rho']:.3f} [{top['low']:.3f}, {top['high']:.3f}]" in section
    assert f"{top['null']:.3f} (critical {top['null_high']:.3f})" in section
    assert audited["strongest"].is_file()


# -- in Chromium -------------------------------------------------------------------------

PROBE = """JSON.stringify((() => {
  const lamp = document.querySelector('.lamp').getBoundingClientRect();
  const over = [];
  for (const el of document.querySelectorAll('body *')) {
    if (el.closest('table') && el.tagName !== 'TABLE') continue;
    if (el.scrollWidth > el.clientWidth + 1 && getComputedStyle(el).overflowX !== 'visible'
        || el.getBoundingClientRect().right > document.documentElement.clientWidth + 1)
      over.push(el.tagName + '.' + el.className + ': ' + (el.textContent || '').slice(0, 60));
  }
  return {
    lamp: [lamp.top, lamp.bottom, lamp.left, lamp.right],
    word: document.querySelector('.lamp').textContent,
    viewport: [innerWidth, innerHeight],
    pageWidth: document.documentElement.scrollWidth,
    images: [...document.images].map(i => [i.getAttribute('src'), i.complete && i.naturalWidth]),
    text: document.body.innerText,
    over: over,
  };
})())"""


def test_the_page_in_chromium_at_1280_px(headless_chromium, audited, tmp_path):
    load = headless_chromium(audited["html"], width=1280, height=800, expression=PROBE)
    (tmp_path / "verdict.png").write_bytes(load.screenshot)
    if os.environ.get("STEREOVAR_SHOTS"):  # the whole page, to look at
        whole = headless_chromium(audited["html"], width=1280, height=6000)
        Path(os.environ["STEREOVAR_SHOTS"]).mkdir(parents=True, exist_ok=True)
        (Path(os.environ["STEREOVAR_SHOTS"]) / "verdict_first.png").write_bytes(load.screenshot)
        (Path(os.environ["STEREOVAR_SHOTS"]) / "verdict_whole.png").write_bytes(whole.screenshot)
    shown = json.loads(load.value)
    assert load.errors == []
    assert shown["word"] == audited["written"]["light"].upper()
    top, bottom, left, right = shown["lamp"]
    assert 0 <= top and bottom <= shown["viewport"][1] and right <= 1280  # on the first screen
    assert shown["pageWidth"] <= 1280, shown["over"]
    assert shown["over"] == []
    assert shown["images"] and all(w and w > 0 for _, w in shown["images"]), shown["images"]
    assert not TEX.search(shown["text"]), TEX.search(shown["text"])
    for kind in ("thumbnail", "statistics"):
        assert caption(kind, frame="f00").split("**")[1].rstrip(".") in shown["text"]


def test_the_page_is_one_file_that_says_where_it_came_from(headless_chromium, audited,
                                                           interval_problems):
    """Every image embedded, so the one file can be shared; the version, the date and the
    inputs' and config's hashes shown; each quantity with its one interval, none of a
    correlation outside [-1, 1]."""
    import stereovar
    from stereovar.provenance import inputs_digest

    load = headless_chromium(audited["html"], width=1280, height=800, expression=PROBE)
    shown = json.loads(load.value)
    assert shown["images"] and all(src.startswith("data:image/png;base64,")
                                   for src, _ in shown["images"])
    written = json.loads(audited["summary"].read_text())
    origin = written["provenance"]
    records = [json.loads((audited["root"] / import_record(NAME, f)).read_text())
               for f in FRAMES]
    hashes = {p: e["sha256"] for r in records for p, e in r["files"].items()}
    assert origin["inputs_sha256"] == inputs_digest(hashes) and origin["n_inputs"] == len(hashes)
    assert f"stereovar {stereovar.__version__}" in shown["text"]
    assert origin["inputs_sha256"][:12] in shown["text"]
    assert origin["created"][:10] in shown["text"]
    rows = [(r["value"], r["low"], r["high"]) for r in written["rows"]
            if None not in (r["value"], r["low"], r["high"])]
    assert interval_problems(shown["text"], rows) == []
    assert interval_problems("rho 0.967 [0.724, 1.210]") != []  # the check can fail


def test_the_summary_gives_the_number_a_script_reads(audited):
    written = json.loads(audited["summary"].read_text())
    top = written["mc_specific_rho"]
    row = next((r for r in written["rows"]
                if r["quantity"] == "Monte Carlo-specific rho" and r["region"] == "all"),
               {"value": None, "low": None, "high": None})  # no matched null: no number
    assert (top["value"], top["low"], top["high"]) == (row["value"], row["low"], row["high"])
    assert top["light"] == written["light"]


def test_a_summary_of_another_major_version_is_refused_in_one_line(audited, tmp_path):
    from stereovar.audit.summary_schema import read_summary
    from stereovar.errors import AuditError

    written = json.loads(audited["summary"].read_text())
    path = tmp_path / "summary.json"
    path.write_text(json.dumps({**written, "schema_version": "2.0"}))
    with pytest.raises(AuditError, match=r"schema version 2\.0; this stereovar .* reads 1\.x"):
        read_summary(path)
    path.write_text(json.dumps({**written, "schema_version": "1.0"}))
    assert read_summary(path)["light"] == written["light"]  # an older 1.x reads the same


def test_the_docs_page_describes_every_key_of_the_schema():
    docs = (Path(__file__).parents[1] / "docs" / "summary_json.md").read_text()
    schema = summary_schema()
    keys = set(schema["properties"])
    keys |= set(schema["$defs"]["frame_rank"]["properties"])
    keys |= set(schema["$defs"]["tile"]["properties"])
    missing = sorted(k for k in keys if f"`{k}`" not in docs)
    assert not missing
    assert f'"{SUMMARY_SCHEMA_VERSION}"' in docs
    guide = (Path(__file__).parents[1] / "docs" / "guide.md").read_text()
    assert "\nsummary_json\n" in guide


def test_the_declared_strongest_figure_exists_when_nothing_can_be_ranked(tmp_path):
    outputs = {k: tmp_path / f"verdict.{k}" for k in ("md", "html")}
    outputs.update(summary=tmp_path / "summary.json", strongest=tmp_path / "strongest.png")
    summary = verdict_job([], [], [], outputs, name="empty", found="0 frames")
    assert summary["strongest"] is None and outputs["strongest"].stat().st_size > 0
    validate_summary(json.loads(outputs["summary"].read_text()))
    assert 'id="strongest"' not in outputs["html"].read_text()
