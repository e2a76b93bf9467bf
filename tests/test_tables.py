"""Table writers: Markdown, LaTeX and HTML parse back to the rows; the CSV round-trips."""

import gzip
import math
import re
from html.parser import HTMLParser

import pytest

from stereovar.io.tables import (
    FORMATS,
    read_rows,
    to_csv,
    to_html,
    to_latex,
    to_markdown,
    write_tables,
)

NAN = float("nan")
COLUMNS = ["region", "n_points", "mean_rho", "std_rho", "reason"]
ROWS = [
    {"region": "all", "n_points": 12345, "mean_rho": 0.7512345678, "std_rho": 0.05, "reason": ""},
    {"region": "non_glass", "n_points": 3, "mean_rho": -1.23456789e-5, "std_rho": NAN},
    {
        "region": "glass",
        "n_points": 0,
        "mean_rho": NAN,
        "std_rho": 123456.789,
        "reason": "fewer than 30 valid pixels (n=0)",
    },
]


def shown(value, digits=4):
    """What a table cell should show, computed here independently of the writers."""
    if isinstance(value, float):
        return "NaN" if math.isnan(value) else f"{value:.{digits}g}"
    return str(value)


def expected_cells(rows=ROWS, columns=COLUMNS, digits=4):
    return [[shown(row.get(c, ""), digits) for c in columns] for row in rows]


def markdown_cells(text):
    """Header and body cells of the pipe table in ``text`` (unescaping ``\\|``)."""
    lines = [ln for ln in text.splitlines() if ln.startswith("|")]
    split = [
        [c.strip().replace(r"\|", "|") for c in re.split(r"(?<!\\)\|", ln.strip()[1:-1])]
        for ln in lines
    ]
    header, rule, *body = split
    assert all(set(c) <= set(":-") and c for c in rule)
    return header, body


class _TableParser(HTMLParser):
    """Collects the caption, the header cells and the body rows of an HTML table."""

    def __init__(self):
        super().__init__()
        self.caption, self.headers, self.rows = "", [], []
        self._where, self._text = None, None

    def handle_starttag(self, tag, attrs):
        if tag == "tr" and self._where == "tbody":
            self.rows.append([])
        elif tag in ("thead", "tbody"):
            self._where = tag
        elif tag in ("th", "td", "caption"):
            self._text = []

    def handle_endtag(self, tag):
        if tag in ("th", "td", "caption"):
            text = "".join(self._text)
            if tag == "caption":
                self.caption = text
            elif self._where == "thead":
                self.headers.append(text)
            else:
                self.rows[-1].append(text)
            self._text = None

    def handle_data(self, data):
        if self._text is not None:
            self._text.append(data)


def test_markdown_parses_back_to_the_rows():
    text = to_markdown(ROWS, COLUMNS, caption="Cross-scene correlation")
    assert text.splitlines()[:2] == ["Cross-scene correlation", ""]
    header, body = markdown_cells(text)
    assert header == COLUMNS
    assert len(body) == len(ROWS) and all(len(r) == len(COLUMNS) for r in body)
    assert body == expected_cells()
    # Numbers come back to 4 significant digits.
    for row, cells in zip(ROWS, body, strict=True):
        for c, cell in zip(COLUMNS, cells, strict=True):
            value = row.get(c, "")
            if isinstance(value, float) and not math.isnan(value):
                assert float(cell) == pytest.approx(value, rel=5e-4)


def test_markdown_without_caption_starts_with_the_table_and_escapes_pipes():
    rows = [{"a": "x|y", "b": 1.0}]
    text = to_markdown(rows, ["a", "b"], digits=2)
    assert text.startswith("|") and text.endswith("\n")
    header, body = markdown_cells(text)
    assert header == ["a", "b"] and body == [["x|y", shown(1.0, 2)]]


