"""Jobs of ``workflow/rules/audit.smk``: an audit's import (one job per frame), its verdict
page and the export of renders."""

from __future__ import annotations

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


SEEDING_COLUMNS = [
    "scene",
    "region",
    "alignment",
    "rho",
    "low",
    "high",
    "n_pixels",
    "n_seeds",
    "n_tiles",
    "reason",
]
"""One frame's residual-correlation rows (:func:`seeding_job`)."""


def seeding_job(left, right, ground_truth, out, *, analysis=None, controls=None) -> list[dict]:
    """Whether the two views of one imported frame share their random streams: the
    cross-view correlation of the per-seed residuals at zero disparity and at the
    ground-truth disparity (:func:`stereovar.statistics.residuals.residual_correlation`),
    per region of the valid set, with block-bootstrap intervals; seed :math:`n` of the left
    view is paired with seed :math:`n` of the right (the audit's seed labels, sorted)."""
    import numpy as np

    from ..io.store import load_store
    from ..io.tables import write_tables
    from ..statistics.regions import REGIONS, region_masks, valid_set
    from ..statistics.residuals import residual_correlation
    from .common import view_stack
    from .correlation import analysis_settings

    settings, _ = analysis_settings(analysis, controls)
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    gl = gt.sel(view="left")
    stacks = {}
    for view, paths in (("left", left), ("right", right)):
        stack, seeds, _, attrs = view_stack(paths)
        stacks[view] = stack[np.argsort(seeds, kind="stable")]
    sign = int(gt.attrs.get("disparity_sign", 1))
    disparity = gl["disparity"].transpose("y", "x").values
    valid = gl["valid"].transpose("y", "x").values
    masks = region_masks(gl, valid_set(disparity, sign=sign, valid=valid))
    regions = REGIONS if gt.attrs.get("material_mask") != "none" else ("all",)
    rows = residual_correlation(
        stacks["left"],
        stacks["right"],
        disparity,
        sign=sign,
        masks={r: masks[r] for r in regions},
        valid=valid,
        settings=settings.bootstrap,
        min_pixels=settings.min_pixels,
    )
    scene = attrs.get("scene", gt.attrs.get("scene", ""))
    for r in rows:
        r["scene"] = scene
        log.info(
            "%s %-9s residual rho at %-12s %.4f [%.4f, %.4f] (n=%d)%s",
            scene, r["region"], r["alignment"], r["rho"], r["low"], r["high"], r["n_pixels"],
            f" [{r['reason']}]" if r["reason"] else "",
        )
    write_tables(rows, SEEDING_COLUMNS, {"csv": out})
    return rows


def thumbnail_job(left, ground_truth, out) -> None:
    """One frame's thumbnail (:func:`stereovar.figures.preview.thumbnail_figure`): the first
    seed of the left view and the imported disparity."""
    from ..figures.preview import thumbnail_figure
    from ..io.store import load_store
    from .common import save_figure

    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    renders = load_store(left[0], "render store", ["radiance"])
    image = renders["radiance"].isel(seed=0).transpose("y", "x", "channel").values
    scene = renders.attrs.get("scene", "")
    files = list(renders.attrs.get("source_files") or [])
    title = f"{scene}: {'/'.join(Path(files[0]).parts[-3:])}" if files else str(scene)
    save_figure(thumbnail_figure(image, gt, title=title), out, dpi=90)


