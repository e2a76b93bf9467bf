"""The main run's results page, ``results/index.html``: what a person opens after a run.

:func:`page_sections` puts the run's results in reading order, and :func:`to_html_page`
writes them as one self-contained page (figures embedded, links relative to ``results/``):

1. what the run is (the report's ``workflow.rst``) and its settings (renderer, estimator,
   scenes, N and SPP, the config digest);
2. the headline :math:`\\rho` (all valid pixels, Eq. 3) with its 95% interval, and beside it
   the controls that bear on it (:data:`CONTROL_GROUPS`: the sensor baseline, the
   intensity-controlled :math:`\\rho`, the null warps) in every region, each with its
   interval (:func:`headline`, :func:`control_rows`), so the number is never read alone;
3. the claims table (:func:`claim_cells`), on a band of colour :data:`CLAIMS_BAND`, what
   it holds and the verdicts' rules (folded) below it;
4. the figures with their captions (``workflow/report/*.rst``);
5. the mitigations and the learned probe, when they have run;
6. links to every table in each format, and to Snakemake's report or how to make it.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import html
import math

from .captions import rst_to_html
from .html import document, figure

__all__ = [
    "CLAIMS_BAND",
    "CONTROL_GROUPS",
    "REGIONS",
    "claim_cells",
    "control_rows",
    "headline",
    "interval_text",
    "significant",
    "page_sections",
    "to_html_page",
]

CLAIMS_BAND = "#e3eefb"
"""Background of the claims table, a colour used nowhere else on the page (a browser test
finds the table on a screenshot by it)."""

REGIONS = {"all": "all valid pixels", "non_glass": "non-glass", "glass": "glass"}
"""Regions of the headline table, in order, with their labels."""

HEADLINE_METHOD = "warp"
"""The statistic of the headline: Pearson's :math:`\\rho` after the warp (Eq. 3)."""

CONTROL_GROUPS = (
    (
        "sensor baseline",
        "the same statistic on a simulated camera's noise over the same N frames: what any "
        "stereo pair shows",
        (("sensor_sim", "simulated camera"),),
    ),
    (
        "intensity-controlled",
        "ρ of ln σ² once ln μ is regressed out of each view: the Monte Carlo-specific part",
        (("partial", "partial ρ"),),
    ),
    (
        "null warps",
        "wrong alignments: the warp matters when these sit well below ρ",
        (
            ("null_shift", "disparity shifted"),
            ("null_flip", "right field flipped"),
            ("no_warp", "no warp"),
        ),
    ),
)
"""The controls shown beside the headline: (group, what it tells, ((method, label), ...));
every other statistic and control is in the statistics table and figure."""

VERDICT_CLASSES = {
    "holds": "holds",
    "does not hold": "fails",
    "explained by a control": "explained",
    "not testable at this scale": "untestable",
}
"""CSS class of each claims verdict (others, such as the probe's yes/no, are plain)."""

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
    "mitigations": "Mitigations",
    "probe": "Learned probe",
    "calibration": "Calibration: false positives, power and coverage of every rule",
    "calibration_nulls": "Calibration: each scene's matched null per transform",
}
"""Labels of the tables the page links, by file name."""

