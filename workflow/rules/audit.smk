# An audit of renders made elsewhere (config section `audit:`): common.smk only finds its
# files (stereovar.audit.run.discover_audit: nothing is read or written while the workflow is
# parsed); `audit_import` imports each frame in a job of its own, and every rule downstream of
# the renders runs on the stores under results/audit/{name}/. These rules add one teaser per
# frame and the verdict page. `export` writes this project's renders, variance fields and
# disparity as files other tools (and the audit) read.


if AUDIT:

    # One job per frame. Snakemake imports a frame again when one of its files is newer
    # than its stores (unless its bytes are those it recorded: --max-checksum-file-size,
    # profiles/default), when the import settings change, or when the fingerprint does.
    rule audit_import:
        wildcard_constraints:
            scene=frame_pattern(AUDIT_DISCOVERY),
        input:
            lambda wc: frame_files(AUDIT_DISCOVERY, wc.scene),
        output:
            **{
                # the record is kept until the job replaces it: the job's own process
                # reads it to give the fingerprint Snakemake planned with
                key: update(path) if key == "record" else directory(path)
                for key, path in import_outputs(AUDIT, AUDIT_DISCOVERY.n_seeds).items()
            },
        params:
            # the digest of the settings as the import applies them: reordering the audit:
            # keys or writing a default out reruns nothing (the job reads config["audit"])
            settings=import_params(AUDIT),
            # changes when a file is replaced keeping its size and mtime (cp -p), not when
            # it is only touched (stereovar.audit.hashing.frame_fingerprint)
            fingerprint=lambda wc: import_fingerprint(AUDIT, AUDIT_DISCOVERY, wc.scene),
        log:
            f"logs/audit/{AUDIT['name']}/import/{{scene}}.log",
        benchmark:
            f"benchmarks/audit/{AUDIT['name']}/import/{{scene}}.tsv"
        threads: 2
        conda:
            ENV
        script:
            "../scripts/audit_import.py"


# Do the two views share their random streams? The per-seed residuals' cross-view
# correlation at zero disparity and at the ground-truth disparity.
rule audit_seeding:
    input:
        unpack(audit_frame_inputs),
    output:
        layout.audit_seeding("{name}", "{scene}"),
    params:
        analysis=config["analysis"],
        controls=config["controls"],
    log:
        "logs/audit/{name}/seeding/{scene}.log",
    benchmark:
        "benchmarks/audit/{name}/seeding/{scene}.tsv"
    conda:
        ENV
    script:
        "../scripts/audit_seeding.py"


# One render and the disparity per frame: the reader sees that the right files were read.
rule audit_thumbnail:
    input:
        unpack(audit_frame_inputs),
    output:
        layout.audit_thumbnail("{name}", "{scene}"),
    log:
        "logs/audit/{name}/figures/thumbnail_{scene}.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/audit_thumbnail.py"


rule audit_teaser:
    input:
        variance=lambda wc: layout.variance_store(
            layout.audit_source(wc.name), "seeds", wc.scene, MAIN_SPP
        ),
        warped=lambda wc: layout.warped_store(
            layout.audit_source(wc.name), "seeds", wc.scene, MAIN_SPP
        ),
    output:
        report(
            layout.audit_teaser("{name}", "{scene}"),
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
        unpack(audit_verdict_stores),
        correlations=lambda wc: [
            layout.correlation_rows(layout.audit_source(wc.name), "seeds", s, MAIN_SPP)
            for s in SCENES
        ],
        interventions=lambda wc: [
            layout.intervention_metrics(layout.audit_source(wc.name), "seeds", s) for s in SCENES
        ],
        teasers=lambda wc: [layout.audit_teaser(wc.name, s) for s in SCENES],
        thumbnails=lambda wc: [layout.audit_thumbnail(wc.name, s) for s in SCENES],
        seeding=lambda wc: [layout.audit_seeding(wc.name, s) for s in SCENES],
        imports=lambda wc: [layout.import_record(wc.name, s) for s in SCENES],
        # audit.mitigations: the mitigation table and its figure
        mitigations=mitigation_targets()[:1],
        mitigation_figure=mitigation_targets()[-1:],
        # the dose-response of sensor_only when audit.mitigations measures it
        dose=dose_response_targets()[:1],
        # audit.probe: the learned probe's verdict and figure
        probe=probe_targets()[-1:],
        probe_figure=probe_targets()[-2:-1],
        # the calibration: its table's sentence and the matched nulls the verdict rests on
        calibration=CALIBRATION_TABLES[0],
        nulls=CALIBRATION_NULLS,
    output:
        md=layout.audit_verdict("{name}", "md"),
        html=report(
            layout.audit_verdict("{name}", "html"),
            caption="../report/audit_verdict.rst",
            category="1. Claims",
            labels={"audit": "{name}", "table": "verdict"},
        ),
        summary=layout.audit_summary("{name}"),
        strongest=layout.audit_strongest("{name}"),
    params:
        name=lambda wc: wc.name,
        found=AUDIT_FOUND,
        analysis=config["analysis"],
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
        directory(layout.export_dir("{renderer}", "{estimator}", "{format}", "{scene}")),
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
