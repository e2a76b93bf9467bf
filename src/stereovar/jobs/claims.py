"""Jobs of ``workflow/rules/claims.smk``: every statistic across scenes, the seed curve, the
claims table and ``results/summary.json``, and the results page ``results/index.html``."""

from __future__ import annotations

from .common import log, run_of


def statistics_job(correlations, curves, outputs: dict, curve_outputs: dict, *, spp) -> list:
    """Every statistic and control across scenes at the main SPP, and :math:`\\rho`
    against the number of seeds."""
    from ..io.tables import read_rows, write_tables
    from ..statistics.across import (
        CURVE_TABLE_COLUMNS,
        STATISTICS_COLUMNS,
        curve_table,
        statistics_table,
    )

    rows = [r for path in correlations for r in read_rows(path)]
    run = run_of(rows)
    table = statistics_table(rows, spp=int(spp))
    write_tables(
        table,
        STATISTICS_COLUMNS,
        outputs,
        caption=(
            f"Every statistic and control across scenes at SPP={spp}: mean rho with the 95% "
            "interval from the scenes' spatial block bootstraps (boot_low, boot_high: these "
            "scenes) and the 95% interval for the mean over scenes like these (scenes_low, "
            "scenes_high: random effects, as the claims read them), the spread over scenes, "
            "the mean widths of the Fisher-z (independent pixels) and bootstrap intervals, "
            "the share of the covariance in the top 0.1% of products, fireflies, split-half "
            "reliabilities and the attenuation-corrected rho"
        ),
        constants=run,
    )
    curve = [r for path in curves for r in read_rows(path)]
    write_tables(
        curve_table(curve, rows),
        CURVE_TABLE_COLUMNS,
        curve_outputs,
        caption="rho against the number of seeds N' (disjoint seed subsets), across scenes",
        constants=run,
    )
    return table


