"""Jobs of ``workflow/rules/audit.smk``: an audit's import (one job per frame), its verdict
page and the export of renders."""

from __future__ import annotations

import html
import json
from pathlib import Path

from .common import log


def import_job(settings: dict, *, frame: str, workers: int = 2, fingerprint=None):
    """Import one frame of an audit (:func:`stereovar.audit.importer.import_frame`): each
    view's render store, the ground-truth store and the frame's import record (each file's
    SHA-256), at the paths of :func:`stereovar.audit.run.import_outputs`; log what the
    import found. ``fingerprint`` is the job's ``params.fingerprint``
    (:func:`stereovar.audit.importer.frame_fingerprint`), recorded with the files."""
    from ..audit.importer import import_frame

    report = import_frame(settings, frame, workers=workers, fingerprint=fingerprint)
    for line in report.lines():
        log.info("%s", line)
    return report


def verdict_job(
    correlations,
    interventions,
    teasers,
    outputs: dict,
    *,
    name: str,
    found: str,
    mitigations=None,
    mitigation_figure=None,
) -> dict:
    """Write ``results/audit/{name}/verdict.{md,html}`` and ``summary.json``: the claims-style
    rows over the audit's frames with intervals, the plain-language verdict and one teaser
    per frame (:mod:`stereovar.audit.verdict`); with ``mitigations`` (the audit's mitigation
    table), which mitigation removes the Monte Carlo-specific part and at what cost
    (:func:`stereovar.statistics.mitigations.mitigation_findings`), and its figure."""
    from ..audit.verdict import (
        RULES,
        VERDICT_COLUMNS,
        as_table,
        summary_lines,
        verdict,
        verdict_rows,
    )
    from ..io.store import write_file
    from ..io.tables import read_rows, to_csv, to_html, to_markdown

    corr = [r for p in correlations for r in read_rows(p)]
    iv = [r for p in interventions for r in read_rows(p)]
    rows = verdict_rows(corr, iv)
    result = verdict(rows)
    lines = summary_lines(name, found, rows, result)
    for line in lines:
        log.info("%s", line)
    table = as_table(rows)
    base = Path(outputs["md"]).parent
    figures = [Path(t).relative_to(base).as_posix() for t in teasers]
    findings = []
    if mitigations:
        from ..statistics.mitigations import mitigation_findings

        findings = mitigation_findings(read_rows(mitigations))
        for line in findings:
            log.info("mitigations: %s", line)
        lines += [f"mitigations: {findings[-1]}"]
    if mitigation_figure:
        figures.append(Path(mitigation_figure).relative_to(base).as_posix())
    caption = f"Audit {name}: {found}. {RULES}"
    md = "\n".join(
        [
            f"# Audit {name}: verdict",
            "",
            f"{found}.",
            "",
            f"**Verdict.** {result['text']}",
            "",
            to_markdown(table, VERDICT_COLUMNS, caption=caption),
            "",
            *(["## Mitigations", "", *[f"- {f}" for f in findings], ""] if findings else []),
            *[f"![{Path(f).stem}]({f})" for f in figures],
            "",
        ]
    )
    page = to_html(table, VERDICT_COLUMNS, caption=caption)
    extra = (
        f"<h1>Audit {html.escape(name)}: verdict</h1>\n"
        f"<p><b>Verdict.</b> {html.escape(result['text'])}</p>\n"
    )
    if findings:
        items = "".join(f"<li>{html.escape(f)}</li>" for f in findings)
        extra += f"<h2>Mitigations</h2>\n<ul>{items}</ul>\n"
    images = "".join(
        f'<figure><img src="{html.escape(f)}" style="max-width:100%">'
        f"<figcaption>{html.escape(Path(f).stem)}</figcaption></figure>\n"
        for f in figures
    )
    page = page.replace("<body>", "<body>\n" + extra, 1).replace("</body>", images + "</body>", 1)
    summary = {
        "audit": name,
        "found": found,
        **result,
        "summary": lines,
        "mitigations": findings,
        "rules": RULES,
        "rows": json.loads(json.dumps(table, default=str).replace("NaN", "null")),
        "csv": to_csv(table, VERDICT_COLUMNS),
    }
    write_file(outputs["md"], lambda tmp: Path(tmp).write_text(md))
    write_file(outputs["html"], lambda tmp: Path(tmp).write_text(page))
    write_file(outputs["summary"], lambda tmp: Path(tmp).write_text(json.dumps(summary, indent=1)))
    return summary


def export_job(renders: dict, ground_truth, out, *, scene: str, format: str, variance=None):
    """Export one scene's renders, variance fields and ground truth as ``format`` files
    (:func:`stereovar.audit.export.export_scene`)."""
    from ..audit.export import export_scene
    from ..io.renders import RenderStore

    spp = RenderStore(renders["left"][0]).attrs.get("spp")
    settings = export_scene(
        renders, ground_truth, out, fmt=format, scene=scene, variance=variance, spp=spp
    )
    log.info("exported %s to %s; audit it with the audit: section in %s/audit.yaml",
             scene, out, out)
    return settings
