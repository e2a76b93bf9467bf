"""Write result tables as CSV, Markdown, LaTeX and HTML from one list of rows.

The CSV keeps full precision (it is what the other jobs read back with :func:`read_rows`);
the Markdown (:meth:`pandas.DataFrame.to_markdown`, through ``tabulate``), LaTeX
(:meth:`pandas.io.formats.style.Styler.to_latex`, booktabs rules) and HTML
(:meth:`pandas.io.formats.style.Styler.to_html`, a small self-contained page for the
Snakemake report) show floats to a number of significant digits and ``NaN`` for missing
numbers.
"""

from __future__ import annotations

import csv
import gzip
import html
import io
import math
import numbers
import re
from pathlib import Path

from .store import write_file

FORMATS = ("csv", "md", "tex", "html")

# Characters that LaTeX treats specially, as pandas' ``escape="latex"`` replaces them in
# headers and cells; the caption, which Styler inserts verbatim, gets the same treatment.
_LATEX_SPECIALS = {
    "\\": r"\textbackslash ",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde ",
    "^": r"\textasciicircum ",
}
_LATEX_PATTERN = re.compile("|".join(re.escape(c) for c in _LATEX_SPECIALS))

_EMPTY_STYLE = re.compile(r"<style[^>]*>\s*</style>\s*")

_PAGE_CSS = """\
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       margin: 1em; color: #222; }
table { border-collapse: collapse; font-size: 0.9em; }
caption { caption-side: top; text-align: left; font-weight: 600; padding: 0 0 0.6em 0;
          max-width: 60em; }
th, td { padding: 0.3em 0.8em; text-align: left; white-space: nowrap; }
thead th { border-top: 2px solid #222; border-bottom: 1px solid #222;
           background: #f3f3f3; }
tbody tr:last-child td { border-bottom: 2px solid #222; }
tbody tr:nth-child(even) { background: #fafafa; }
tbody tr:hover { background: #eef4ff; }
td { font-variant-numeric: tabular-nums; }"""


def _is_number(value) -> bool:
    """Whether ``value`` is a real number other than a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _cell(value, digits: int) -> str:
    """Text of one cell: floats to ``digits`` significant digits, ``NaN`` for NaN or None.

    Parameters
    ----------
    value : object
        The cell's value.
    digits : int
        Significant digits of a float.

    Returns
    -------
    str
        The cell as shown in the Markdown, LaTeX and HTML tables.
    """
    if value is None:
        return "NaN"
    if _is_number(value) and not isinstance(value, numbers.Integral):
        if math.isnan(value):
            return "NaN"
        return f"{value:.{digits}g}"
    return str(value)


def _frame(rows: list[dict], columns: list[str]):
    """The rows as an object-dtype :class:`pandas.DataFrame` (values keep their Python type,
    so integers stay integers), missing keys as empty strings."""
    import pandas as pd

    return pd.DataFrame(
        [[row.get(c, "") for c in columns] for row in rows], columns=list(columns), dtype=object
    )


def _numeric_columns(rows: list[dict], columns: list[str]) -> list[bool]:
    """For each column, whether every non-empty cell is a number (for right alignment)."""
    flags = []
    for c in columns:
        values = [row.get(c, "") for row in rows]
        values = [v for v in values if not (isinstance(v, str) and v == "")]
        flags.append(bool(values) and all(v is None or _is_number(v) for v in values))
    return flags


def _styler(rows: list[dict], columns: list[str], *, digits: int, escape: str):
    """A :class:`pandas.io.formats.style.Styler` of the rows without the index, with cells
    formatted by :func:`_cell` and headers and cells escaped for ``escape`` (``"latex"`` or
    ``"html"``).

    The table id is fixed and cell ids are left out, so the output is deterministic.
    """
    from pandas.io.formats.style import Styler

    return (
        Styler(_frame(rows, columns), uuid="stereovar", cell_ids=False)
        .format(lambda v: _cell(v, digits), na_rep="NaN", escape=escape)
        .format_index(escape=escape, axis=1)
        .hide(axis="index")
    )


def _latex_escape(text: str) -> str:
    """``text`` with LaTeX's special characters escaped (for the caption)."""
    return _LATEX_PATTERN.sub(lambda m: _LATEX_SPECIALS[m.group()], text)


def to_csv(rows: list[dict], columns: list[str]) -> str:
    """CSV text at full precision.

    Parameters
    ----------
    rows : list of dict
        One dict per row, keyed by column name.
    columns : list of str
        The columns, in order; keys of a row that are not listed are dropped.

    Returns
    -------
    str
        A header line, then one line per row; a missing key is an empty field and a NaN is
        written as Python prints it (``nan``), which :func:`read_rows` parses back.
    """
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: row.get(c, "") for c in columns})
    return buf.getvalue()


