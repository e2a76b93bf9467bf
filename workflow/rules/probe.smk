# The learned probe (stereovar.probe): per architecture (MC-CNN fast, a small cost-volume
# network), every training condition's networks and their cue-blind twins, cross-validated over
# scenes and tested on counterfactual inputs; a planted cue of known strength is the positive
# control; then results/tables/probe.*, probe_training.*, its figure and the verdict.
# Not part of `all`: `snakemake -j2 probe`.


wildcard_constraints:
    condition=PROBE_CONDITION_PATTERN,
    arch=PROBE_ARCH_PATTERN,
    variant="main|twin",


# The renders' strength and each scene's camera law: the planted cue's settings.
rule probe_planted:
    input:
        unpack(probe_planted_inputs),
    output:
        PROBE_PLANTED,
    params:
        scenes=SCENES,
        factors=sorted({c.factor for c in PROBE_CONDITIONS.values() if c.planted}),
    log:
        f"logs/{PROBE_SOURCE}/probe/planted.log",
    resources:
        **analysis_resources(images=4 * N_SEEDS + 8, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/probe_planted.py"


# The networks of one condition, architecture and fold: per variant (the network and its
# cue-blind twin), one per training seed, each trained to a plateau of validation accuracy
# (the twin as many steps as its network); the control sensor_only has no twin.
rule probe_train:
    input:
        unpack(probe_train_inputs),
    output:
        [
            layout.probe_network(PROBE_SOURCE, "{condition}", "{arch}", v, "{fold}", j)
            for v in ("main", "twin")
            for j in PROBE_SEEDS
        ],
    wildcard_constraints:
        condition=PROBE_TWINNED_PATTERN,
    params:
        scenes=lambda wc: probe_folds()[int(wc.fold)][0],
        condition=lambda wc: wc.condition,
        arch=lambda wc: wc.arch,
        variants=lambda wc: PROBE_CONDITIONS[wc.condition].variants,
        fold=lambda wc: int(wc.fold),
        seeds=[int(PROBE["seed"]) + j for j in PROBE_SEEDS],
        training=lambda wc: PROBE[architecture(wc.arch).config_key],
        factor=lambda wc: PROBE_CONDITIONS[wc.condition].factor,
        shipped=lambda wc: probe_shipped(wc.condition),
        strata=PROBE["strata"],
        planted_seed=PROBE["seed"],
        validation_rows=PROBE["validation_rows"],
        device=PROBE["device"],
    log:
        f"logs/{PROBE_SOURCE}/probe/{{condition}}/{{arch}}/train/fold{{fold}}.log",
    benchmark:
        f"benchmarks/{PROBE_SOURCE}/probe/{{condition}}/{{arch}}/train/fold{{fold}}.tsv"
    threads: PROBE["training"]["threads"]
    resources:
        **analysis_resources(images=2 * N_SEEDS * len(SCENES) + 8, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/probe_train.py"


# The control's networks of one architecture and fold, without a twin (judged, sensor_only
# trains as sensor_only_shipped through probe_train).
if PROBE_CONTROL_UNTWINNED:

    use rule probe_train as probe_train_control with:
        output:
            [
                layout.probe_network(PROBE_SOURCE, "{condition}", "{arch}", "main", "{fold}", j)
                for j in PROBE_SEEDS
            ],
        wildcard_constraints:
            condition=re.escape(PROBE_CONTROL),


# Every network of the condition, its twins and the control's for one architecture and fold,
# on the fold's held-out scenes under the condition, on every counterfactual input.
rule probe_test:
    input:
        unpack(probe_test_inputs),
    output:
        layout.probe_tiles(PROBE_SOURCE, "{condition}", "{arch}", "{fold}"),
    params:
        scenes=lambda wc: probe_folds()[int(wc.fold)][1],
        tested=lambda wc: wc.condition,
        arch=lambda wc: wc.arch,
        factor=lambda wc: PROBE_CONDITIONS[wc.condition].factor,
        shipped=lambda wc: probe_shipped(wc.condition),
        planted_seed=PROBE["seed"],
        test={
            "test_frames": PROBE["test_frames"],
            "strata": PROBE["strata"],
            "shuffle_seed": config["intervention"]["seed"],
            "conflict_shift": PROBE["conflict_shift"],
            "tile": config["analysis"]["bootstrap"]["tile"],
            "seed": PROBE["seed"],
        },
        max_disparity_fixed=config["intervention"]["max_disparity"],
        disparity_margin=config["intervention"]["disparity_margin"],
        threads=1,
        device=PROBE["device"],
    log:
        f"logs/{PROBE_SOURCE}/probe/{{condition}}/{{arch}}/test/fold{{fold}}.log",
    benchmark:
        f"benchmarks/{PROBE_SOURCE}/probe/{{condition}}/{{arch}}/test/fold{{fold}}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=4 * N_SEEDS * len(SCENES) + 16, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/probe_test.py"


rule probe_table:
    input:
        unpack(probe_table_inputs),
    output:
        csv=PROBE_TABLES[0],
        md=PROBE_TABLES[1],
        tex=PROBE_TABLES[2],
        html=report(
            PROBE_TABLES[3],
            caption="../report/probe.rst",
            category="Tables",
            labels={"table": "learned probe"},
        ),
        training_csv=PROBE_TRAINING_TABLES[0],
        training_md=PROBE_TRAINING_TABLES[1],
        training_tex=PROBE_TRAINING_TABLES[2],
        training_html=PROBE_TRAINING_TABLES[3],
        figure=report(
            PROBE_FIGURE,
            caption="../report/probe_figure.rst",
            category="Figures",
            labels={"figure": "learned probe"},
        ),
        verdict=PROBE_VERDICT,
    params:
        source=PROBE_SOURCE,
        n_seeds=N_SEEDS,
        runs=[
            {"condition": c.name, "spp": c.run.spp, "planted": c.factor}
            for c in PROBE_CONDITIONS.values()
        ],
    log:
        f"logs/{PROBE_SOURCE}/tables/probe.log",
    benchmark:
        f"benchmarks/{PROBE_SOURCE}/tables/probe.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/probe_table.py"


rule probe:
    input:
        probe_targets(),
    localrule: True
