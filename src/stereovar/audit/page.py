"""The audit's verdict page: a decision first, then the import's facts, then the details.

:func:`page_sections` puts what :mod:`stereovar.audit.verdict` computed in reading order:

1. banners (an inconclusive sign check the audit went on with, ``audit.sign_check: warn``,
   a sign check won with a high error, and a disparity that seems offset:
   :mod:`stereovar.audit.offset`);
2. the decision: a traffic light and sentences (:func:`stereovar.audit.decision.decision`);
3. the import's facts: frames, seeds and files, each frame's sign check and valid pixels,
   and every warning and flag as a row of its own;
4. one thumbnail per frame (a render and the disparity), so the reader sees that the right
   files were read;
5. the details: the verdict paragraph, the seeding finding, the table with intervals, how
   the verdict reads them (a short list) and the statistics against their controls;
6. where the cue is strongest (:mod:`stereovar.audit.strongest`): the frames ranked, their
   top tiles each beside its null, and their figure;
7. the mitigations, the learned probe and the teasers.

:func:`to_markdown_page` and :func:`to_html_page` write the same sections; the HTML page is
self-contained (its own stylesheet, images by relative path), the template
``verdict.html.j2`` of :mod:`stereovar.pages.templates`. Captions and the rules are
reStructuredText inline markup (:data:`CAPTIONS`, :data:`~stereovar.audit.verdict.RULE_ITEMS`),
their math MathML on the HTML page and ``$...$`` in the Markdown. Every text the sections
carry (file paths, audit and frame names, warnings) is escaped on both pages: HTML-escaped
on the HTML page, and on the Markdown page made inert (:func:`markdown_text`), so a folder
named ``d<img src=x onerror=alert(1)>`` is shown, not run.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from urllib.parse import quote

from ..io.tables import to_markdown
from ..provenance import provenance_line
from .decision import LIGHTS
from .flags import FLAG_LABELS
from .importer import WARNING_KINDS
from .verdict import RULE_ITEMS, VERDICT_COLUMNS

FACT_COLUMNS = [
    "frame",
    "seeds",
    "files",
    "valid_px",
    "invalid_disparity_px",
    "outside_px",
    "nonfinite_render_px",
    "sign_check",
    "clipped",
    "quantised",
]
"""Columns of the import-facts table (one row per frame): ``clipped`` is the share of a
view's valid pixels at a PNG's full scale in some render, ``quantised`` the share whose
8-bit renders are all identical (8-bit PNG) or whose spread across the seeds is below
:data:`~stereovar.audit.importer.HALF_STEPS` half-float steps (half-float renders, marked
``half float``; ``n/a`` for 16-bit PNG and 32-bit float formats)."""

BANNER_KINDS = ("sign_check", "sign_check_error", "disparity_offset")
"""Import warnings the page opens with, above the decision: the sign check the disparity
rests on was inconclusive, or won with a high error, or the disparity seems offset (the
warp matches better shifted by a pixel or more: :mod:`stereovar.audit.offset`)."""

FACT_LABELS = {
    "valid_px": "valid pixels",
    "invalid_disparity_px": "invalid disparity (px)",
    "outside_px": "warped outside the image (px)",
    "nonfinite_render_px": "non-finite render pixels",
    "sign_check": "sign check: median warp error, declared / opposite convention",
    "clipped": "clipped (share of pixels)",
    "quantised": "quantised (share of pixels)",
}
"""Headers of the import-facts table, with units (the columns keep their names in the
Markdown page's table and in scripts)."""

FLAG_COLUMNS = ["flag", "frame", "what"]
"""Columns of the flags table (one row per warning or flag)."""

CAPTIONS = {
    "thumbnail": (
        "**Frame {frame}.** The left view's first render and the imported disparity (with the "
        "glass region where a material mask was given): the files the audit read."
    ),
    "teaser": (
        "**Frame {frame}: the noise-level fields.** :math:`\\sigma^2_L` and "
        ":math:`\\sigma^2_R`, each pixel's variance over the imported renders' seeds, the "
        "right field moved into the left view by the given disparity, "
        ":math:`\\hat\\sigma^2_{R \\to L}`, and their joint histogram over the pixels both "
        "views see, with Pearson's :math:`\\rho`."
    ),
    "statistics": (
        "**Every statistic against its controls.** One row per statistic (above the dashed "
        "line) and control (below it), one colour per frame: the dot is :math:`\\rho`, the "
        "thin capped bar its spatial block-bootstrap 95% interval, the short thick bar the "
        "Fisher-z interval, which assumes independent pixels. The controls are the null warps "
        "(wrong alignments), the intensity-controlled and relative statistics, and a simulated "
        "camera on the same clean images: a statistic means something only where it stands "
        "apart from them."
    ),
    "strongest": (
        "**Where the cue is strongest.** One row per top frame: the frame with its top "
        "{tile}×{tile} px tiles outlined and numbered by rank (solid yellow: above the null at "
        "its rank; dashed white: not), the local intensity-controlled :math:`\\rho` of every "
        "tile, and the top tile's two residual fields, :math:`e_L` and "
        ":math:`e_{R \\to L}`, side by side: where the views share a pattern, it shows in both."
    ),
    "mitigations": (
        "**Mitigation trade-off.** One point per mitigation: the Monte Carlo-specific "
        ":math:`\\rho` of what it ships (the intensity-controlled :math:`\\rho` minus its "
        "matched null) against its image quality (PSNR, dB), with 95% intervals, and the "
        "calibration's margin as a grey band around 0: a mitigation removes the cue where its "
        "whole interval lies inside its band; the cue remains where the interval lies above "
        "the red dotted line at 0.05. The point to look for sits inside its band, on the "
        "right."
    ),
    "probe": (
        "**Learned probe: accuracy per test input.** Winner-take-all accuracy of each training "
        "condition's networks on each test input, per region, with 95% intervals over test "
        "tiles and training seeds."
    ),
}
"""Each figure's caption (reStructuredText inline markup, ``:math:`` roles): what it shows,
by kind; ``{frame}`` and ``{tile}`` are filled in."""


_RST_ACTIVE = re.compile(r"([\\`*_|<>\[\]])")


def caption(kind: str, **fields) -> str:
    """The caption of a figure of one :data:`CAPTIONS` kind, its ``{field}`` placeholders
    filled in (braces of the math are left alone).

    Examples
    --------
    >>> caption("thumbnail", frame="f00").startswith("**Frame f00.** The left view's")
    True
    """
    text = CAPTIONS[kind]
    for key, value in fields.items():
        text = text.replace("{" + key + "}", _RST_ACTIVE.sub(r"\\\1", str(value)))
    return text


_MATH_ROLE = re.compile(r":math:`(.+?)`", re.S)
_LITERAL = re.compile(r"``(.+?)``", re.S)
_TEX_NAMES = {
    "rho": "ρ", "sigma": "σ", "mu": "μ", "epsilon": "ε", "delta": "δ", "Delta": "Δ",
    "Omega": "Ω", "tau": "τ", "to": "→", "pm": "±", "times": "×", "cdot": "·", "ln": "ln ",
    "le": "≤", "ge": "≥", "approx": "≈",
}
"""TeX commands of the captions and rules, as the characters a plain text shows."""
_SUPERSCRIPTS = str.maketrans("0123456789+-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻")


def math_text(tex: str) -> str:
    r"""Inline TeX of the captions as plain text: Greek letters and arrows as characters,
    ``^2`` as ², ``\hat x`` with a combining hat, subscripts after ``_`` without braces.

    Examples
    --------
    >>> math_text("\\hat\\sigma^2_{R \\to L}"), math_text("C_\\sigma"), math_text("\\ln\\mu")
    ('σ̂²_R→L', 'C_σ', 'ln μ')
    """
    text = re.sub(r"\\hat\s*\\?([A-Za-z]+)",
                  lambda m: _TEX_NAMES.get(m.group(1), m.group(1)) + "\u0302", tex)
    text = re.sub(r"\\([A-Za-z]+)", lambda m: _TEX_NAMES.get(m.group(1), m.group(1)), text)
    text = re.sub(r"  +", " ", text)
    text = re.sub(r"\^\{?([0-9+-]+)\}?", lambda m: m.group(1).translate(_SUPERSCRIPTS), text)
    text = re.sub(r"_\{([^}]*)\}", lambda m: "_" + m.group(1).replace(" ", ""), text)
    return text.replace("{", "").replace("}", "").strip()


def caption_markdown(text: str) -> str:
    r"""A caption's inline markup as plain Markdown, readable in a text editor as rendered:
    ``:math:`x``` as text (:func:`math_text`), ````x```` as a code span, ``**bold**`` kept,
    on one line.

    Examples
    --------
    >>> caption_markdown("**A.** :math:`\\rho` < 1 in ``x_R``")
    '**A.** ρ &lt; 1 in `x_R`'
    """
    text = _MATH_ROLE.sub(lambda m: math_text(m.group(1)), text)
    return _LITERAL.sub(lambda m: f"`{m.group(1)}`", markdown_text(text))


_MARKDOWN_ACTIVE = re.compile(r"[&<>]|\](?=\()|[\r\n]+")
_MARKDOWN_INERT = {"&": "&amp;", "<": "&lt;", ">": "&gt;", "]": "]\\"}


def markdown_text(text) -> str:
    r"""``text`` made inert in a Markdown page, reading as it did once rendered.

    ``&``, ``<`` and ``>`` become HTML entities (no raw HTML, no autolink), a ``]`` before
    ``(`` is escaped (no inline link or image) and line breaks become spaces (no new
    block); anything else is left as it is, so a path, ``x_R = x_L - d`` or an interval
    reads the same in the file. Text that starts a line goes through :func:`markdown_line`.

    Parameters
    ----------
    text : object
        The text (``str()`` of it).

    Returns
    -------
    str
        The text for a Markdown page, on one line.

    Examples
    --------
    >>> markdown_text("d<img src=x onerror=alert(1)>/seg.png")
    'd&lt;img src=x onerror=alert(1)&gt;/seg.png'
    >>> print(markdown_text("[click](https://example.com) [0.1, 0.2]"))
    [click]\(https://example.com) [0.1, 0.2]
    """
    return _MARKDOWN_ACTIVE.sub(lambda m: _MARKDOWN_INERT.get(m.group(), " "), str(text))


_BLOCK_MARKER = re.compile(r"[#+*=_`~\[|-]|\d{1,9}(?=[.)])")
"""What opens a Markdown block at the start of a line: a heading (``#``), a list item or a
thematic break (``-``, ``+``, ``*``, ``_``, ``1.``, ``1)``), a setext underline (``=``), a
code fence (a backtick, ``~``), a link reference definition (``[x]: url``) or a table
row (``|``); ``>`` and ``<`` are entities already (:func:`markdown_text`)."""


def markdown_line(text) -> str:
    r"""``text`` made inert (:func:`markdown_text`) where it starts a line of its own: leading
    blanks dropped (four would open a code block) and a leading block marker escaped, so the
    line is a plain paragraph (or list item's text) reading as ``text`` once rendered.

    Parameters
    ----------
    text : object
        The text (``str()`` of it).

    Returns
    -------
    str
        One line of Markdown.

    Examples
    --------
    >>> print(markdown_line("[x]: https://example.com"))
    \[x]: https://example.com
    >>> print(markdown_line("# 1 frame"))
    \# 1 frame
    >>> print(markdown_line("1. frame"))
    1\. frame
    """
    line = markdown_text(text).lstrip()
    marker = _BLOCK_MARKER.match(line)
    if marker is None:
        return line
    at = marker.end() if marker.group()[0].isdigit() else 0  # 1. -> 1\. ; # -> \#
    return line[:at] + "\\" + line[at:]


_ALT_ACTIVE = re.compile(r"[&<>\[\]\\]|[\r\n]+")
_ALT_INERT = {"&": "&amp;", "<": "&lt;", ">": "&gt;", "[": "\\[", "]": "\\]", "\\": "\\\\"}


def _markdown_alt(text) -> str:
    """``text`` as the alt text of a Markdown image: :func:`markdown_text`'s entities, and
    every ``[``, ``]`` and backslash escaped, so no bracket ends the alt text early."""
    return _ALT_ACTIVE.sub(lambda m: _ALT_INERT.get(m.group(), " "), str(text))


def _markdown_rows(rows: list[dict]) -> list[dict]:
    """Table rows with every text cell through :func:`markdown_text`."""
    return [{k: markdown_text(v) if isinstance(v, str) else v for k, v in r.items()} for r in rows]


def _markdown_image(path: str) -> str:
    """A Markdown image of a relative path: its alt text inert, its address URL-quoted."""
    return f"![{_markdown_alt(Path(path).stem)}]({quote(path, safe='/')})"


def _sign_fact(sign: dict) -> str:
    if not sign:
        return ""
    text = (
        f"{100 * sign['error']:.1f}% declared / {100 * sign['opposite_error']:.1f}% opposite"
    )
    text += "" if sign.get("conclusive", True) else " (inconclusive)"
    return text + (" (error high)" if sign.get("high_error") else "")


def _offset_fact(offset: dict) -> str:
    """The offset check's estimate, where it fired (:mod:`stereovar.audit.offset`)."""
    if not offset.get("fires"):
        return ""
    if offset.get("varies"):
        return " (disparity offset varies)"
    return f" (disparity offset about {offset['offset']:+.1f} px)"


def import_facts(records: list[dict]) -> list[dict]:
    """One :data:`FACT_COLUMNS` row per frame from the frames' import records
    (``found``: :meth:`stereovar.audit.importer.FrameReport.facts`)."""
    rows = []
    for record in records:
        found = record.get("found") or {}
        clipped = found.get("clipped") or {}
        quantised = [f"{v} {100 * f:.2f}%" for v, f in (found.get("floored") or {}).items()]
        quantised += [
            f"{v} {100 * f:.2f}% (half float)" for v, f in (found.get("half") or {}).items()
        ]
        rows.append(
            {
                "frame": record.get("frame", ""),
                "seeds": found.get("n_seeds", math.nan),
                "files": len(record.get("files") or {}),
                "valid_px": found.get("valid", math.nan),
                "invalid_disparity_px": found.get("invalid_disparity", math.nan),
                "outside_px": found.get("outside", math.nan),
                "nonfinite_render_px": sum((found.get("nonfinite_pixels") or {}).values()),
                "sign_check": _sign_fact(found.get("sign") or {})
                + _offset_fact(found.get("offset") or {}),
                "clipped": ", ".join(f"{v} {100 * f:.2f}%" for v, f in clipped.items()) or "n/a",
                "quantised": ", ".join(quantised) or "n/a",
            }
        )
    return rows


def import_flags(records: list[dict]) -> list[dict]:
    """The import's warnings of every frame, each once (a warning of the whole audit, such
    as the PNG transfer, is repeated in every frame's record)."""
    seen, out = set(), []
    for record in records:
        for flag in (record.get("found") or {}).get("warnings", []):
            if flag["text"] not in seen:
                seen.add(flag["text"])
                out.append(flag)
    return out


def _label(kind: str) -> str:
    return WARNING_KINDS.get(kind) or FLAG_LABELS.get(kind) or kind


def flag_rows(flags: list[dict]) -> list[dict]:
    """:data:`FLAG_COLUMNS` rows of the flags."""
    return [
        {"flag": _label(f["kind"]), "frame": f.get("frame") or "all", "what": f["text"]}
        for f in flags
    ]


def _captioned(items, kind: str) -> list[tuple[str, str]]:
    """``(path, caption)`` pairs: a pair is kept, a bare path gets the :data:`CAPTIONS` caption
    of ``kind`` with the frame read from its name (``thumbnail_f00.png``: ``f00``)."""
    out = []
    for item in items:
        if isinstance(item, str):
            stem = Path(item).stem
            frame = stem.split("_", 1)[1] if "_" in stem else stem
            item = (item, caption(kind, frame=frame, tile=""))
        out.append(tuple(item))
    return out


STRONGEST_FRAME_COLUMNS = ["rank", "frame", "ranked by", "value (95% interval)",
                           "intensity-controlled rho", "matched null"]
"""Columns of the page's frame ranking."""

STRONGEST_TILE_COLUMNS = ["frame", "rank", "tile (x, y)", "pixels", "local rho (95% interval)",
                          "null at its rank", "stands out"]
"""Columns of the page's tile table."""


def _iv(value, low, high) -> str:
    if not (math.isfinite(value)):
        return "n/a"
    if not (math.isfinite(low) and math.isfinite(high)):
        return f"{value:.3f}"
    return f"{value:.3f} [{low:.3f}, {high:.3f}]"


def strongest_rows(ranking: list[dict], tiles: list[dict]) -> tuple[list[dict], list[dict]]:
    """The page's rows of :mod:`stereovar.audit.strongest`: each number with its interval,
    and beside it its control (the frame's matched null; the tile's null at its rank, with
    the value it must exceed, the Monte Carlo test's critical value at 5%)."""
    frames = [
        {
            "rank": r["rank"],
            "frame": r["frame"],
            "ranked by": "intensity-controlled rho minus matched null"
            if r["statistic"] == "difference"
            else "intensity-controlled rho (no matched null)",
            "value (95% interval)": _iv(r["value"], r["low"], r["high"]),
            "intensity-controlled rho": _iv(r["partial"], math.nan, math.nan),
            "matched null": _iv(r["null"], math.nan, math.nan),
        }
        for r in ranking
    ]
    rows = [
        {
            "frame": t["frame"],
            "rank": t["rank"],
            "tile (x, y)": f"{t['x0']}-{t['x1'] - 1}, {t['y0']}-{t['y1'] - 1}",
            "pixels": t["n_pixels"],
            "local rho (95% interval)": _iv(t["rho"], t["low"], t["high"]),
            "null at its rank": f"{t['null']:.3f} (critical {t['null_high']:.3f})"
            if math.isfinite(t["null_high"])
            else "n/a",
            "stands out": "yes" if t["stands_out"] else "no",
        }
        for t in tiles
    ]
    return frames, rows


def page_sections(
    *,
    name: str,
    found: str,
    decision: dict,
    result: dict,
    seeding: dict,
    records: list[dict],
    flags: list[dict],
    table: list[dict],
    caption: str,
    mitigations: list[str],
    thumbnails: list,
    figures: list,
    probe: str = "",
    statistics: tuple | None = None,
    strongest: dict | None = None,
    rules=RULE_ITEMS,
    meaning=(),
    provenance: dict | None = None,
) -> dict:
    """Everything the page shows, in reading order (see the module docstring).

    ``thumbnails`` and ``figures`` are ``(path, caption)`` pairs (a bare path: a thumbnail's
    or a teaser's caption, :data:`CAPTIONS`), paths relative to the page; ``probe`` is the
    learned probe's verdict paragraph (``audit.probe: true``); ``statistics`` the
    statistics-against-controls figure as a pair; ``strongest``: ``text``, ``ranking`` and
    ``tiles`` (:mod:`stereovar.audit.strongest`) and its figure as a pair or None;
    ``rules``: how the verdict reads its numbers, one item each (inline markup);
    ``meaning``: the "What these numbers mean" box, ``(term, text)`` pairs
    (:func:`stereovar.audit.plain.meaning_items`); ``provenance``: the stereovar version, the
    date and the hashes of the inputs and config (:func:`stereovar.provenance.provenance`).
    """
    banners = [f["text"] for f in flags if f["kind"] in BANNER_KINDS]
    if strongest:
        frames, tiles = strongest_rows(strongest["ranking"], strongest["tiles"])
        strongest = {**strongest, "frame_rows": frames, "tile_rows": tiles}
    return {
        "title": f"Audit {name}: verdict",
        "banners": banners,
        "decision": decision,
        "found": found,
        "facts": import_facts(records),
        "flags": flag_rows(flags),
        "thumbnails": _captioned(thumbnails, "thumbnail"),
        "verdict": result["text"],
        "seeding": seeding["text"],
        "table": table,
        "caption": caption,
        "rules": list(rules),
        "statistics": tuple(statistics) if statistics else None,
        "strongest": strongest,
        "mitigations": mitigations,
        "probe": probe,
        "figures": _captioned(figures, "teaser"),
        "meaning": [tuple(item) for item in meaning],
        "provenance": dict(provenance or {}),
    }


def _normalised(s: dict) -> dict:
    """Sections as :func:`page_sections` gives them, from sections made by hand: figures as
    ``(path, caption)`` pairs, and the optional parts present."""
    return {
        "rules": [],
        "statistics": None,
        "strongest": None,
        "probe": "",
        "meaning": [],
        "provenance": {},
        **s,
        "thumbnails": _captioned(s["thumbnails"], "thumbnail"),
        "figures": _captioned(s["figures"], "teaser"),
    }


def _md_figure(item) -> list[str]:
    path, text = item
    return [_markdown_image(path), "", f"*{caption_markdown(text)}*", ""]


def to_markdown_page(s: dict) -> str:
    """The page as Markdown; every text of the sections through :func:`markdown_text`, and
    through :func:`markdown_line` where it starts a line."""
    s = _normalised(s)
    d = s["decision"]
    m = markdown_text
    lines = [f"# {m(s['title'])}", ""]
    lines += [f"> **Warning.** {m(b)}" for b in s["banners"]] + ([""] if s["banners"] else [])
    lines += [f"**{m(d['light'].upper())}: {m(d['headline'])}**", ""]
    if d.get("do"):
        lines += [f"**What to do.** {m(d['do'])}", "", m(d["sure"]), ""]
    else:
        lines += [" ".join(m(x) for x in d["sentences"]), ""]
    if s["provenance"]:
        lines += [f"*{m(provenance_line(s['provenance']))}*", ""]
    if s["meaning"]:
        lines += ["### What these numbers mean", ""]
        lines += [f"- **{m(term)}:** {m(text)}" for term, text in s["meaning"]] + [""]
    lines += [
        "## What was imported",
        "",
        f"{markdown_line(s['found'])}.",
        "",
        to_markdown(_markdown_rows(s["facts"]), FACT_COLUMNS),
        "",
    ]
    if s["flags"]:
        lines += [
            "### Warnings and flags",
            "",
            to_markdown(_markdown_rows(s["flags"]), FLAG_COLUMNS),
            "",
        ]
    else:
        lines += ["No warnings or flags.", ""]
    for item in s["thumbnails"]:
        lines += _md_figure(item)
    lines += [
        "## Details",
        "",
        f"**Verdict.** {m(s['verdict'])}",
        "",
        f"**Seeding.** {m(s['seeding'])}",
        "",
        to_markdown(
            _markdown_rows(s["table"]), VERDICT_COLUMNS, caption=markdown_line(s["caption"])
        ),
        "",
    ]
    if s["rules"]:
        lines += ["### How the verdict reads these numbers", "",
                  *[f"- {caption_markdown(r)}" for r in s["rules"]], ""]
    if s.get("statistics"):
        lines += _md_figure(s["statistics"])
    st = s.get("strongest")
    if st:
        lines += ["## Where the cue is strongest", "", caption_markdown(st["text"]), ""]
        lines += [to_markdown(_markdown_rows(st["frame_rows"]), STRONGEST_FRAME_COLUMNS), ""]
        if st["tile_rows"]:
            lines += [to_markdown(_markdown_rows(st["tile_rows"]), STRONGEST_TILE_COLUMNS), ""]
        if st.get("figure"):
            lines += _md_figure(st["figure"])
    if s["mitigations"]:
        lines += ["## Mitigations", "", *[f"- {markdown_line(f)}" for f in s["mitigations"]], ""]
    if s.get("probe"):
        lines += ["## Learned probe", "", markdown_line(s["probe"]), ""]
    for item in s["figures"]:
        lines += _md_figure(item)
    return "\n".join(lines)


def to_html_page(s: dict, base=None) -> str:
    """The page as one self-contained HTML document: the template ``verdict.html.j2``
    (:mod:`stereovar.pages.templates`), every text escaped, captions and rules rendered from
    their inline markup (:func:`stereovar.pages.captions.caption_markup`, math as MathML).

    With ``base`` (the page's folder), every image is embedded as a ``data:`` URI
    (:func:`stereovar.pages.html.data_uri`) read from its path relative to ``base``, so the
    one file can be mailed or attached on its own; without it, images are linked by those
    relative paths."""
    from ..pages.html import data_uri
    from ..pages.templates import render

    def embed(src):
        return data_uri(Path(base) / src) if base is not None else src

    s = _normalised(s)
    light = s["decision"]["light"]
    return render(
        "verdict.html.j2",
        title=s["title"],
        s=s,
        word=light.upper(),
        colour=LIGHTS[light],
        alt=lambda src: Path(src).stem,
        fact_columns=FACT_COLUMNS,
        fact_labels=FACT_LABELS,
        embed=embed,
        provenance=provenance_line(s["provenance"]),
        flag_columns=FLAG_COLUMNS,
        verdict_columns=VERDICT_COLUMNS,
        strongest_frame_columns=STRONGEST_FRAME_COLUMNS,
        strongest_tile_columns=STRONGEST_TILE_COLUMNS,
    )