_CSS = f"""
body {{ max-width: 78em; margin: 0 auto; padding: 0 1.2em 3em; line-height: 1.4; }}
h1 {{ margin: 0.6em 0 0.1em; font-size: 1.7em; }}
h2 {{ margin: 1.6em 0 0.5em; border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }}
p, li {{ max-width: 70em; }}
nav {{ font-size: 0.9em; margin: 0.3em 0 0.8em; }}
nav a {{ margin-right: 1em; }}
.run {{ color: #555; margin: 0.2em 0 0.8em; }}
.intro p {{ margin: 0.2em 0; color: #333; font-size: 0.92em; }}
code {{ font-size: 0.92em; background: #f3f3f3; padding: 0 0.2em; border-radius: 3px; }}
.headline {{ display: flex; flex-wrap: wrap; gap: 1.5em; align-items: flex-start;
  border: 1px solid #ccc; border-radius: 6px; padding: 0.8em 1.2em; }}
.headline .rho {{ flex: 0 0 17em; }}
.headline .calibration {{ flex: 1 0 100%; margin: 0; font-size: 0.92em; }}
.headline .what {{ color: #555; font-size: 0.9em; margin: 0; }}
.headline .value {{ font-size: 2.3em; font-weight: 600; margin: 0.1em 0 0; }}
.headline .interval {{ font-size: 1.15em; margin: 0 0 0.4em; }}
.headline .tally {{ font-size: 0.9em; margin: 0.4em 0 0; }}
.headline div.controls {{ flex: 1 1 30em; }}
table.controls {{ font-size: 0.88em; width: 100%; }}
table.controls th, table.controls td {{ padding: 0.15em 0.7em; }}
table.controls tr.main td {{ font-weight: 600; }}
.headline .notes {{ font-size: 0.8em; color: #555; margin: 0.4em 0 0; }}
table.controls tbody tr {{ background: none; }}
table.claims {{ background: {CLAIMS_BAND}; width: 100%; font-size: 0.9em; }}
table.claims thead th, table.claims tbody tr, table.claims tbody tr:hover {{
  background: none; }}
table.claims td {{ white-space: normal; vertical-align: top; }}
table.claims td.num {{ white-space: nowrap; text-align: right; }}
.nowrap {{ white-space: nowrap; }}
table.claims .sub {{ color: #555; font-size: 0.88em; }}
.verdict {{ display: inline-block; padding: 0.05em 0.5em; border-radius: 1em;
  white-space: nowrap; background: #fff; border: 1px solid #bbb; }}
.verdict.holds {{ background: #d4edda; border-color: #5cb85c; }}
.verdict.fails {{ background: #f8d7da; border-color: #d9534f; }}
.verdict.explained {{ background: #fff3cd; border-color: #e6a700; }}
.verdict.untestable {{ background: #eeeeee; border-color: #aaa; color: #444; }}
.about p {{ font-size: 0.88em; color: #444; margin: 0.5em 0; max-width: 70em; }}
details {{ margin: 0.5em 0; font-size: 0.9em; max-width: 70em; }}
figure {{ margin: 1.4em 0; }}
figure img {{ border: 1px solid #eee; }}
figcaption {{ font-size: 0.9em; color: #333; max-width: 70em; }}
figcaption p {{ margin: 0.3em 0; }}
h3.group {{ color: #555; font-weight: 600; font-size: 1em; margin: 1.2em 0 0; }}
table.links td {{ white-space: normal; }}
table.mitigations td {{ white-space: normal; vertical-align: top; }}
table.links a {{ margin-right: 0.6em; }}
"""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def significant(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits (at least), with no exponent from 0.0001 up
    to a million: a value of ``digits`` or more integer digits is shown whole.

    Examples
    --------
    >>> significant(0.75412), significant(3594.2), significant(-10613.0), significant(7.0)
    ('0.754', '3594', '-10613', '7')
    >>> significant(0.000123), significant(2.5e7)
    ('0.000123', '2.5e+07')
    """
    if 10 ** (digits - 1) <= abs(value) < 1e6:
        return f"{value:.0f}"
    return f"{value:.{digits}g}"


def interval_text(value, low, high, *, fmt: str = ".3f") -> str:
    """``value [low, high]``, ``value (no interval)`` or ``n/a``; ``fmt`` is a format
    specification, or ``sig`` for :func:`significant`.

    Examples
    --------
    >>> interval_text(0.75412, 0.7311, 0.7766)
    '0.754 [0.731, 0.777]'
    >>> interval_text(7.04, None, "", fmt="sig"), interval_text(float("nan"), 0, 1)
    ('7.04 (no interval)', 'n/a')
    """
    v, lo, hi = _f(value), _f(low), _f(high)

    def show(x):
        return significant(x) if fmt == "sig" else format(x, fmt)

    if not math.isfinite(v):
        return "n/a"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{show(v)} (no interval)"
    return f"{show(v)} [{show(lo)}, {show(hi)}]"


def _statistic(statistics: list[dict], region: str, method: str) -> dict | None:
    return next(
        (r for r in statistics if r.get("region") == region and r.get("method") == method), None
    )


def headline(statistics: list[dict]) -> dict:
    """The headline of ``summary.json``'s ``statistics``: :math:`\\rho` after the warp over
    all valid pixels, the mean over scenes with its combined bootstrap interval.

    Returns
    -------
    dict
        ``rho``, ``low``, ``high`` (NaN when missing), ``n_scenes`` and ``text``
        (:func:`interval_text`).

    Examples
    --------
    >>> h = headline([{"region": "all", "method": "warp", "mean_rho": 0.7, "boot_low": 0.6,
    ...                "boot_high": 0.8, "n_scenes": 3}])
    >>> h["text"], h["n_scenes"]
    ('0.700 [0.600, 0.800]', 3)
    """
    row = _statistic(statistics, "all", HEADLINE_METHOD) or {}
    rho, low, high = (_f(row.get(k)) for k in ("mean_rho", "boot_low", "boot_high"))
    return {
        "rho": rho,
        "low": low,
        "high": high,
        "n_scenes": row.get("n_scenes"),
        "text": interval_text(rho, low, high),
    }


def control_rows(statistics: list[dict]) -> list[dict]:
    """The headline table: the headline statistic, then each control of
    :data:`CONTROL_GROUPS` that ``statistics`` holds, with its interval in every region.

    Returns
    -------
    list of dict
        ``method``, ``group`` (empty for the headline), ``label`` and ``cells`` (region to
        :func:`interval_text`).

    Examples
    --------
    >>> stats = [{"region": g, "method": m, "mean_rho": 0.5, "boot_low": 0.4, "boot_high": 0.6}
    ...          for g in ("all", "glass") for m in ("warp", "partial")]
    >>> [(r["method"], r["label"]) for r in control_rows(stats)]
    [('warp', 'ρ after the warp (Eq. 3)'), ('partial', 'intensity-controlled: partial ρ')]
    >>> control_rows(stats)[1]["cells"]
    {'all': '0.500 [0.400, 0.600]', 'non_glass': 'n/a', 'glass': '0.500 [0.400, 0.600]'}
    """

    def cells(method):
        return {
            region: interval_text(
                *(_f((_statistic(statistics, region, method) or {}).get(k))
                  for k in ("mean_rho", "boot_low", "boot_high"))
            )
            for region in REGIONS
        }

    rows = [{"method": HEADLINE_METHOD, "group": "", "label": "ρ after the warp (Eq. 3)",
             "cells": cells(HEADLINE_METHOD)}]
    present = {r.get("method") for r in statistics}
    for group, _, methods in CONTROL_GROUPS:
        rows += [
            {"method": m, "group": group, "label": f"{group}: {label}", "cells": cells(m)}
            for m, label in methods
            if m in present
        ]
    return rows


def claim_cells(row: dict) -> dict:
    """One claims-table row (:data:`stereovar.statistics.claims.CLAIMS_COLUMNS`) as the
    page shows it: numbers to 3 significant digits with their 95% intervals.

    Examples
    --------
    >>> c = claim_cells({"claim": "rho = 0.754", "section": "Sec. 3.2", "paper": 0.754,
    ...     "ours": 0.7012, "ours_low": 0.65, "ours_high": 0.75, "control": "sensor_sim rho",
    ...     "control_value": 0.01, "control_low": -0.02, "control_high": 0.04,
    ...     "verdict": "does not hold", "note": ""})
    >>> c["ours"], c["control"], c["control_value"], c["verdict_class"]
    ('0.701 [0.65, 0.75]', 'sensor_sim rho', '0.01 [-0.02, 0.04]', 'fails')
    """
    paper = row.get("paper")
    control_value = interval_text(
        row.get("control_value"), row.get("control_low"), row.get("control_high"), fmt="sig"
    )
    verdict = str(row.get("verdict", ""))
    return {
        "id": str(row.get("id", "")),
        "claim": str(row.get("claim", "")),
        "section": str(row.get("section", "")),
        "note": str(row.get("note") or ""),
        "paper": significant(_f(paper)) if math.isfinite(_f(paper)) else str(paper or ""),
        "ours": interval_text(row.get("ours"), row.get("ours_low"), row.get("ours_high"),
                              fmt="sig"),
        "control": str(row.get("control") or "") or "none",
        "control_value": control_value if row.get("control") else "",
        "verdict": verdict,
        "verdict_class": VERDICT_CLASSES.get(verdict, ""),
    }


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
    report_command: str = "snakemake --report results/report.html",
    calibration: str = "",
) -> dict:
    """Everything the page shows, in reading order (see the module docstring).

    Parameters
    ----------
    summary : dict
        ``results/summary.json`` (:func:`stereovar.jobs.claims.claims_job`).
    claims : list of dict
        The claims table's rows (``results/tables/claims.csv``).
    claims_text, intro : str
        The claims table's and the run's captions (reStructuredText).
    rules : list of str
        The verdicts' rules and the intervals, as the claims table's caption states them.
    figures : list of dict
        ``name``, ``src`` (a data URI or a path relative to the page), ``caption``
        (reStructuredText) and ``group`` (the run it belongs to) of each figure.
    tables : list of dict
        ``name``, ``group`` and ``links`` (format to a path relative to the page).
    mitigations, probe : dict, optional
        When they have run: ``lines`` (mitigations) or ``paragraph`` (probe), ``figure``
        (as in ``figures``, or None) and ``tables`` (as in ``tables``).
    generators : dict, optional
        When the ``generators`` target has run: ``rows``
        (:func:`stereovar.statistics.generators.compact_table`), ``figure`` and ``tables``.
    report : str, optional
        Snakemake's report relative to the page, when it exists.
    report_command : str, optional
        The command that makes the report.
    calibration : str, optional
        The calibration's sentence (:func:`stereovar.calibration.summary.headline`), shown
        under the headline.
    """
    statistics = list(summary.get("statistics") or [])
    tally: dict[str, int] = {}
    for row in claims:
        tally[str(row.get("verdict", ""))] = tally.get(str(row.get("verdict", "")), 0) + 1
    scenes = list(summary.get("scenes") or [])
    return {
        "title": "stereovar: results of this run",
        "run": {
            "renderer": summary.get("renderer", ""),
            "estimator": summary.get("estimator", ""),
            "scenes": scenes,
            "spp": summary.get("spp"),
            "n_seeds": summary.get("n_seeds"),
            "config_digest": str(summary.get("config_digest") or ""),
        },
        "intro": intro,
        "headline": headline(statistics),
        "interval": str(summary.get("interval") or "95% interval"),
        "controls": control_rows(statistics),
        "tally": tally,
        "claims": [claim_cells(r) for r in claims],
        "claims_text": claims_text,
        "rules": list(rules),
        "figures": list(figures),
        "mitigations": mitigations,
        "probe": probe,
        "generators": generators,
        "tables": list(tables),
        "report": report,
        "report_command": report_command,
        "calibration": calibration,
    }


def _e(text) -> str:
    return html.escape(str(text))


def _run_line(run: dict) -> str:
    scenes = run["scenes"]
    shown = ", ".join(scenes[:6]) + (f" and {len(scenes) - 6} more" if len(scenes) > 6 else "")
    parts = [
        f"renderer <b>{_e(run['renderer'])}</b>",
        f"estimator <b>{_e(run['estimator'])}</b>",
        f"{len(scenes)} scene{'s' if len(scenes) != 1 else ''} ({_e(shown)})",
        f"N = {_e(run['n_seeds'])} seeds at SPP {_e(run['spp'])}",
    ]
    if run["config_digest"]:
        parts.append(f"config <code>{_e(run['config_digest'][:12])}</code>")
    return '<p class="run">' + " · ".join(parts) + "</p>"


def _headline_html(s: dict) -> str:
    h = s["headline"]
    if math.isfinite(h["rho"]):
        value = f"ρ = {h['rho']:.3f}"
        interval = (
            f"95% interval [{h['low']:.3f}, {h['high']:.3f}]"
            if math.isfinite(h["low"]) and math.isfinite(h["high"])
            else "no interval (too few tiles or scenes)"
        )
    else:
        value, interval = "ρ: n/a", "no headline statistic in this run"
    n = h["n_scenes"]
    tally = ", ".join(f"{count} {verdict}" for verdict, count in s["tally"].items())
    left = (
        '<div class="rho">'
        '<p class="what">Cross-view variance correlation, all valid pixels, after the '
        "warp (Eq. 3)</p>"
        f'<p class="value">{_e(value)}</p><p class="interval">{_e(interval)}</p>'
        f'<p class="what">{_e(s["interval"])}'
        + (f"; mean over {_e(n)} scenes" if n not in (None, "") else "")
        + ". Read it against the controls beside it.</p>"
        + (f'<p class="tally"><a href="#claims">Claims</a>: {_e(tally)}.</p>' if tally else "")
        + "</div>"
    )
    head = "".join(f"<th>{_e(label)}</th>" for label in REGIONS.values())
    rows = []
    for r in s["controls"]:
        cells = "".join(f'<td class="num">{_e(r["cells"][g])}</td>' for g in REGIONS)
        cls = ' class="main"' if not r["group"] else ""
        rows.append(f'<tr{cls} data-method="{_e(r["method"])}"><td>{_e(r["label"])}</td>'
                    f"{cells}</tr>")
    shown = {r["group"] for r in s["controls"]}
    notes = "; ".join(
        f"<b>{_e(group)}</b>: {_e(note)}" for group, note, _ in CONTROL_GROUPS if group in shown
    )
    controls = (
        '<div class="controls"><table class="controls"><caption>ρ and its controls by region, '
        f"with 95% intervals</caption><thead><tr><th>statistic</th>{head}</tr></thead>"
        f"<tbody>{''.join(rows)}</tbody></table>"
        + (f'<p class="notes">{notes}.</p>' if notes else "")
        + "</div>"
    )
    calibration = (
        f'<p class="calibration"><b>Calibration</b>: {_e(s["calibration"])} '
        '(<code>tables/calibration.md</code>)</p>'
        if s.get("calibration")
        else ""
    )
    return (
        f'<section id="headline" class="headline">{left}{controls}{calibration}</section>'
    )


def _claims_html(s: dict) -> str:
    rows = []
    for c in s["claims"]:
        sub = " · ".join(x for x in (c["section"], c["note"]) if x)
        verdict = (
            f'<span class="verdict {c["verdict_class"]}">{_e(c["verdict"])}</span>'
            if c["verdict"]
            else ""
        )
        rows.append(
            f'<tr data-claim="{_e(c["id"])}"><td>{_e(c["claim"])}'
            + (f'<div class="sub">{_e(sub)}</div>' if sub else "")
            + f'</td><td class="num">{_e(c["paper"])}</td><td class="num">{_e(c["ours"])}</td>'
            f"<td>{_e(c['control'])}"
            + (f': <span class="nowrap">{_e(c["control_value"])}</span>'
               if c["control_value"] not in ("", "n/a") else "")
            + f"</td><td>{verdict}</td></tr>"
        )
    table = (
        '<table class="claims" id="claims-table"><thead><tr><th>claim</th><th>paper</th>'
        "<th>ours [95% interval]</th><th>control [95% interval]</th><th>verdict</th></tr>"
        f"</thead><tbody>{''.join(rows)}</tbody></table>"
    )
    rules = "".join(f"<p>{_e(r)}</p>" for r in s["rules"])
    return (
        '<section id="claims"><h2>Claims of the paper on this run</h2>'
        + table
        + f'<div class="about">{rst_to_html(s["claims_text"])}</div>'
        + (f"<details><summary>How the verdicts are given</summary>{rules}</details>"
           if rules else "")
        + "</section>"
    )


def _figure_html(f: dict) -> str:
    caption = rst_to_html(f.get("caption") or "") or f"<p>{_e(f['name'])}</p>"
    return figure(f["src"], caption, alt=f["name"], ident=f"figure-{f['name']}")


def _links_html(tables: list[dict]) -> str:
    if not tables:
        return "<p>No tables.</p>"
    rows = []
    for t in tables:
        links = " ".join(
            f'<a href="{_e(href)}">{_e(fmt)}</a>' for fmt, href in t["links"].items()
        )
        label = TABLE_LABELS.get(t["name"], t["name"])
        rows.append(
            f"<tr><td>{_e(label)}</td><td><code>{_e(t['name'])}</code></td>"
            f"<td>{_e(t['group'])}</td><td>{links}</td></tr>"
        )
    return (
        '<table class="links"><thead><tr><th>table</th><th>file</th><th>run</th>'
        f"<th>formats</th></tr></thead><tbody>{''.join(rows)}</tbody></table>"
    )


def _mitigation_headline_html(rows: list[dict]) -> str:
    """The mitigation headline table
    (:func:`stereovar.statistics.mitigations.headline_table`), all pixels."""
    if not rows:
        return ""
    columns = list(rows[0])
    head = "".join(f"<th>{_e(c)}</th>" for c in columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{_e(r[c])}</td>" for c in columns) + "</tr>" for r in rows
    )
    return (
        '<table class="mitigations"><thead><tr>' + head + "</tr></thead><tbody>" + body
        + "</tbody></table><p class=\"what\">All valid pixels; 95% intervals. The Monte "
        "Carlo-specific rho is the intensity-controlled rho minus its matched null through "
        "the same transform; <em>removed</em> means its interval lies inside the "
        "calibration's equivalence margin, <em>inconclusive</em> that it covers 0 but "
        "reaches past it. The full table (every region and control) is linked below.</p>"
    )


def _generator_table_html(rows: list[dict]) -> str:
    """The generator table (:func:`stereovar.statistics.generators.compact_table`), all
    pixels."""
    if not rows:
        return ""
    from ..statistics.generators import PROBE_NOT_RUN

    columns = list(rows[0])
    probe = ""
    if all(r.get("probe") == PROBE_NOT_RUN for r in rows):  # a column of "not run" says less
        columns.remove("probe")
        probe = " The learned probe was not run on these profiles (docs: Generator profiles)."
    head = "".join(f"<th>{_e(c)}</th>" for c in columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{_e(r[c])}</td>" for c in columns) + "</tr>" for r in rows
    )
    return (
        '<table class="mitigations"><thead><tr>' + head + "</tr></thead><tbody>" + body
        + "</tbody></table><p class=\"what\">All valid pixels; 95% intervals." + probe
        + " Each row is "
        "Cycles under one generator's own defaults (its SPP scaled to the budget where it is "
        "above it). The Monte Carlo-specific rho is the intensity-controlled rho minus the "
        "same statistic on the profile's own matched null, whose value stands beside it; the "
        "residual coupling at zero disparity is what one seed shared by both views "
        "couples.</p>"
    )


def to_html_page(s: dict) -> str:
    """The page as one self-contained HTML document (no script)."""
    nav = [("headline", "Headline"), ("claims", "Claims"), ("figures", "Figures")]
    nav += [("mitigations", "Mitigations")] if s["mitigations"] else []
    nav += [("probe", "Learned probe")] if s["probe"] else []
    nav += [("generators", "Generators")] if s.get("generators") else []
    nav += [("tables", "Tables"), ("report", "Snakemake report")]
    body = [
        f"<h1>{_e(s['title'])}</h1>",
        f'<div class="intro">{rst_to_html(s["intro"])}</div>' if s["intro"] else "",
        _run_line(s["run"]),
        "<nav>" + "".join(f'<a href="#{k}">{_e(v)}</a>' for k, v in nav) + "</nav>",
        _headline_html(s),
        _claims_html(s),
        '<section id="figures"><h2>Figures</h2>',
    ]
    group = None
    for f in s["figures"]:
        if f["group"] != group:
            group = f["group"]
            body.append(f'<h3 class="group">{_e(group)}</h3>')
        body.append(_figure_html(f))
    body.append("</section>")
    m = s["mitigations"]
    if m:
        items = "".join(f"<li>{_e(x)}</li>" for x in m["lines"])
        body += [
            '<section id="mitigations"><h2>Mitigations</h2>',
            _mitigation_headline_html(m.get("headline") or []),
            f"<ul>{items}</ul>",
            _figure_html(m["figure"]) if m.get("figure") else "",
            _links_html(m.get("tables") or []),
            "</section>",
        ]
    p = s["probe"]
    if p:
        body += [
            '<section id="probe"><h2>Learned probe</h2>',
            f"<p>{_e(p['paragraph'])}</p>",
            _figure_html(p["figure"]) if p.get("figure") else "",
            _links_html(p.get("tables") or []),
            "</section>",
        ]
    g = s.get("generators")
    if g:
        body += [
            '<section id="generators"><h2>Generator profiles</h2>',
            _generator_table_html(g["rows"]),
            _figure_html(g["figure"]) if g.get("figure") else "",
            _links_html(g.get("tables") or []),
            "</section>",
        ]
    body += [
        '<section id="tables"><h2>Tables</h2>',
        "<p>Every table of the run, in each format (CSV at full precision; Markdown, LaTeX "
        "and HTML to 4 significant digits), relative to this page's folder.</p>",
        _links_html(s["tables"]),
        "</section>",
        '<section id="report"><h2>Snakemake report</h2>',
    ]
    command = f"<code>{_e(s['report_command'])}</code>"
    if s["report"]:
        body.append(
            f'<p><a href="{_e(s["report"])}">Snakemake\'s report</a> holds every table and '
            f"figure with the workflow and each job's provenance ({command} remakes it).</p>"
        )
    else:
        body.append(
            "<p>Snakemake's report, with every table and figure, the workflow and each job's "
            f"provenance, was not made when this page was written: run {command} in the run's "
            "folder.</p>"
        )
    body.append("</section>")
    return document(s["title"], [b for b in body if b], _CSS)
