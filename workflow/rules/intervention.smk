# The residual-shuffle intervention of paper Sec. 3.4: per-scene metrics and Table 3. It
# splits the N seeds into mean and residuals, so its results sit with the seeds estimator's.


rule intervention:
    input:
        unpack(intervention_inputs),
    output:
        metrics="results/{renderer}/seeds/intervention/{scene}.csv",
        margins="results/{renderer}/seeds/intervention/margins/{scene}.csv",
    params:
        **{k: v for k, v in config["intervention"].items() if k not in ("n_seeds", "spp")},
        sensor=config["controls"]["sensor"],
    log:
        "logs/{renderer}/seeds/intervention/{scene}.log",
    benchmark:
        "benchmarks/{renderer}/seeds/intervention/{scene}.tsv"
    threads: 2
    resources:
        **intervention_resources(),
    conda:
        ENV
    script:
        "../scripts/intervention.py"


rule intervention_table:
    input:
        scene_files("{run}/intervention/{scene}.csv", estimator=INTERVENTION_ESTIMATOR),
    output:
        csv="results/{renderer}/seeds/tables/intervention.csv",
        md="results/{renderer}/seeds/tables/intervention.md",
        tex="results/{renderer}/seeds/tables/intervention.tex",
        html=report(
            "results/{renderer}/seeds/tables/intervention.html",
            caption="../report/intervention.rst",
            category="Tables",
            labels={
                "table": "Table 3: intervention",
                "renderer": "{renderer}",
                "estimator": INTERVENTION_ESTIMATOR,
            },
        ),
    log:
        "logs/{renderer}/seeds/tables/intervention.log",
    benchmark:
        "benchmarks/{renderer}/seeds/tables/intervention.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/intervention_table.py"


rule margin_figure:
    input:
        scene_files("{run}/intervention/margins/{scene}.csv", estimator=INTERVENTION_ESTIMATOR),
    output:
        report(
            "results/{renderer}/seeds/figures/fig4_intervention_margins.png",
            caption="../report/fig4_intervention_margins.rst",
            category="Figures",
            labels={
                "figure": "Fig. 4: GT-margin distributions",
                "renderer": "{renderer}",
                "estimator": INTERVENTION_ESTIMATOR,
            },
        ),
    log:
        "logs/{renderer}/seeds/figures/fig4_intervention_margins.log",
    benchmark:
        "benchmarks/{renderer}/seeds/figures/fig4_intervention_margins.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/margin_figure.py"
