"""Write result tables as CSV, Markdown and LaTeX from one list of rows."""

from __future__ import annotations

import csv
import gzip
import io
import math
from pathlib import Path

from .store import write_file

FORMATS = ("csv", "md", "tex", "html")


def _fmt(value, digits: int) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "NaN"
        return f"{value:.{digits}g}"
    return str(value)


def to_csv(rows: list[dict], columns: list[str]) -> str:
    """CSV text (full precision, ``NaN`` for missing values)."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: row.get(c, "") for c in columns})
    return buf.getvalue()


def read_rows(path) -> list[dict]:
    """Rows of a CSV written by :func:`write_tables`, with numbers parsed (``NaN`` too); a
    ``.gz`` path is read through gzip."""

    def parse(value: str):
        for kind in (int, float):
            try:
                return kind(value)
            except ValueError:
                continue
        return value

    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rt", newline="") as fh:
        return [{k: parse(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def to_markdown(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """GitHub-flavoured Markdown table, after a ``caption`` paragraph when one is given."""
    lines = [caption, ""] if caption else []
    lines += ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    for row in rows:
        lines.append("| " + " | ".join(_fmt(row.get(c, ""), digits) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def _tex_escape(text: str) -> str:
    for a, b in (
        ("\\", r"\textbackslash{}"),
        ("_", r"\_"),
        ("%", r"\%"),
        ("&", r"\&"),
        ("#", r"\#"),
    ):
        text = text.replace(a, b)
    return text


def to_latex(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """A ``booktabs`` LaTeX tabular (wrapped in a table environment when ``caption`` is set)."""
    body = [
        r"\begin{tabular}{" + "l" * len(columns) + "}",
        r"\toprule",
        " & ".join(_tex_escape(c) for c in columns) + r" \\",
        r"\midrule",
    ]
    for row in rows:
        body.append(" & ".join(_tex_escape(_fmt(row.get(c, ""), digits)) for c in columns) + r" \\")
    body += [r"\bottomrule", r"\end{tabular}"]
    if caption:
        body = [
            r"\begin{table}[t]",
            r"\centering",
            rf"\caption{{{_tex_escape(caption)}}}",
            *body,
            r"\end{table}",
        ]
    return "\n".join(body) + "\n"


HTML_STYLE = (
    "body{font-family:system-ui,sans-serif;margin:1em}"
    "table{border-collapse:collapse;font-size:0.85em}"
    "caption{caption-side:top;text-align:left;margin-bottom:0.5em;max-width:60em}"
    "th,td{border-bottom:1px solid #ccc;padding:0.25em 0.6em;text-align:right}"
    "th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}"
)


def to_html(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """A self-contained HTML page holding the table (shown inline by ``snakemake --report``)."""
    import html

    import pandas as pd

    frame = pd.DataFrame([{c: row.get(c, "") for c in columns} for row in rows], columns=columns)
    body = frame.to_html(
        index=False,
        na_rep="NaN",
        float_format=lambda v: f"{v:.{digits}g}",
        border=0,
    )
    if caption:
        body = body.replace(">", f"><caption>{html.escape(caption)}</caption>", 1)
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><style>{HTML_STYLE}</style>"
        f"</head><body>{body}</body></html>\n"
    )


def write_tables(
    rows: list[dict],
    columns: list[str],
    paths: dict,
    *,
    caption: str = "",
    digits: int = 4,
    constants: dict | None = None,
) -> None:
    """Write ``rows`` to each of ``paths`` (keys among ``csv``, ``md``, ``tex``, ``html``)
    atomically.

    ``constants`` (e.g. ``{"renderer": "mitsuba", "estimator": "seeds"}``) say what every row
    shows: the CSV gets them as trailing columns, the Markdown and LaTeX captions name them.
    """
    constants = dict(constants or {})
    if constants:
        said = ", ".join(f"{k} {v}" for k, v in constants.items())
        caption = f"{caption} ({said})" if caption else said
    csv_rows = [{**row, **constants} for row in rows]
    csv_columns = [*columns, *(k for k in constants if k not in columns)]
    render = {
        "csv": lambda: to_csv(csv_rows, csv_columns),
        "md": lambda: to_markdown(rows, columns, digits=digits, caption=caption),
        "tex": lambda: to_latex(rows, columns, digits=digits, caption=caption),
        "html": lambda: to_html(rows, columns, digits=digits, caption=caption),
    }
    for kind, path in paths.items():
        text = render[kind]()
        write_file(Path(path), lambda tmp, text=text: Path(tmp).write_text(text))
