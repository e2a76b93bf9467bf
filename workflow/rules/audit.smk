# An audit of renders made elsewhere (config section `audit:`): the files are imported in
# common.smk; every rule downstream of the renders runs on them under results/audit/{name}/.
# These rules add one teaser per frame and the verdict page. `export` writes this project's
# renders, variance fields and disparity as files other tools (and the audit) read.


# A dry run imports nothing (common.smk): the stores an import would write or replace are
# the outputs of this rule, which only a dry run has, so it lists the jobs that read them.
if AUDIT_PLANNED:

    rule audit_import:
        input:
            sorted({f for files in AUDIT_PLANNED.values() for f in files}),
        output:
            [directory(store) for store in AUDIT_PLANNED],
            planned_marker(AUDIT),  # never written (stereovar.audit.run.planned_marker)
        log:
            f"logs/audit/{AUDIT['name']}/import.log",
        localrule: True
        run:
            raise SystemExit("stereovar: a dry run imports nothing; run without -n to import")


rule audit_teaser:
    input:
        variance=lambda wc: f"results/audit/{wc.name}/seeds/variance/{wc.scene}/spp{MAIN_SPP}.zarr",
        warped=lambda wc: f"results/audit/{wc.name}/seeds/warped/{wc.scene}/spp{MAIN_SPP}.zarr",
    output:
        report(
            "results/audit/{name}/figures/teaser_{scene}.png",
            caption="../report/audit_teaser.rst",
            category="Audit",
            labels={"audit": "{name}", "frame": "{scene}", "figure": "teaser"},
        ),
    log:
        "logs/audit/{name}/figures/teaser_{scene}.log",
    benchmark:
        "benchmarks/audit/{name}/figures/teaser_{scene}.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/teaser_figure.py"


rule audit_verdict:
    input:
        correlations=lambda wc: [
            f"results/audit/{wc.name}/seeds/correlation/{s}/spp{MAIN_SPP}.csv" for s in SCENES
        ],
        interventions=lambda wc: [
            f"results/audit/{wc.name}/seeds/intervention/{s}.csv" for s in SCENES
        ],
        teasers=lambda wc: [f"results/audit/{wc.name}/figures/teaser_{s}.png" for s in SCENES],
    output:
        md="results/audit/{name}/verdict.md",
        html=report(
            "results/audit/{name}/verdict.html",
            caption="../report/audit_verdict.rst",
            category="1. Claims",
            labels={"audit": "{name}", "table": "verdict"},
        ),
        summary="results/audit/{name}/summary.json",
    params:
        name=lambda wc: wc.name,
        found=AUDIT_FOUND,
    log:
        "logs/audit/{name}/verdict.log",
    benchmark:
        "benchmarks/audit/{name}/verdict.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/audit_verdict.py"


rule export_scene:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
        format="exr|pfm|npy|png",
    input:
        unpack(export_inputs),
    output:
        directory("results/export/{renderer}/{estimator}/{format}/{scene}"),
    params:
        scene=lambda wc: wc.scene,
        format=lambda wc: wc.format,
    log:
        "logs/export/{renderer}/{estimator}/{format}/{scene}.log",
    benchmark:
        "benchmarks/export/{renderer}/{estimator}/{format}/{scene}.tsv"
    conda:
        ENV
    script:
        "../scripts/export.py"


rule export:
    input:
        export_targets(),
    localrule: True
