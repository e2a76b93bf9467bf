# The residual-shuffle intervention of paper Sec. 3.4: per-scene metrics and Table 3. It
# splits the N seeds into mean and residuals, so its results sit with the seeds estimator's.


rule intervention:
    input:
        unpack(intervention_inputs),
    output:
        metrics=layout.intervention_metrics("{renderer}", INTERVENTION_ESTIMATOR, "{scene}"),
        margins=layout.intervention_margins("{renderer}", INTERVENTION_ESTIMATOR, "{scene}"),
    params:
        **{k: v for k, v in config["intervention"].items() if k not in ("n_seeds", "spp")},
        sensor=config["controls"]["sensor"],
        bootstrap=config["analysis"]["bootstrap"],
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
        scene_results(layout.intervention_metrics, estimator=INTERVENTION_ESTIMATOR),
    output:
        **table_outputs(
            layout.run_tables("{renderer}", INTERVENTION_ESTIMATOR, "intervention"),
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
        scene_results(layout.intervention_margins, estimator=INTERVENTION_ESTIMATOR),
    output:
        report(
            layout.run_figure("{renderer}", INTERVENTION_ESTIMATOR, "fig4_intervention_margins"),
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
