# Mitigations (stereovar.mitigations): renders after a store transform or rendered under a
# seed policy, each measured like the source's own renders (variance, warp, correlation, the
# intervention: the rules of the other files, on the source key "{renderer}/{transform}"),
# plus the cross-view residual correlation and the image quality against a converged
# reference; then results/tables/mitigations.* and the trade-off figure.


# A render-time policy: the scene rendered anew with the policy's sampler seeds (both views
# of a render share one seed under shared_seed).
rule render_policy:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
    input:
        unpack(scene_inputs),
    output:
        left=directory(
            layout.render_store("{renderer}", "{scene}", "left", "{spp}", "{batch}", "{policy}")
        ),
        right=directory(
            layout.render_store("{renderer}", "{scene}", "right", "{spp}", "{batch}", "{policy}")
        ),
    params:
        seeds=lambda wc: batch_seeds(wc.batch),
        spp=lambda wc: int(wc.spp),
        **rig_params(),
        **{k: v for k, v in render_params().items() if k not in ("variant", "seed_policy")},
        seed_policy=lambda wc: SEED_POLICY_MITIGATIONS[wc.policy],
    log:
        "logs/{renderer}/{policy}/renders/{scene}/spp{spp}/seeds{batch}.log",
    benchmark:
        "benchmarks/{renderer}/{policy}/renders/{scene}/spp{spp}/seeds{batch}.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(),
    conda:
        ENV
    script:
        "../scripts/render.py"


# The denoiser's albedo and normal of one view: one cheap pass of the renderer's AOVs.
rule render_aux:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
    input:
        unpack(scene_inputs),
    output:
        directory(layout.aux_store("{renderer}", "{scene}", "{view}")),
    params:
        view=lambda wc: wc.view,
        spp=AUX_SPP,
        **rig_params(),
    log:
        "logs/{renderer}/renders/{scene}/{view}/aux.log",
    benchmark:
        "benchmarks/{renderer}/renders/{scene}/{view}/aux.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(n_views=1, spp=AUX_SPP),
    conda:
        ENV
    script:
        "../scripts/render_aux.py"


# The one generic rule of every store transform: one batch of one view's renders in, the
# same seeds transformed out (stereovar.transforms; the seed of its draws is recorded).
rule transform:
    wildcard_constraints:
        renderer=SOURCE_NAMES,
    input:
        unpack(transform_inputs),
    output:
        directory(
            layout.render_store("{renderer}", "{scene}", "{view}", "{spp}", "{batch}", "{transform}")
        ),
    params:
        transform=lambda wc: wc.transform,
        batch=lambda wc: batch_seeds(wc.batch),
        view=lambda wc: wc.view,
        seed=MITIGATIONS["seed"],
        options=transform_options,
    log:
        "logs/{renderer}/{transform}/renders/{scene}/{view}/spp{spp}/seeds{batch}.log",
    benchmark:
        "benchmarks/{renderer}/{transform}/renders/{scene}/{view}/spp{spp}/seeds{batch}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=2 * N_SEEDS + 4, n_reads=N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/transform.py"


rule mitigation_scene:
    input:
        unpack(mitigation_scene_inputs),
    output:
        layout.mitigation_rows("{renderer}", MITIGATION_ESTIMATOR, "{scene}", "{spp}"),
    params:
        analysis=config["analysis"],
        controls=config["controls"],
        # the reference inputs: each view's moment store, or the source's render stores
        reference_moments=lambda wc: reference_from_moments(
            layout.split_source_key(wc.renderer)[0]
        ),
    log:
        "logs/{renderer}/seeds/mitigation/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/seeds/mitigation/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=4 * N_SEEDS + 8, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/mitigation_scene.py"


rule mitigations_table:
    input:
        unpack(mitigation_table_inputs),
    output:
        csv=MITIGATION_TABLES[0],
        md=MITIGATION_TABLES[1],
        tex=MITIGATION_TABLES[2],
        html=report(
            MITIGATION_TABLES[3],
            caption="../report/mitigations.rst",
            category="Tables",
            labels={"table": "mitigations"},
        ),
        headline_csv=MITIGATION_HEADLINE[0],
        headline_md=MITIGATION_HEADLINE[1],
        headline_tex=MITIGATION_HEADLINE[2],
        headline_html=MITIGATION_HEADLINE[3],
        figure=report(
            MITIGATION_FIGURE,
            caption="../report/mitigations_figure.rst",
            category="Figures",
            labels={"figure": "mitigations"},
        ),
    params:
        runs=mitigation_table_params(),
    log:
        f"logs/{MITIGATION_SOURCE}/tables/mitigations.log",
    benchmark:
        f"benchmarks/{MITIGATION_SOURCE}/tables/mitigations.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/mitigations_table.py"


rule dose_response_scene:
    wildcard_constraints:
        renderer=SOURCE_NAMES,
    input:
        unpack(dose_response_inputs),
    output:
        layout.dose_response_rows("{renderer}", "{scene}", "{spp}"),
    params:
        transforms=DOSE["transforms"],
        cameras=DOSE["cameras"],
        multiples=DOSE["multiples"],
        replicates=DOSE["replicates"],
        analysis=config["analysis"],
        controls=config["controls"],
        seed=MITIGATIONS["seed"],
    log:
        "logs/{renderer}/seeds/dose_response/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/seeds/dose_response/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=4 * N_SEEDS + 8, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/dose_response_scene.py"


rule dose_response_table:
    input:
        rows=[layout.dose_response_rows(MITIGATION_SOURCE, s, MAIN_SPP) for s in SCENES],
        nulls=layout.calibration_nulls(MITIGATION_SOURCE),
    output:
        csv=DOSE_TABLES[0],
        md=DOSE_TABLES[1],
        tex=DOSE_TABLES[2],
        html=report(
            DOSE_TABLES[3],
            caption="../report/dose_response.rst",
            category="Tables",
            labels={"table": "dose_response"},
        ),
    params:
        spp=MAIN_SPP,
    log:
        f"logs/{MITIGATION_SOURCE}/tables/dose_response.log",
    benchmark:
        f"benchmarks/{MITIGATION_SOURCE}/tables/dose_response.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/dose_response_table.py"


rule mitigations:
    input:
        mitigation_targets(),
    localrule: True