def claims_job(
    correlations,
    curves,
    sweep,
    interventions,
    outputs: dict,
    summary,
    *,
    spp,
    config_digest="",
    claims_digest="",
    mitigations=None,
    probe=None,
) -> list[dict]:
    """The claims table and ``results/summary.json``: every headline number with its
    interval and control, the config digest, the renderer, the estimator and the claims file
    with its SHA-256; with ``mitigations`` (``results/tables/mitigations.csv``), every
    mitigation row too; with ``probe`` (``results/tables/probe_verdict.json``, when the probe
    has run), the probe's verdict and a claims row "a trained matcher uses the cue". Its
    ``provenance`` (:func:`stereovar.provenance.provenance`) hashes the tables it reads and
    gives the version and the date; the results page shows it.

    ``claims_digest`` is the claims file's SHA-256 when the workflow was read (the rule's
    rerun trigger); a file changed since is refused, so the table never mixes the two."""
    import json
    import math
    from pathlib import Path

    from ..errors import ClaimsError
    from ..io.store import write_file
    from ..io.tables import read_rows, write_tables
    from ..statistics.across import statistics_table
    from ..statistics.claims import CLAIMS_COLUMNS, claims_table, load_claims

    rows = [r for path in correlations for r in read_rows(path)]
    rows = [r for r in rows if r.get("spp") == int(spp)]
    curve = [r for path in curves for r in read_rows(path)]
    sweep_rows = read_rows(sweep) if sweep else []
    intervention = [r for path in interventions for r in read_rows(path)]
    run = run_of(rows)
    claims_file = load_claims()
    if claims_digest and claims_digest != claims_file.sha256:
        raise ClaimsError(
            f"claims file '{claims_file.path}' changed after the workflow was read; run it again"
        )
    claims = claims_table(
        rows, sweep=sweep_rows, curve=curve, intervention=intervention, claims=claims_file
    )
    probe_verdict = json.loads(Path(probe).read_text()) if probe else None
    if probe_verdict:
        claims.append(probe_claim(probe_verdict))
    write_tables(
        claims,
        CLAIMS_COLUMNS,
        outputs,
        caption=f"The paper's claims on this run (SPP={spp}). {claims_file.caption()}",
        constants=run,
    )

    def clean(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    headline = [
        {
            k: clean(r[k])
            for k in (
                "region",
                "method",
                "mean_rho",
                "boot_low",
                "boot_high",
                "scenes_low",
                "scenes_high",
                "std_rho",
                "n_scenes",
                "mean_rho_corrected",
                "chance_se",
            )
        }
        for r in statistics_table(rows, spp=int(spp))
    ]
    from ..provenance import file_hashes, provenance

    inputs = [*correlations, *curves, *([sweep] if sweep else []), *interventions,
              *([mitigations] if mitigations else []), *([probe] if probe else [])]
    document = {
        "provenance": provenance(file_hashes(inputs), config_digest),
        "config_digest": config_digest,
        **run,
        "spp": int(spp),
        "n_seeds": int(rows[0]["n_seeds"]) if rows else None,
        "scenes": sorted({str(r["scene"]) for r in rows}),
        "interval": "95% spatial block bootstrap (scenes combined): boot_low, boot_high; "
        "95% over scenes like these (random effects, as the claims read them): scenes_low, "
        "scenes_high",
        "statistics": headline,
        "claims_file": {"path": "stereovar/statistics/claims.yaml", "sha256": claims_file.sha256},
        "claims": [{k: clean(v) for k, v in c.items()} for c in claims],
    }
    if mitigations:
        from ..statistics.mitigations import INTERVALS

        document["mitigations"] = {
            "intervals": INTERVALS,
            "rows": [{k: clean(v) for k, v in r.items()} for r in read_rows(mitigations)],
        }
    if probe_verdict:
        document["probe"] = probe_verdict
    text = json.dumps(document, indent=2) + "\n"
    write_file(Path(summary), lambda tmp: Path(tmp).write_text(text))
    from ..pages.names import claim_name

    for c in claims:
        log.info("%-70s %s", claim_name(str(c["id"]), str(c["claim"])), c["verdict"])
    return claims


def probe_claim(verdict: dict) -> dict:
    """The claims-table row of the learned probe's verdict
    (:func:`stereovar.probe.verdict.probe_verdict`): "a trained matcher uses the cue", the
    difference in differences of the residual shuffle with its interval, against the control
    network (the paper leaves the question open, Sec. 5)."""
    import math

    def num(key):
        value = verdict.get(key)
        return math.nan if value is None else float(value)

    uses = verdict.get("uses_cue")
    return {
        "id": "probe",
        "claim": "a trained matcher uses the cue",
        "section": "Sec. 5 (sec:conclusion), left open",
        "kind": "probe",
        "paper": "open",
        "null": 0.0,
        "ours": num("did"),
        "ours_low": num("did_low"),
        "ours_high": num("did_high"),
        "control": f"shuffle drop of the {verdict.get('control', 'sensor_only')} network",
        "control_value": math.nan,
        "control_low": math.nan,
        "control_high": math.nan,
        "verdict": "n/a" if uses is None else ("yes" if uses else "no"),
        "note": (
            f"difference in differences of the residual shuffle, {verdict.get('region')} "
            "pixels; results/tables/probe.*"
        ),
    }


def _page_group(path) -> str:
    """The run a result file belongs to, from its folder: ``across the run`` for
    ``results/{tables,figures}/``, else ``{source key}, {estimator} estimator``."""
    from pathlib import PurePosixPath

    parts = PurePosixPath(str(path)).parts[1:-2]  # results/<key...>/<estimator>/<kind>/<file>
    if not parts:
        return "across the run"
    return f"{'/'.join(parts[:-1])}, {parts[-1]} estimator" if len(parts) > 1 else parts[0]


def _page_tables(paths, page) -> list[dict]:
    """The tables among ``paths`` (every format of each), one entry per table with its
    links from ``page`` in :data:`stereovar.layout.TABLE_FORMATS` order, the tables across
    the run first."""
    from pathlib import PurePosixPath

    from ..layout import TABLE_FORMATS
    from ..pages.html import relative_link

    tables: dict = {}
    for path in paths:
        p = PurePosixPath(str(path))
        if p.suffix[1:] not in TABLE_FORMATS:
            continue
        entry = tables.setdefault(
            (str(p.parent), p.stem), {"name": p.stem, "group": _page_group(p), "links": {}}
        )
        entry["links"][p.suffix[1:]] = relative_link(p, page)
    for entry in tables.values():
        entry["links"] = {f: entry["links"][f] for f in TABLE_FORMATS if f in entry["links"]}
    # the run's own tables (claims, scenes) first, then each run's in the order given
    return sorted(tables.values(), key=lambda t: t["group"] != "across the run")


def _page_figure(path, captions: dict) -> dict:
    """One figure of the page: embedded as a data URI, with its caption."""
    from pathlib import Path

    from ..pages.html import data_uri

    name = Path(path).stem
    return {
        "name": name,
        "src": data_uri(path),
        "caption": captions.get(name, ""),
        "group": _page_group(path),
    }


PAGE_INTRO = (
    "**stereovar** renders path-traced stereo scenes and measures how the per-pixel Monte "
    "Carlo variance fields of the two views correlate once aligned by the ground-truth "
    "disparity, and how much of that is Monte Carlo's own rather than what camera noise "
    "would give."
)
"""The results page's paragraph on what the run is (reStructuredText)."""


def report_command(report) -> str:
    """The command that writes Snakemake's report at ``report``.

    Examples
    --------
    >>> report_command("results/report.html"), report_command("out/r.html")
    ('stereovar report', 'stereovar report -o out/r.html')
    """
    from ..layout import snakemake_report

    return "stereovar report" if str(report) == snakemake_report() else (
        f"stereovar report -o {report}"
    )


def claim_statistics(claims: list[dict]) -> dict:
    """Claim id to the (region, method) of the :math:`\\rho` it tests, for the claims whose
    statistic is a :math:`\\rho` (the page marks those numbers when a control explains
    them).

    Examples
    --------
    >>> claim_statistics([{"id": "a", "statistic": {"name": "rho", "region": "all",
    ...                    "method": "warp"}}, {"id": "b", "statistic": {"name": "seed_change"}}])
    {'a': ('all', 'warp')}
    """
    return {
        c["id"]: (c["statistic"]["region"], c["statistic"]["method"])
        for c in claims
        if c.get("statistic", {}).get("name") == "rho"
    }


def _calibration_nulls(tables, calibration) -> str | None:
    """The calibration's matched nulls (``calibration_nulls.csv``): among ``tables``, else
    beside the calibration table (the same job writes both); None when there are none."""
    from pathlib import Path

    for path in tables:
        if Path(str(path)).name == "calibration_nulls.csv":
            return str(path)
    if calibration:
        beside = Path(str(calibration)).with_name("calibration_nulls.csv")
        if beside.is_file():
            return str(beside)
    return None


def results_page_job(
    claims,
    summary,
    out,
    *,
    figures=(),
    tables=(),
    captions=None,
    report=None,
    mitigations=None,
    mitigation_figure=None,
    dose=None,
    probe=None,
    probe_figure=None,
    generators=None,
    generators_figure=None,
    calibration=None,
) -> dict:
    """Write ``results/index.html`` (:mod:`stereovar.pages.results`): a one-line conclusion
    and the headline, the Monte Carlo-specific :math:`\\rho` (the intensity-controlled
    :math:`\\rho` of ``summary``, ``results/summary.json``, minus the calibration's matched
    null, ``calibration_nulls.csv`` among ``tables`` or beside ``calibration``) with its
    interval and controls; the claims table (``claims``, its CSV) by claim name; every figure
    of ``figures`` embedded with its caption (``captions``: figure name and ``claims`` to the
    report's caption, its Jinja already filled); with ``mitigations`` (the mitigation
    table's CSV, with ``dose``, the dose-response table's, the budget and camera that
    remove the cue) and ``probe`` (the probe's verdict JSON) and ``generators`` (the generator
    table's files) their sections and figures; links to every table of ``tables`` relative
    to the page, to ``report`` (Snakemake's report) when it exists, and to the
    documentation (:func:`stereovar.links.docs_page`); with ``calibration`` (the
    calibration table's CSV) its sentence under the headline.

    Returns the page's sections."""
    import json
    from pathlib import Path

    from ..calibration.sentences import headline
    from ..io.store import write_file
    from ..io.tables import read_rows
    from ..layout import snakemake_report
    from ..links import docs_page
    from ..pages.html import relative_link
    from ..pages.results import page_sections, to_html_page
    from ..statistics.claim_rules import KINDS
    from ..statistics.claims import load_claims

    captions = dict(captions or {})
    claim_rows = read_rows(claims, required=["claim", "verdict"])
    document = json.loads(Path(summary).read_text())
    claims_file = load_claims()
    all_tables = _page_tables(tables, out)

    def section_tables(name):
        return [t for t in all_tables if t["name"] == name]

    mitigation_section = None
    if mitigations:
        from ..statistics.dose_response import dose_findings

        mitigation_section = {
            "rows": read_rows(mitigations),
            "figure": _page_figure(mitigation_figure, captions) if mitigation_figure else None,
            "tables": section_tables("mitigations"),
            "dose": dose_findings(read_rows(dose)) if dose else [],
        }
    probe_section = None
    if probe:
        probe_section = {
            "paragraph": json.loads(Path(probe).read_text())["paragraph"],
            "figure": _page_figure(probe_figure, captions) if probe_figure else None,
            "tables": section_tables("probe"),
        }
    generator_section = None
    if generators:
        from ..statistics.generators import compact_table

        generator_section = {
            "rows": compact_table(read_rows(next(p for p in generators if p.endswith(".csv")))),
            "figure": _page_figure(generators_figure, captions) if generators_figure else None,
            "tables": _page_tables(generators, out),
        }
    report = report or snakemake_report()
    nulls = _calibration_nulls(tables, calibration)
    sections = page_sections(
        summary=document,
        claims=claim_rows,
        claims_text=captions.get("claims", ""),
        rules=[*(claims_file.rules[k] for k in KINDS), claims_file.intervals],
        figures=[_page_figure(f, captions) for f in figures],
        tables=all_tables,
        intro=PAGE_INTRO,
        mitigations=mitigation_section,
        probe=probe_section,
        generators=generator_section,
        report=relative_link(report, out) if Path(report).is_file() else None,
        report_command=report_command(report),
        calibration=headline(read_rows(calibration)) if calibration else "",
        nulls=read_rows(nulls) if nulls else None,
        claim_statistics=claim_statistics(claims_file.claims),
        own_scale={c["id"] for c in claims_file.claims if c.get("paper_scale") == "own"},
        provenance=document.get("provenance"),
        docs={
            "page": docs_page("outputs", "the-results-page"),
            "calibration": docs_page("calibration"),
            "mitigations": docs_page("mitigations"),
            "probe": docs_page("probe"),
            "generators": docs_page("generators"),
        },
    )
    page = to_html_page(sections)
    write_file(Path(out), lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
    log.info("%s: %s", sections["conclusion"]["word"], sections["conclusion"]["text"])
    log.info("%d claims, %d figures, %d tables%s%s", len(claim_rows), len(figures),
             len(all_tables), "; mitigations" if mitigation_section else "",
             "; probe" if probe_section else "")
    log.info("wrote %s (%.0f KiB): open it in a browser", out, len(page.encode()) / 1024)
    return sections
