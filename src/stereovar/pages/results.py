"""The main run's results page, ``results/index.html``: what a person opens after a run.

:func:`page_sections` puts the run's results in reading order, and :func:`to_html_page`
renders them with the template ``results.html.j2`` (:mod:`stereovar.pages.templates`) as one
self-contained page (figures embedded, links relative to ``results/``):

1. a one-line conclusion (:mod:`stereovar.pages.conclusion`): whether the views' Monte Carlo
   variance fields correlate beyond their matched null, with the number that says so, its
   interval and its control;
2. the run's settings (renderer, estimator, scenes, N and SPP, the config digest);
3. the headline (:mod:`stereovar.pages.headline`): the Monte Carlo-specific :math:`\\rho`, the
   intensity-controlled :math:`\\rho` minus its matched null through the same path, with its
   95% interval and the null beside it; then every control by region with its interval
   (:mod:`stereovar.pages.controls`), each number the claims call "explained by a control"
   marked so beside it; and the calibration's sentence;
4. the claims table (:mod:`stereovar.pages.claims_table`), each claim by name and section
   name (:mod:`stereovar.pages.names`), on a band of colour of its own;
5. the figures with their captions (``workflow/report/*.rst``, MathML math);
6. the mitigations (one compact table, :mod:`stereovar.pages.mitigation_table`), the learned
   probe and the generator profiles, when they have run;
7. links to every table in each format (:data:`TABLE_LABELS`), and to Snakemake's report or
   the command that makes it.

Every number is written by :mod:`stereovar.pages.numbers`. A number is called Monte
Carlo-specific only as a difference from its matched null (the calibration's camera-law
noise through the same statistic): without the calibration's nulls the page says so, and
headlines :math:`\\rho` after the warp with its controls.
"""

from __future__ import annotations

from .claims_table import CLAIMS_BAND, claim_cells
from .conclusion import conclusion
from .controls import CONTROL_GROUPS, INTERVAL_NOTE, REGIONS, control_rows, explained_statistics
from .headline import headline, matched_headline
from .mitigation_table import MITIGATION_COLUMNS, mitigation_rows
from .names import readable

__all__ = ["page_sections", "to_html_page"]

TABLE_LABELS = {
    "claims": "Claims of the paper on this run",
    "scenes": "Scenes",
    "statistics": "Every statistic and control across scenes",
    "seed_curve": "ρ against the number of seeds",
    "cross_scene": "Table 1: per scene",
    "spp_sweep": "Table 2: ρ against SPP",
    "spp_sweep_fit": "Table 2: fit against SPP",
    "intervention": "Table 3: the residual-shuffle intervention",
    "cross_renderer": "The renderers side by side",
    "mitigations": "Mitigations: every region, control and Table 3 column",
    "mitigations_headline": "Mitigations: the table on this page",
    "probe": "Learned probe",
    "probe_training": "Learned probe: training",
    "generators": "Generator profiles",
    "calibration": "Calibration: false positives, power and coverage of every rule",
    "calibration_nulls": "Calibration: each scene's matched null per transform",
}
"""Labels of the tables the page links, by file name."""


