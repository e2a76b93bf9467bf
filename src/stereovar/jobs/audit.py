"""Jobs of ``workflow/rules/audit.smk``: an audit's import (one job per frame), its verdict
page and the export of renders."""

from __future__ import annotations

import json
import math
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
    from .settings import analysis_settings

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


def _json_value(v):
    """A table cell as a JSON value: numpy scalars as Python's, a non-finite number as null."""
    import numpy as np

    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


def _json_numbers(rows: list[dict]) -> list[dict]:
    """Rows as JSON values (:func:`_json_value`)."""
    return [{k: _json_value(v) for k, v in r.items()} for r in rows]


def _scene_paths(paths) -> dict:
    """Stores by the frame they hold (their ``scene`` attribute; nothing is read)."""
    from ..io.store import open_dataset

    out = {}
    for p in paths or ():
        out.setdefault(str(open_dataset(p).attrs.get("scene", "")), p)
    return out


def frame_residuals(variance, warped, ground_truth) -> tuple:
    """One frame's left seed mean and its two :math:`\\ln\\sigma^2` residual fields after
    intensity (:func:`stereovar.audit.strongest.residual_fields`) from its variance, warped
    and ground-truth stores."""
    import numpy as np

    from ..audit.strongest import residual_fields
    from ..io.contracts import read_alignment
    from ..io.store import load_store
    from ..statistics.fields import control_covariates, seed_mean_controls
    from .calibration import stored_encoding

    v = load_store(variance, "variance store")
    aligned = read_alignment(load_store(warped, "warped store"))
    sigma_l = v["variance"].sel(view="left").transpose("y", "x").values
    mean_left = mu_l = mu_w = covariates = None
    if "mean" in v:
        gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
        gl = gt.sel(view="left")
        means = {k: v["mean"].sel(view=k).transpose("y", "x", "channel").values
                 for k in ("left", "right")}
        mean_left = means["left"]
        truth = {k: gl[k].transpose("y", "x").values for k in ("disparity", "valid")}
        sign = int(gt.attrs["disparity_sign"])
        controls = seed_mean_controls(mean_left, means["right"], truth, sign=sign,
                                      encoding=stored_encoding(v.attrs))
        mu_l, mu_w = controls["intensity"]
        covariates = control_covariates(sigma_l.shape, colour=controls["colour"],
                                        quantisation=controls.get("quantisation"),
                                        disparity=truth["disparity"], sign=sign)
    e_left, e_right, controlled = residual_fields(sigma_l, aligned["warped"], aligned["omega"],
                                                  mu_l, mu_w, covariates)
    if mean_left is None:  # no seed mean: show the variance field itself
        mean_left = np.repeat(np.sqrt(np.maximum(sigma_l, 0))[..., None], 3, axis=-1)
    return mean_left, e_left, e_right, controlled


