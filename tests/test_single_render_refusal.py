"""An audit given one render per view refuses in one line that says why, with the numbers
measured by bench/single_render.py and the page that holds the measurement."""

from __future__ import annotations

from pathlib import Path

import pytest

from stereovar.audit.layout import discover
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.errors import AuditError
from stereovar.estimators.single import DOCS_PAGE, MEASURED, refusal
from stereovar.links import docs_page

REPO = Path(__file__).resolve().parents[1]


def test_the_refusal_is_one_line_with_the_measured_numbers_and_the_page():
    line = refusal()
    assert "\n" not in line
    assert line.startswith("one render per view cannot tell a Monte Carlo cue from none")
    assert MEASURED["method"] in line and "N >= 2" in line
    assert docs_page("single_render") in line and DOCS_PAGE not in line  # no repository path
    assert f"Spearman {MEASURED['spearman']:.2f}" in line
    assert f"{100 * MEASURED['fpr']:.0f}% of cue-free camera frames" in line
    assert f"from {MEASURED['n2_smallest']:.3g}x" in line
    assert f"at most {100 * MEASURED['n2_fpr']:.0f}% false positives" in line


def test_the_page_the_refusal_points_at_exists_and_quotes_its_numbers():
    page = (REPO / DOCS_PAGE).read_text(encoding="utf-8")
    assert "REFUSED" in page and "ACCEPTED" not in page
    assert MEASURED["method"] in page
    for number in (f"{100 * MEASURED['fpr']:.0f}%", f"{MEASURED['spearman']:.2f}",
                   f"{MEASURED['n2_smallest']:.3g}"):
        assert number in page, number
    output = (REPO / "bench" / "single_render_output.md").read_text(encoding="utf-8")
    assert f"{100 * MEASURED['fpr']:.0f}% [" in output
    assert "single_render" in (REPO / "docs" / "guide.md").read_text(encoding="utf-8")


def test_an_audit_of_one_render_per_view_refuses_with_the_reason(tmp_path):
    settings, _ = write_synthetic_audit(
        tmp_path, n_frames=1, n_seeds=1, width=24, height=12, render_format="npy",
        disparity_format="npy",
    )
    with pytest.raises(AuditError) as caught:
        discover(settings)
    message = str(caught.value)
    assert "\n" not in message
    assert "view left (L): 1 render (" in message
    assert refusal() in message


def test_two_renders_per_view_are_still_accepted(tmp_path):
    settings, _ = write_synthetic_audit(
        tmp_path, n_frames=1, n_seeds=2, width=24, height=12, render_format="npy",
        disparity_format="npy",
    )
    assert discover(settings).n_seeds == 2
