"""The audit's verdict page: a decision first, then the import's facts, then the details.

:func:`page_sections` puts what :mod:`stereovar.audit.verdict` computed in reading order:

1. banners (an inconclusive sign check the audit went on with, ``audit.sign_check: warn``,
   and a sign check won with a high error);
2. the decision: a traffic light and two or three sentences (what was found, how sure,
   what to do; :func:`stereovar.audit.verdict.decision`);
3. the import's facts: frames, seeds and files, each frame's sign check and valid pixels,
   and every warning and flag as a row of its own;
4. one thumbnail per frame (a render and the disparity), so the reader sees that the right
   files were read;
5. the details: the verdict paragraph, the seeding finding, the table with intervals, the
   mitigations and the teasers.

:func:`to_markdown_page` and :func:`to_html_page` write the same sections; the HTML page is
self-contained (its own stylesheet, images by relative path), built from the blocks of
:mod:`stereovar.pages.html`. Every text the sections carry (file paths, audit and frame
names, warnings) is escaped on both pages: HTML-escaped on the HTML page, and on the
Markdown page made inert (:func:`markdown_text`), so a folder named
``d<img src=x onerror=alert(1)>`` is shown, not run.
"""

from __future__ import annotations

import html
import math
import re
from pathlib import Path
from urllib.parse import quote

from ..io.tables import to_markdown
from ..pages.html import document, figure
from ..pages.html import table as _table_html
from .importer import WARNING_KINDS
from .verdict import FLAG_LABELS, LIGHTS, VERDICT_COLUMNS

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

BANNER_KINDS = ("sign_check", "sign_check_error")
"""Import warnings the page opens with, above the decision: the sign check the disparity
rests on was inconclusive, or won with a high error."""

FLAG_COLUMNS = ["flag", "frame", "what"]
"""Columns of the flags table (one row per warning or flag)."""

_CSS = """
.light { display: flex; gap: 1em; align-items: flex-start; border: 1px solid #ccc;
  border-radius: 6px; padding: 0.8em 1em; margin: 1em 0; max-width: 60em; }
.light .dot { flex: none; width: 2.2em; height: 2.2em; border-radius: 50%; }
.light p { margin: 0.3em 0; }
.light .headline { font-size: 1.15em; font-weight: bold; }
.banner { background: #fff3cd; border: 1px solid #e6a700; border-radius: 6px;
  padding: 0.6em 1em; margin: 0.6em 0; max-width: 60em; }
.thumbs { display: flex; flex-wrap: wrap; gap: 1em; }
.thumbs figure { margin: 0; }
p, li { max-width: 60em; }
.flags td { white-space: normal; vertical-align: top; }
.flags td.col2 { min-width: 30em; max-width: 60em; }
"""


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
        f"{100 * sign['error']:.1f}% declared vs {100 * sign['opposite_error']:.1f}% opposite"
    )
    text += "" if sign.get("conclusive", True) else " (inconclusive)"
    return text + (" (error high)" if sign.get("high_error") else "")


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
                "sign_check": _sign_fact(found.get("sign") or {}),
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
    thumbnails: list[str],
    figures: list[str],
    probe: str = "",
) -> dict:
    """Everything the page shows, in reading order (see the module docstring).

    ``thumbnails`` and ``figures`` are paths relative to the page; ``probe`` is the learned
    probe's verdict paragraph (``audit.probe: true``).
    """
    banners = [f["text"] for f in flags if f["kind"] in BANNER_KINDS]
    return {
        "title": f"Audit {name}: verdict",
        "banners": banners,
        "decision": decision,
        "found": found,
        "facts": import_facts(records),
        "flags": flag_rows(flags),
        "thumbnails": thumbnails,
        "verdict": result["text"],
        "seeding": seeding["text"],
        "table": table,
        "caption": caption,
        "mitigations": mitigations,
        "probe": probe,
        "figures": figures,
    }


def to_markdown_page(s: dict) -> str:
    """The page as Markdown; every text of the sections through :func:`markdown_text`, and
    through :func:`markdown_line` where it starts a line."""
    d = s["decision"]
    m = markdown_text
    lines = [f"# {m(s['title'])}", ""]
    lines += [f"> **Warning.** {m(b)}" for b in s["banners"]] + ([""] if s["banners"] else [])
    lines += [
        f"**{m(d['light'].upper())}: {m(d['headline'])}** "
        + " ".join(m(x) for x in d["sentences"]),
        "",
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
    lines += [_markdown_image(t) for t in s["thumbnails"]] + [""]
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
    if s["mitigations"]:
        lines += ["## Mitigations", "", *[f"- {markdown_line(f)}" for f in s["mitigations"]], ""]
    if s.get("probe"):
        lines += ["## Learned probe", "", markdown_line(s["probe"]), ""]
    lines += [_markdown_image(f) for f in s["figures"]] + [""]
    return "\n".join(lines)


def _figure(path: str) -> str:
    return figure(path, html.escape(Path(path).stem), alt=Path(path).stem)


def to_html_page(s: dict) -> str:
    """The page as one self-contained HTML document."""
    d = s["decision"]
    e = html.escape
    body = [f"<h1>{e(s['title'])}</h1>"]
    body += [f'<div class="banner"><b>Warning.</b> {e(b)}</div>' for b in s["banners"]]
    body.append(
        f'<div class="light" id="decision"><div class="dot" title="{e(d["light"])}" '
        f'style="background:{LIGHTS[d["light"]]}"></div><div>'
        f'<p class="headline">{e(d["headline"])}</p>'
        + "".join(f"<p>{e(x)}</p>" for x in d["sentences"])
        + "</div></div>"
    )
    body += [
        "<h2>What was imported</h2>",
        f"<p>{e(s['found'])}.</p>",
        _table_html(s["facts"], FACT_COLUMNS),
    ]
    if s["flags"]:
        body += [
            "<h3>Warnings and flags</h3>",
            f'<div class="flags">{_table_html(s["flags"], FLAG_COLUMNS)}</div>',
        ]
    else:
        body.append("<p>No warnings or flags.</p>")
    body.append('<div class="thumbs">' + "".join(map(_figure, s["thumbnails"])) + "</div>")
    body += [
        "<h2>Details</h2>",
        f"<p><b>Verdict.</b> {e(s['verdict'])}</p>",
        f"<p><b>Seeding.</b> {e(s['seeding'])}</p>",
        _table_html(s["table"], VERDICT_COLUMNS, s["caption"]),
    ]
    if s["mitigations"]:
        items = "".join(f"<li>{e(f)}</li>" for f in s["mitigations"])
        body.append(f"<h2>Mitigations</h2>\n<ul>{items}</ul>")
    if s.get("probe"):
        body.append(f"<h2>Learned probe</h2>\n<p>{e(s['probe'])}</p>")
    body += [_figure(f) for f in s["figures"]]
    return document(s["title"], body, _CSS)
