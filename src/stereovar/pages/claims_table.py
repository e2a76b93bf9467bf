"""The results page's claims table (:func:`claim_cells`): each claim of the paper by name,
where the paper makes it by section name (:mod:`stereovar.pages.names`), our number with its
95% interval, the control in words and the verdict as a coloured badge
(:data:`VERDICT_CLASSES`), on a band of colour :data:`CLAIMS_BAND`.
"""

from __future__ import annotations

import math

from .names import claim_name, control_name, readable, section_name
from .numbers import _f, interval_text, significant

__all__ = ["CLAIMS_BAND", "claim_cells"]

CLAIMS_BAND = "#e3eefb"
"""Background of the claims table, a colour used nowhere else on the page (a browser test
finds the table on a screenshot by it)."""

VERDICT_CLASSES = {
    "holds": "holds",
    "does not hold": "fails",
    "explained by a control": "explained",
    "not testable at this scale": "untestable",
    "remains": "remains",
    "removed": "removed",
    "inconclusive": "inconclusive",
    "reversed": "remains",
    "n/a": "na",
}
"""CSS class of each verdict (others, such as the probe's yes/no, are plain)."""


def claim_cells(row: dict, *, rho: bool = False, own_scale: bool = False) -> dict:
    """One claims-table row (:data:`stereovar.statistics.claims.CLAIMS_COLUMNS`) as the
    page shows it: the claim by name (:func:`stereovar.pages.names.claim_name`), where the
    paper makes it by section name, numbers to 3 significant digits with their 95%
    intervals (``rho``: a correlation claim, to 3 decimals as the headline table shows the
    same numbers), the control in words. ``own_scale``: the paper's value is in the paper's
    own units (``paper_scale: own`` in the claims file), so the paper column gives its sign,
    the only part that compares, with the value named as the paper's own.

    Examples
    --------
    >>> c = claim_cells({"id": "rho_all", "claim": "rho (all) = 0.754",
    ...     "section": "Sec. 3.2 (sec:exp-main)", "paper": 0.754,
    ...     "ours": 0.7012, "ours_low": 0.65, "ours_high": 0.75, "control": "sensor_sim rho",
    ...     "control_value": 0.01, "control_low": -0.02, "control_high": 0.04,
    ...     "verdict": "does not hold", "note": ""})
    >>> c["claim"], c["section"]
    ('ρ over all valid pixels is 0.754', 'Sec. 3.2, cross-scene correlation')
    >>> c["ours"], c["verdict_class"]
    ('0.701 [0.65, 0.75]', 'fails')
    >>> c["control"], c["control_value"]
    ("ρ of a simulated camera's noise", '0.01 [-0.02, 0.04]')
    """
    paper = row.get("paper")
    fmt = ".3f" if rho else "sig"
    control_value = interval_text(
        row.get("control_value"), row.get("control_low"), row.get("control_high"), fmt=fmt
    )
    paper_note = ""
    if math.isfinite(_f(paper)) and own_scale:
        paper_text = "> 0" if _f(paper) > 0 else "< 0" if _f(paper) < 0 else "0"
        paper_note = f"sign only: the paper's {significant(_f(paper))} is in its own units"
    elif math.isfinite(_f(paper)):
        paper_text = significant(_f(paper))
    else:
        paper_text = str(paper or "")
    verdict = str(row.get("verdict", ""))
    return {
        "id": str(row.get("id", "")),
        "claim": claim_name(str(row.get("id", "")), str(row.get("claim", ""))),
        "section": section_name(str(row.get("section", ""))),
        "note": readable(str(row.get("note") or "")),
        "paper": paper_text,
        "paper_note": paper_note,
        "ours": interval_text(row.get("ours"), row.get("ours_low"), row.get("ours_high"),
                              fmt=fmt),
        "control": control_name(str(row.get("control") or "")) or "none",
        "control_value": control_value if row.get("control") else "",
        "verdict": verdict,
        "verdict_class": VERDICT_CLASSES.get(verdict, ""),
    }
