# The learned probe (stereovar.probe): MC-CNN fast trained on single renders of each training
# condition, cross-validated over scenes, tested on counterfactual inputs; then
# results/tables/probe.*, its figure and the verdict. Not part of `all`: `snakemake -j2 probe`.


# One network: condition (the source key), fold and training seed.
rule probe_train:
    input:
        unpack(probe_train_inputs),
    output:
        layout.probe_network("{renderer}", "{spp}", "{fold}", "{train_seed}"),
    params:
        scenes=lambda wc: probe_folds()[int(wc.fold)][0],
        condition=lambda wc: PROBE_KEYS[(wc.renderer, wc.spp)].name,
        fold=lambda wc: int(wc.fold),
        seed=lambda wc: int(PROBE["seed"]) + int(wc.train_seed),
        training=PROBE["training"],
    log:
        "logs/{renderer}/probe/spp{spp}/train/fold{fold}/seed{train_seed}.log",
    benchmark:
        "benchmarks/{renderer}/probe/spp{spp}/train/fold{fold}/seed{train_seed}.tsv"
    threads: PROBE["training"]["threads"]
    resources:
        **analysis_resources(images=2 * N_SEEDS * len(SCENES) + 8, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/probe_train.py"


# Every network of the condition and of the control for one fold, on the fold's held-out
# scenes rendered under the condition, on every counterfactual input.
rule probe_test:
    input:
        unpack(probe_test_inputs),
    output:
        layout.probe_tiles("{renderer}", "{spp}", "{fold}"),
    params:
        scenes=lambda wc: probe_folds()[int(wc.fold)][1],
        tested=lambda wc: PROBE_KEYS[(wc.renderer, wc.spp)].name,
        test={
            "test_frames": PROBE["test_frames"],
            "block": config["intervention"]["block"],
            "shuffle_seed": config["intervention"]["seed"],
            "conflict_shift": PROBE["conflict_shift"],
            "tile": config["analysis"]["bootstrap"]["tile"],
            "gain": config["controls"]["sensor"]["gain"],
            "read_noise": config["controls"]["sensor"]["read_noise"],
            "seed": PROBE["seed"],
        },
        max_disparity_fixed=config["intervention"]["max_disparity"],
        disparity_margin=config["intervention"]["disparity_margin"],
        threads=1,
    log:
        "logs/{renderer}/probe/spp{spp}/test/fold{fold}.log",
    benchmark:
        "benchmarks/{renderer}/probe/spp{spp}/test/fold{fold}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=4 * N_SEEDS * len(SCENES) + 16, n_reads=2 * N_SEEDS),
    conda:
        ENV
    script:
        "../scripts/probe_test.py"


rule probe_table:
    input:
        probe_tile_files(),
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
        figure=report(
            PROBE_FIGURE,
            caption="../report/probe_figure.rst",
            category="Figures",
            labels={"figure": "learned probe"},
        ),
        verdict=PROBE_VERDICT,
    params:
        reps=PROBE["reps"],
        seed=PROBE["seed"],
        source=PROBE_SOURCE,
        runs=[{"condition": r.name, "spp": r.spp} for r in PROBE_RUNS.values()],
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