def strongest_section(corr, nulls, *, variance=(), warped=(), ground_truth=(), figure=None,
                      analysis=None) -> dict | None:
    """Where the cue is strongest (:mod:`stereovar.audit.strongest`): the frames ranked, the
    tiles of the top :data:`~stereovar.audit.strongest.TOP_FRAMES` frames whose stores are
    given, and their figure written to ``figure``. None without correlation rows."""
    from ..audit.strongest import NULL_OFFSETS, TILE, TOP_FRAMES, frame_ranking, rank_tiles
    from ..figures.strongest import strongest_figure
    from .common import save_figure

    ranking = frame_ranking(corr, nulls)
    if not ranking:
        if figure:  # the rule declares it: say there is nothing to rank
            save_figure(strongest_figure([], tile=TILE), figure, dpi=100)
        return None
    min_pixels = int(dict(analysis or {}).get("min_pixels", 30))
    stores = [_scene_paths(p) for p in (variance, warped, ground_truth)]
    shown, tiles, controlled = [], [], True
    for r in ranking:
        if len(shown) == TOP_FRAMES:
            break
        paths = [s.get(r["frame"]) for s in stores]
        if paths[0] is None or paths[1] is None or not math.isfinite(r["value"]):
            continue
        image, e_left, e_right, ok = frame_residuals(*paths)
        controlled &= ok
        rows, summary = rank_tiles(e_left, e_right, frame=r["frame"], min_pixels=min_pixels)
        log.info("%s: %d of %d tiles above the null at their rank", r["frame"],
                 summary["n_stand_out"], summary["n_tiles"])
        tiles += rows
        shown.append({"frame": r["frame"], "image": image, "rho": summary["rho"], "rows": rows,
                      "e_left": e_left, "e_right": e_right, "n_tiles": summary["n_tiles"],
                      "n_stand_out": summary["n_stand_out"]})
    by = ("the intensity-controlled :math:`\\rho` minus its matched null"
          if ranking[0]["statistic"] == "difference"
          else "the intensity-controlled :math:`\\rho` (no matched null for these frames)")
    text = f"Frames ranked by {by}, with its 95% interval."
    if shown:
        residual = (
            "the :math:`\\ln\\sigma^2` residuals after intensity" if controlled
            else ":math:`\\ln\\sigma^2` (no seed mean: no intensity control)"
        )
        text += (
            f" Within the top {len(shown)} frame{'s' * (len(shown) != 1)}, {TILE}×{TILE} px "
            f"tiles ranked by the local correlation of {residual} across the views, each "
            "beside the null at its rank: the same ranking with the right field moved far "
            "out of line. A tile stands out when it is above the null's critical value at its "
            f"rank (a Monte Carlo test at 5% over {NULL_OFFSETS} offsets). Tiles standing out: "
            + "; ".join(f"{f['frame']} {f['n_stand_out']} of {f['n_tiles']}" for f in shown)
            + ". A tile's interval is its :math:`\\rho` plus or minus 1.96 times the null "
            "tiles' standard deviation."
        )
    if figure:
        save_figure(strongest_figure(shown, tile=TILE), figure, dpi=100)
    return {"text": text, "ranking": ranking, "tiles": tiles,
            "frames": [{k: f[k] for k in ("frame", "n_tiles", "n_stand_out")} for f in shown]}


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
    dose=None,
    probe=None,
    probe_figure=None,
    calibration=None,
    nulls=None,
    statistics_figure=None,
    variance=(),
    warped=(),
    ground_truth=(),
    analysis=None,
    config_digest: str = "",
) -> dict:
    """Write ``results/audit/{name}/verdict.{md,html}`` and ``summary.json``.

    The page (:mod:`stereovar.audit.page`) opens with a traffic light and what to do
    (:func:`stereovar.audit.decision.decision`), then what was imported (each frame's
    import record: seeds, files, the sign check, the warnings) with every warning and flag
    (:func:`stereovar.audit.flags.control_flags`) as a row of its own and one thumbnail
    per frame, then the details: the claims-style rows over the audit's frames with
    intervals, the plain-language verdict, whether the views share their random streams
    (``seeding``: :func:`seeding_job`), the teasers and, with ``mitigations`` (the audit's
    mitigation table), which mitigation removes the Monte Carlo-specific part and at what
    cost (:func:`stereovar.statistics.mitigations.mitigation_findings`), and its figure; with
    ``dose`` (the audit's dose-response table), the budget and camera at which ``sensor_only``
    removes it (:func:`stereovar.statistics.dose_response.dose_findings`); with
    ``probe`` (``audit.probe: true``), the learned probe's verdict paragraph and figure; with
    ``calibration`` and ``nulls`` (the audit's calibration table and matched nulls,
    :mod:`stereovar.calibration`), the Monte Carlo-specific row the verdict rests on, the
    encoding its matched null was drawn through, as the frames' ``variance`` stores say
    (:func:`stereovar.audit.verdict.null_encoding`), and the calibration's sentence; with
    ``statistics_figure`` (the run's ``statistics_dots.png``), every statistic against its
    controls; with the frames' ``variance``, ``warped`` and ``ground_truth`` stores, where
    the cue is strongest (:func:`strongest_section`: the frames ranked, the top tiles of the
    top frames, and their figure at ``outputs["strongest"]`` when given). Every figure has a
    caption that says what it shows (:data:`stereovar.audit.page.CAPTIONS`). ``summary.json``
    carries ``schema_version`` and is validated against its schema before it is written
    (:mod:`stereovar.audit.summary_schema`). The page opens with what to do and a "What these
    numbers mean" box (:func:`stereovar.audit.plain.meaning_items`); the HTML page embeds its
    images, and both pages and ``summary.json`` carry the provenance
    (:func:`stereovar.provenance.provenance`: the stereovar version, the date, the SHA-256
    over the imported files' recorded SHA-256s and ``config_digest``, the config's)."""
    from ..audit.decision import decision
    from ..audit.flags import control_flags
    from ..audit.page import (
        caption,
        import_flags,
        page_sections,
        to_html_page,
        to_markdown_page,
    )
    from ..audit.seeding import seeding_finding, seeding_rows
    from ..audit.strongest import TILE
    from ..audit.summary_schema import SUMMARY_SCHEMA_VERSION, validate_summary
    from ..audit.verdict import (
        RULES,
        SPECIFIC,
        VERDICT_COLUMNS,
        as_table,
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
        from ..calibration.sentences import VERDICT_COVERAGE_SHOWN, headline

        calibrated = headline(read_rows(calibration), shown=VERDICT_COVERAGE_SHOWN)
    result = verdict(rows)
    encoded = ""
    if result["matched_null"] and variance:  # what the null was drawn through (its stores)
        from ..audit.verdict import null_encoding
        from ..io.store import open_dataset

        encoded = null_encoding([dict(open_dataset(p).attrs) for p in variance], records)
        result = {**result, "text": f"{result['text']} {encoded}"}
    if calibrated:
        result = {**result, "text": f"{result['text']} {calibrated}"}
    shared = seeding_finding(residual)
    flags = import_flags(records) + control_flags(rows, corr)
    findings = []
    if mitigations:
        from ..statistics.mitigations import mitigation_findings

        findings = mitigation_findings(read_rows(mitigations))
    budgets = []
    if dose:  # what sensor_only ships over the budget and the camera, on these frames
        from ..statistics.dose_response import dose_findings

        budgets = dose_findings(read_rows(dose))
    opening = decision(result, shared, flags, findings, rows, dose=budgets)
    lines = summary_lines(name, found, rows, result)
    lines.insert(0, f"{opening['light'].upper()}: {opening['headline']}")
    lines.append(f"  seeding: {shared['text']}")
    if calibrated or encoded:  # the matched null's encoding, then how it calibrates
        lines.append("  calibration: " + " ".join(t for t in (encoded, calibrated) if t))
    lines += [f"  flag: {f['text']}" for f in flags]
    if findings:
        lines.append(f"mitigations: {findings[-1]}")
    if budgets and findings and findings[-1].startswith("No mitigation"):
        lines.append(f"what removes it: {opening['sentences'][-1].split('To remove it: ')[-1]}"
                     if "To remove it: " in opening["sentences"][-1] else
                     f"what removes it: {budgets[0]}")
    for line in lines:
        log.info("%s", line)
    table = as_table(rows)
    base = Path(outputs["md"]).parent

    def relative(path):
        return Path(path).relative_to(base).as_posix()

    def frame_of(path):
        return Path(path).stem.split("_", 1)[-1]

    figures = [(relative(t), caption("teaser", frame=frame_of(t))) for t in teasers]
    if mitigation_figure:
        figures.append((relative(mitigation_figure), caption("mitigations")))
    probe_result = json.loads(Path(probe).read_text()) if probe else None
    if probe_figure:
        figures.append((relative(probe_figure), caption("probe")))
    if probe_result:
        lines.append(f"probe: {probe_result['paragraph']}")
    strongest = strongest_section(
        corr, null_rows, variance=variance, warped=warped, ground_truth=ground_truth,
        figure=outputs.get("strongest"), analysis=analysis,
    )
    if strongest and strongest["frames"] and outputs.get("strongest"):
        strongest["figure"] = (relative(outputs["strongest"]),
                               caption("strongest", tile=TILE))
    from ..audit.plain import meaning_items
    from ..provenance import provenance

    origin = provenance(
        {path: entry["sha256"] for record in records
         for path, entry in (record.get("files") or {}).items() if entry.get("sha256")},
        config_digest,
    )
    sections = page_sections(
        name=name,
        found=found,
        decision=opening,
        result=result,
        seeding=shared,
        records=records,
        flags=flags,
        table=table,
        caption=f"Audit {name}: {found}. Every statistic over the frames, with its 95% "
        "interval and the control it is read against. rho values are correlations (-1 to 1); "
        "C_sigma rows are shares of pixels.",
        mitigations=findings,
        thumbnails=[(relative(t), caption("thumbnail", frame=frame_of(t))) for t in thumbnails],
        figures=figures,
        probe=probe_result["paragraph"] if probe_result else "",
        statistics=(relative(statistics_figure), caption("statistics"))
        if statistics_figure
        else None,
        strongest=strongest,
        meaning=meaning_items(rows, result),
        provenance=origin,
    )
    specific = next((r for r in table if r["quantity"] == SPECIFIC and r["region"] == "all"),
                    {})
    summary = {
        "schema_version": SUMMARY_SCHEMA_VERSION,
        "audit": name,
        "found": found,
        "mc_specific_rho": {
            **_json_numbers([{k: specific.get(k, math.nan)
                              for k in ("value", "low", "high", "null")}])[0],
            "interval": "95%: the frames' spatial block-bootstrap intervals combined, with the "
            "matched null's standard error",
            "light": opening["light"],
        },
        "provenance": origin,
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
        "rows": _json_numbers(table),
        "csv": to_csv(table, VERDICT_COLUMNS),
        "strongest": {
            "frames": _json_numbers(strongest["ranking"]),
            "tiles": _json_numbers(strongest["tiles"]),
        }
        if strongest
        else None,
    }
    validate_summary(summary)
    md, page = to_markdown_page(sections), to_html_page(sections, base=base)
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