def test_latex_is_booktabs_with_escapes_and_caption():
    caption = "Table 1: rho_warp at 95% & #2"
    text = to_latex(ROWS, COLUMNS, caption=caption)
    for rule in (r"\toprule", r"\midrule", r"\bottomrule"):
        assert text.count(rule) == 1
    assert r"\begin{table}" in text and r"\end{table}" in text
    assert r"\caption{Table 1: rho\_warp at 95\% \& \#2}" in text
    assert r"\begin{tabular}{" + "l" * len(COLUMNS) + "}" in text
    lines = text.splitlines()
    top, mid, bottom = (lines.index(r) for r in (r"\toprule", r"\midrule", r"\bottomrule"))
    assert lines[top + 1] == " & ".join(c.replace("_", r"\_") for c in COLUMNS) + r" \\"
    body = lines[mid + 1 : bottom]
    assert len(body) == len(ROWS)
    for line, cells in zip(body, expected_cells(), strict=True):
        assert line == " & ".join(c.replace("_", r"\_") for c in cells) + r" \\"
    assert "non\\_glass" in text and "n\\_points" in text
    assert not re.search(r"(?<!\\)_", text.replace(r"\_", ""))


def test_latex_without_caption_is_a_bare_tabular():
    text = to_latex(ROWS, COLUMNS)
    assert text.startswith(r"\begin{tabular}") and r"\begin{table}" not in text
    assert r"\caption" not in text and r"\toprule" in text


def test_html_is_a_page_with_every_header_and_row():
    caption = "Residual <shuffle> & friends (Table 3)"
    text = to_html(ROWS, COLUMNS, caption=caption)
    assert text.startswith("<!DOCTYPE html>") and "<style>" in text and "<table" in text
    assert "<script" not in text and "http" not in text
    parser = _TableParser()
    parser.feed(text)
    assert parser.caption == caption
    assert parser.headers == COLUMNS
    assert parser.rows == expected_cells()


def test_html_escapes_cells_and_honours_digits():
    rows = [{"name": "<b>x</b>", "value": math.pi}]
    text = to_html(rows, ["name", "value"], digits=3)
    assert "<b>" not in text
    parser = _TableParser()
    parser.feed(text)
    assert parser.caption == ""
    assert parser.rows == [["<b>x</b>", shown(math.pi, 3)]]


def test_empty_tables_keep_their_headers():
    header, body = markdown_cells(to_markdown([], COLUMNS))
    assert header == COLUMNS and body == []
    assert r"\toprule" in to_latex([], COLUMNS)
    parser = _TableParser()
    parser.feed(to_html([], COLUMNS))
    assert parser.headers == COLUMNS and parser.rows == []


def assert_same_rows(got, want, columns):
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert list(g) == columns
        for c in columns:
            value = w.get(c, "")
            if isinstance(value, float) and math.isnan(value):
                assert isinstance(g[c], float) and math.isnan(g[c]), c
            else:
                assert g[c] == value and type(g[c]) is type(value), c


def test_csv_round_trips_at_full_precision(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(to_csv(ROWS, COLUMNS))
    lines = path.read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS) and len(lines) == 1 + len(ROWS)
    assert_same_rows(read_rows(path), ROWS, COLUMNS)
    gz = tmp_path / "t.csv.gz"
    with gzip.open(gz, "wt") as fh:
        fh.write(to_csv(ROWS, COLUMNS))
    assert_same_rows(read_rows(gz), ROWS, COLUMNS)


def test_write_tables_writes_every_format(tmp_path):
    assert set(FORMATS) == {"csv", "md", "tex", "html"}
    paths = {k: tmp_path / f"table.{k}" for k in FORMATS}
    run = {"renderer": "mitsuba", "estimator": "seeds"}
    write_tables(ROWS, COLUMNS, paths, caption="Table 1", constants=run)
    assert_same_rows(read_rows(paths["csv"]), [{**r, **run} for r in ROWS], [*COLUMNS, *run])
    said = "Table 1 (renderer mitsuba, estimator seeds)"
    md = paths["md"].read_text()
    assert md.splitlines()[0] == said
    assert markdown_cells(md) == (COLUMNS, expected_cells())
    assert r"\caption{" + said + "}" in paths["tex"].read_text()
    parser = _TableParser()
    parser.feed(paths["html"].read_text(encoding="utf-8"))
    assert parser.caption == said and parser.headers == COLUMNS
    assert parser.rows == expected_cells()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in paths.values())


def test_write_tables_rejects_an_unknown_format(tmp_path):
    with pytest.raises(ValueError, match="pdf"):
        write_tables(ROWS, COLUMNS, {"csv": tmp_path / "t.csv", "pdf": tmp_path / "t.pdf"})
    assert not list(tmp_path.iterdir())