def verdict_job(
    correlations,
    interventions,
    teasers,
    outputs: dict,
    *,
    name: str,
    found: str,
    thumbnails=(),
    seeding=(),
    imports=(),
    mitigations=None,
    mitigation_figure=None,
    probe=None,
    probe_figure=None,
    calibration=None,
    nulls=None,
) -> dict:
    """Write ``results/audit/{name}/verdict.{md,html}`` and ``summary.json``.

    The page (:mod:`stereovar.audit.page`) opens with a traffic light and what to do
    (:func:`stereovar.audit.verdict.decision`), then what was imported (each frame's
    import record: seeds, files, the sign check, the warnings) with every warning and flag
    (:func:`stereovar.audit.verdict.control_flags`) as a row of its own and one thumbnail
    per frame, then the details: the claims-style rows over the audit's frames with
    intervals, the plain-language verdict, whether the views share their random streams
    (``seeding``: :func:`seeding_job`), the teasers and, with ``mitigations`` (the audit's
    mitigation table), which mitigation removes the Monte Carlo-specific part and at what
    cost (:func:`stereovar.statistics.mitigations.mitigation_findings`), and its figure; with
    ``probe`` (``audit.probe: true``), the learned probe's verdict paragraph and figure; with
    ``calibration`` and ``nulls`` (the audit's calibration table and matched nulls,
    :mod:`stereovar.calibration`), the Monte Carlo-specific row the verdict rests on and the
    calibration's sentence."""
    from ..audit.page import import_flags, page_sections, to_html_page, to_markdown_page
    from ..audit.verdict import (
        RULES,
        VERDICT_COLUMNS,
        as_table,
        control_flags,
        decision,
        seeding_finding,
        seeding_rows,
        summary_lines,
        verdict,
        verdict_rows,
    )
    from ..io.store import write_file
    from ..io.tables import read_rows, to_csv

    corr = [r for p in correlations for r in read_rows(p)]
    iv = [r for p in interventions for r in read_rows(p)]
    residual = [r for p in seeding for r in read_rows(p)]
    records = [json.loads(Path(p).read_text()) for p in imports]
    null_rows = read_rows(nulls) if nulls else None
    rows = verdict_rows(corr, iv, null_rows) + seeding_rows(residual)
    calibrated = ""
    if calibration:
        from ..calibration.summary import headline

        calibrated = headline(read_rows(calibration))
    result = verdict(rows)
    if calibrated:
        result = {**result, "text": f"{result['text']} {calibrated}"}
    shared = seeding_finding(residual)
    flags = import_flags(records) + control_flags(rows, corr)
    findings = []
    if mitigations:
        from ..statistics.mitigations import mitigation_findings

        findings = mitigation_findings(read_rows(mitigations))
    opening = decision(result, shared, flags, findings, rows)
    lines = summary_lines(name, found, rows, result)
    lines.insert(0, f"{opening['light'].upper()}: {opening['headline']}")
    lines.append(f"  seeding: {shared['text']}")
    if calibrated:
        lines.append(f"  calibration: {calibrated}")
    lines += [f"  flag: {f['text']}" for f in flags]
    if findings:
        lines.append(f"mitigations: {findings[-1]}")
    for line in lines:
        log.info("%s", line)
    table = as_table(rows)
    base = Path(outputs["md"]).parent

    def relative(paths):
        return [Path(t).relative_to(base).as_posix() for t in paths]

    figures = relative(teasers) + (relative([mitigation_figure]) if mitigation_figure else [])
    probe_result = json.loads(Path(probe).read_text()) if probe else None
    if probe_figure:
        figures += relative([probe_figure])
    if probe_result:
        lines.append(f"probe: {probe_result['paragraph']}")
    sections = page_sections(
        name=name,
        found=found,
        decision=opening,
        result=result,
        seeding=shared,
        records=records,
        flags=flags,
        table=table,
        caption=f"Audit {name}: {found}. {RULES}",
        mitigations=findings,
        thumbnails=relative(thumbnails),
        figures=figures,
        probe=probe_result["paragraph"] if probe_result else "",
    )
    summary = {
        "audit": name,
        "found": found,
        **result,
        "light": opening["light"],
        "decision": [opening["headline"], *opening["sentences"]],
        "shared_streams": shared["shared"],
        "seeding": shared["text"],
        "flags": flags,
        "summary": lines,
        "mitigations": findings,
        "probe": probe_result,
        "calibration": calibrated,
        "rules": RULES,
        "rows": json.loads(json.dumps(table, default=str).replace("NaN", "null")),
        "csv": to_csv(table, VERDICT_COLUMNS),
    }
    md, page = to_markdown_page(sections), to_html_page(sections)
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