def page_sections(
    *,
    summary: dict,
    claims: list[dict],
    claims_text: str,
    rules: list[str],
    figures: list[dict],
    tables: list[dict],
    intro: str = "",
    mitigations: dict | None = None,
    probe: dict | None = None,
    generators: dict | None = None,
    report: str | None = None,
    report_command: str = "stereovar report",
    calibration: str = "",
    nulls: list[dict] | None = None,
    claim_statistics: dict | None = None,
    docs: dict | None = None,
    own_scale=(),
    provenance: dict | None = None,
) -> dict:
    """Everything the page shows, in reading order (see the module docstring).

    Parameters
    ----------
    summary : dict
        ``results/summary.json`` (:func:`stereovar.jobs.claims.claims_job`).
    claims : list of dict
        The claims table's rows (``results/tables/claims.csv``).
    claims_text, intro : str
        The claims table's caption and a paragraph on the run (reStructuredText).
    rules : list of str
        The verdicts' rules and the intervals, as the claims table's caption states them.
    figures : list of dict
        ``name``, ``src`` (a data URI or a path relative to the page), ``caption``
        (reStructuredText) and ``group`` (the run it belongs to) of each figure.
    tables : list of dict
        ``name``, ``group`` and ``links`` (format to a path relative to the page).
    mitigations, probe : dict, optional
        When they have run: ``rows`` (the mitigation table's rows) and ``lines``
        (:func:`stereovar.statistics.mitigations.mitigation_findings`), or ``paragraph``
        (probe); ``figure`` (as in ``figures``, or None) and ``tables`` (as in ``tables``).
    generators : dict, optional
        When the ``generators`` target has run: ``rows``
        (:func:`stereovar.statistics.generators.compact_table`), ``figure`` and ``tables``.
    report : str, optional
        Snakemake's report relative to the page, when it exists.
    report_command : str, optional
        The command that makes the report.
    calibration : str, optional
        The calibration's sentence (:func:`stereovar.calibration.sentences.headline`).
    nulls : list of dict, optional
        The calibration's matched nulls (``calibration_nulls.csv``): with them the headline
        is the Monte Carlo-specific :math:`\\rho`
        (:func:`~stereovar.pages.headline.matched_headline`).
    claim_statistics : dict, optional
        Claim id to the (region, method) of the :math:`\\rho` it tests
        (:func:`~stereovar.pages.controls.explained_statistics`).
    docs : dict, optional
        Documentation addresses by topic (``page``, ``calibration``, ``mitigations``,
        ``probe``, ``generators``; :func:`stereovar.links.docs_page`).
    own_scale : iterable of str, optional
        Ids of the claims whose paper value is in the paper's own units
        (:func:`~stereovar.pages.claims_table.claim_cells`).
    provenance : dict, optional
        :func:`stereovar.provenance.provenance` of the page.
    """
    statistics = list(summary.get("statistics") or [])
    tally: dict[str, int] = {}
    for row in claims:
        tally[str(row.get("verdict", ""))] = tally.get(str(row.get("verdict", "")), 0) + 1
    scenes = list(summary.get("scenes") or [])
    explained = explained_statistics(claims, claim_statistics or {})
    matched = matched_headline(statistics, nulls or [], scenes=scenes or None)
    warp = headline(statistics)
    mitigation_section = None
    if mitigations:
        from ..statistics.mitigations import mitigation_findings

        rows = list(mitigations.get("rows") or [])
        table = mitigation_rows(rows)
        columns = [c for c in MITIGATION_COLUMNS
                   if c != "ships" or any(r["ships"] != "as measured" for r in table)]
        findings = mitigation_findings(rows) if rows else list(mitigations.get("lines") or [])
        n_rows = len([r for r in rows if r.get("region") == "all"])
        mitigation_section = {
            "rows": table,
            "columns": columns,
            "labels": MITIGATION_COLUMNS,
            "summary": (findings[n_rows:] if rows else findings) + [
                f"What removes it (dose-response, dose_response.md): {line}"
                for line in mitigations.get("dose") or []],
            "figure": mitigations.get("figure"),
            "tables": _labelled(mitigations.get("tables") or []),
        }
    if probe:
        probe = {**probe, "tables": _labelled(probe.get("tables") or [])}
    if generators:
        generators = {**generators, **_generator_table(generators.get("rows") or []),
                      "tables": _labelled(generators.get("tables") or [])}
    return {
        "title": "stereovar: results of this run",
        "conclusion": conclusion(matched, warp, explained),
        "run": {
            "renderer": summary.get("renderer", ""),
            "estimator": summary.get("estimator", ""),
            "scenes": scenes,
            "spp": summary.get("spp"),
            "n_seeds": summary.get("n_seeds"),
            "config_digest": str(summary.get("config_digest") or ""),
        },
        "intro": intro,
        "headline": warp,
        "matched": matched,
        "explained": explained,
        "interval": INTERVAL_NOTE,
        "provenance": dict(provenance or {}),
        "controls": control_rows(statistics, matched, explained),
        "control_notes": [(group, note) for group, note, _ in CONTROL_GROUPS],
        "tally": tally,
        "claims": [claim_cells(r, rho=r.get("id") in (claim_statistics or {}),
                               own_scale=r.get("id") in set(own_scale)) for r in claims],
        "claims_text": claims_text,
        "rules": list(rules),
        "figures": list(figures),
        "mitigations": mitigation_section,
        "probe": probe,
        "generators": generators,
        "tables": _labelled(tables),
        "report": report,
        "report_command": report_command,
        "calibration": calibration,
        "calibration_links": next(
            (t["links"] for t in tables if t["name"] == "calibration" and t.get("links")), {}
        ),
        "docs": dict(docs or {}),
    }


def _labelled(tables: list[dict]) -> list[dict]:
    """``tables`` with each one's label (:data:`TABLE_LABELS`)."""
    return [{**t, "label": TABLE_LABELS.get(t["name"], readable(t["name"]))} for t in tables]


def _generator_table(rows: list[dict]) -> dict:
    """The generator table's columns, without a probe column that says only "not run"."""
    from ..statistics.generators import PROBE_NOT_RUN

    columns = list(rows[0]) if rows else []
    probe_not_run = bool(rows) and all(r.get("probe") == PROBE_NOT_RUN for r in rows)
    if probe_not_run:
        columns.remove("probe")
    labels = {c: c.replace("rho", "ρ") for c in columns}
    return {"columns": columns, "labels": labels, "probe_not_run": probe_not_run}


def to_html_page(s: dict) -> str:
    """The page as one self-contained HTML document (``results.html.j2``, no script)."""
    from ..provenance import provenance_line
    from .templates import render

    return render("results.html.j2", s=s, title=s["title"], band=CLAIMS_BAND,
                  regions=REGIONS, provenance=provenance_line(s.get("provenance") or {}))
