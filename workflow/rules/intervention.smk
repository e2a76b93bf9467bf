# The residual-shuffle intervention of paper Sec. 3.4: per-scene metrics and Table 3. It
# splits the N seeds into mean and residuals, so its results sit with the seeds estimator's.


rule intervention:
    input:
        unpack(intervention_inputs),
    output:
        metrics=INTERVENTION_RUN + "/intervention/{scene}.csv",
        margins=INTERVENTION_RUN + "/intervention/margins/{scene}.csv",
    params:
        **config["intervention"],
    log:
        f"logs/{{renderer}}/{INTERVENTION_ESTIMATOR}/intervention/{{scene}}.log",
    benchmark:
        f"benchmarks/{{renderer}}/{INTERVENTION_ESTIMATOR}/intervention/{{scene}}.tsv"
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
        csv=report(
            INTERVENTION_RUN + "/tables/intervention.csv",
            caption="../report/intervention.rst",
            category="Tables",
            labels={
                "table": "Table 3: intervention",
                "renderer": "{renderer}",
                "estimator": INTERVENTION_ESTIMATOR,
            },
        ),
        md=INTERVENTION_RUN + "/tables/intervention.md",
        tex=INTERVENTION_RUN + "/tables/intervention.tex",
    log:
        f"logs/{{renderer}}/{INTERVENTION_ESTIMATOR}/tables/intervention.log",
    benchmark:
        f"benchmarks/{{renderer}}/{INTERVENTION_ESTIMATOR}/tables/intervention.tsv"
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
            INTERVENTION_RUN + "/figures/fig4_intervention_margins.png",
            caption="../report/fig4_intervention_margins.rst",
            category="Figures",
            labels={
                "figure": "Table 3: GT-margin distributions",
                "renderer": "{renderer}",
                "estimator": INTERVENTION_ESTIMATOR,
            },
        ),
    log:
        f"logs/{{renderer}}/{INTERVENTION_ESTIMATOR}/figures/fig4_intervention_margins.log",
    benchmark:
        f"benchmarks/{{renderer}}/{INTERVENTION_ESTIMATOR}/figures/fig4_intervention_margins.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/margin_figure.py"