def read_rows(path, *, required=()) -> list[dict]:
    """Rows of a CSV written by :func:`write_tables`, with numbers parsed.

    Parameters
    ----------
    path : str or path-like
        The CSV; a path ending in ``.gz`` is read through gzip.
    required : sequence of str, keyword-only
        Columns the header must have.

    Returns
    -------
    list of dict
        One dict per row: integers as ``int``, other numbers (``NaN`` too) as ``float``,
        everything else (empty fields too) as ``str``.

    Raises
    ------
    StoreError
        The file is missing or unreadable, a row has more or fewer fields than the header
        (a truncated or damaged file), or a required column is missing: one line with the
        command that rebuilds it (:func:`stereovar.io.store.store_error`).
    """
    from .store import store_error

    def parse(value: str):
        for kind in (int, float):
            try:
                return kind(value)
            except ValueError:
                continue
        return value

    opener = gzip.open if str(path).endswith(".gz") else open
    rows = []
    try:
        with opener(path, "rt", newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            for row in reader:
                if None in row or None in row.values():
                    raise ValueError(
                        f"line {reader.line_num} has a different number of fields than the header"
                    )
                rows.append({k: parse(v) for k, v in row.items()})
            header = list(reader.fieldnames or [])
    except (OSError, EOFError, UnicodeDecodeError, csv.Error, ValueError) as err:
        raise store_error(path, f"{type(err).__name__}: {err}", what="table") from None
    missing = [c for c in required if c not in header]
    if missing:
        raise store_error(path, f"no column {', '.join(missing)}", what="table")
    return rows


def to_markdown(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """A GitHub-flavoured (pipe) Markdown table, made by :meth:`pandas.DataFrame.to_markdown`.

    Parameters
    ----------
    rows : list of dict
        One dict per row, keyed by column name.
    columns : list of str
        The columns, in order.
    digits : int, optional
        Significant digits of floats (NaN is shown as ``NaN``).
    caption : str, optional
        A paragraph written before the table when given.

    Returns
    -------
    str
        The Markdown text, ending in a newline. Numeric columns are right-aligned and ``|``
        in a cell is escaped.
    """
    frame = _frame(rows, columns).map(lambda v: _cell(v, digits).replace("|", r"\|"))
    align = ["right" if n else "left" for n in _numeric_columns(rows, columns)]
    table = frame.to_markdown(
        index=False, tablefmt="pipe", disable_numparse=True, colalign=align or None
    )
    lines = [caption, ""] if caption else []
    return "\n".join([*lines, table]) + "\n"


def to_latex(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """A booktabs LaTeX tabular, made by :meth:`pandas.io.formats.style.Styler.to_latex`.

    Parameters
    ----------
    rows : list of dict
        One dict per row, keyed by column name.
    columns : list of str
        The columns, in order.
    digits : int, optional
        Significant digits of floats (NaN is shown as ``NaN``).
    caption : str, optional
        When given, the tabular is wrapped in a centred ``table`` environment (placement
        ``[t]``) with this ``\\caption``.

    Returns
    -------
    str
        The LaTeX text (``\\toprule``, ``\\midrule``, ``\\bottomrule``; needs the booktabs
        package), with LaTeX's special characters escaped in headers, cells and caption.
    """
    styler = _styler(rows, columns, digits=digits, escape="latex")
    options = {"position": "t", "position_float": "centering"} if caption else {}
    text = styler.to_latex(
        hrules=True,
        column_format="l" * len(columns),
        caption=_latex_escape(caption) if caption else None,
        **options,
    )
    return text if text.endswith("\n") else text + "\n"


def to_html(rows: list[dict], columns: list[str], *, digits: int = 4, caption: str = "") -> str:
    """A small self-contained HTML page holding the table, for the Snakemake report.

    The table is made by :meth:`pandas.io.formats.style.Styler.to_html`; the page has its
    own stylesheet and loads nothing.

    Parameters
    ----------
    rows : list of dict
        One dict per row, keyed by column name.
    columns : list of str
        The columns, in order.
    digits : int, optional
        Significant digits of floats (NaN is shown as ``NaN``).
    caption : str, optional
        The table's ``<caption>`` (and the page title) when given.

    Returns
    -------
    str
        The HTML document, starting with ``<!DOCTYPE html>``; headers, cells and caption are
        HTML-escaped and numeric columns are right-aligned.
    """
    styler = _styler(rows, columns, digits=digits, escape="html")
    if caption:
        styler = styler.set_caption(html.escape(caption))
    # Styler puts a (here empty) <style> block for its cell styles before the table.
    table = _EMPTY_STYLE.sub("", styler.to_html())
    right = ", ".join(
        f"th.col{i}, td.col{i}" for i, n in enumerate(_numeric_columns(rows, columns)) if n
    )
    css = _PAGE_CSS + (f"\n{right} {{ text-align: right; }}" if right else "")
    title = html.escape(caption) if caption else "Table"
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{title}</title>\n<style>\n{css}\n</style>\n</head>\n"
        f"<body>\n{table.strip()}\n</body>\n</html>\n"
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
    """Write ``rows`` to each of ``paths``, atomically.

    Parameters
    ----------
    rows : list of dict
        One dict per row, keyed by column name.
    columns : list of str
        The columns, in order.
    paths : dict
        Output path by format, keys among :data:`FORMATS` (``csv``, ``md``, ``tex``,
        ``html``).
    caption : str, optional
        The caption of the Markdown, LaTeX and HTML tables.
    digits : int, optional
        Significant digits of floats in the Markdown, LaTeX and HTML tables (the CSV keeps
        full precision).
    constants : dict, optional
        What every row shows (e.g. ``{"renderer": "mitsuba", "estimator": "seeds"}``): the
        CSV gets them as trailing columns, the other formats' captions name them.

    Raises
    ------
    ValueError
        If a key of ``paths`` is not one of :data:`FORMATS`.
    """
    unknown = sorted(set(paths) - set(FORMATS))
    if unknown:
        raise ValueError(f"unknown table format(s) {unknown}; expected some of {FORMATS}")
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
        write_file(Path(path), lambda tmp, text=text: Path(tmp).write_text(text, encoding="utf-8"))
