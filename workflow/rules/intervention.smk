# The residual-shuffle intervention of paper Sec. 3.4: per-scene metrics and Table 3.


rule intervention:
    input:
        unpack(lambda wc: scene_renders(wc, spp=MAIN_SPP)),
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        metrics="results/intervention/{scene}.csv",
        margins="results/intervention/margins/{scene}.csv",
    params:
        **config["intervention"],
    log:
        "logs/intervention/{scene}.log",
    benchmark:
        "benchmarks/intervention/{scene}.tsv"
    threads: 2
    resources:
        **intervention_resources(),
    conda:
        ENV
    script:
        "../scripts/intervention.py"


rule intervention_table:
    input:
        expand("results/intervention/{scene}.csv", scene=SCENES),
    output:
        csv=report(
            "results/tables/intervention.csv",
            caption="../report/intervention.rst",
            category="Tables",
            labels={"table": "Table 3: intervention"},
        ),
        md="results/tables/intervention.md",
        tex="results/tables/intervention.tex",
    log:
        "logs/tables/intervention.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/intervention_table.py"


rule margin_figure:
    input:
        expand("results/intervention/margins/{scene}.csv", scene=SCENES),
    output:
        report(
            "results/figures/fig4_intervention_margins.png",
            caption="../report/fig4_intervention_margins.rst",
            category="Figures",
            labels={"figure": "Table 3: GT-margin distributions"},
        ),
    log:
        "logs/figures/fig4_intervention_margins.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/margin_figure.py"
