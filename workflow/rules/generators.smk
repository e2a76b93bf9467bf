# Generator profiles (stereovar.generators; `snakemake generators`, not part of `all`): the
# scenes of `generators.scenes` rendered by Cycles under each generator's own defaults
# (render_profile, under results/cycles/{profile}) and under the paper's (the Cycles renders of
# render.smk), each measured like a mitigation (the variance, warp, correlation and
# mitigation_scene rules on the source key) against its own matched null (generator_calibration),
# then results/tables/generators.* and its figure, with the verdicts' calibration
# (results/tables/generators_calibration.csv).


rule render_profile:
    wildcard_constraints:
        profile="|".join(PROFILES),
    input:
        unpack(scene_inputs),
    output:
        left=directory(
            layout.render_store("cycles", "{scene}", "left", "{spp}", "{batch}", "{profile}")
        ),
        right=directory(
            layout.render_store("cycles", "{scene}", "right", "{spp}", "{batch}", "{profile}")
        ),
    params:
        seeds=lambda wc: batch_seeds(wc.batch),
        spp=lambda wc: int(wc.spp),
        renderer="cycles",
        width=config["resolution"]["width"],
        height=config["resolution"]["height"],
        baseline_m=config["rig"]["baseline_m"],
        convention=config["rig"]["convention"],
        **{
            k: v
            for k, v in render_params().items()
            if k not in ("seed_policy", "renderer_options")
        },
        seed_policy=lambda wc: GENERATOR_ROWS[wc.profile].seed_policy,
        renderer_options=lambda wc: cycles_options(GENERATOR_ROWS[wc.profile].cycles),
    log:
        "logs/cycles/{profile}/renders/{scene}/spp{spp}/seeds{batch}.log",
    benchmark:
        "benchmarks/cycles/{profile}/renders/{scene}/spp{spp}/seeds{batch}.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(gpu=False),
    conda:
        ENV
    script:
        "../scripts/render.py"


rule generator_calibration:
    wildcard_constraints:
        profile="|".join([PAPER, *PROFILES]),
    input:
        unpack(generator_calibration_inputs),
    output:
        layout.generator_calibration_rows("{profile}", "{scene}", "{spp}"),
    params:
        transforms=lambda wc: generator_calibration_transforms(GENERATOR_ROWS[wc.profile]),
        outputs=lambda wc: generator_outputs(GENERATOR_ROWS[wc.profile]),
        options={},
        calibration={
            **config["calibration"],
            "pipelines": [],
            "denoised_replicates": GENERATORS["denoised_replicates"],
        },
        analysis=config["analysis"],
        controls=config["controls"],
        intervention=config["intervention"],
    log:
        "logs/generators/{profile}/calibration/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/generators/{profile}/calibration/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **calibration_resources(),
    conda:
        ENV
    script:
        "../scripts/calibration_scene.py"


rule generators_table:
    input:
        correlation=[p for run in generator_table_params() for p in run["correlation"]],
        scene_rows=[p for run in generator_table_params() for p in run["scene_rows"]],
        calibration=[p for run in generator_table_params() for p in run["calibration"]],
    output:
        csv=layout.generator_tables()[0],
        md=layout.generator_tables()[1],
        tex=layout.generator_tables()[2],
        html=report(
            layout.generator_tables()[3],
            caption="../report/generators.rst",
            category="Tables",
            labels={"table": "generators"},
        ),
        figure=report(
            layout.generator_figure(),
            caption="../report/generators.rst",
            category="Figures",
            labels={"figure": "generators"},
        ),
        calibration=layout.generator_calibration_table(),
    params:
        runs=generator_table_params(),
    log:
        "logs/cycles/tables/generators.log",
    benchmark:
        "benchmarks/cycles/tables/generators.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/generators_table.py"


rule generators:
    input:
        generator_targets(),
    localrule: True
