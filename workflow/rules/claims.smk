# Every statistic and control across scenes, rho against the number of seeds, and the claims
# table with results/summary.json (the run's headline numbers with their intervals).
from stereovar.statistics.claims import claims_digest


rule statistics_table:
    input:
        correlations=scene_files("{run}/correlation/{scene}/spp{spp}.csv"),
        curves=scene_files("{run}/correlation/{scene}/spp{spp}_curve.csv"),
    output:
        csv="results/{renderer}/{estimator}/tables/statistics.csv",
        md="results/{renderer}/{estimator}/tables/statistics.md",
        tex="results/{renderer}/{estimator}/tables/statistics.tex",
        html=report(
            "results/{renderer}/{estimator}/tables/statistics.html",
            caption="../report/statistics.rst",
            category="Tables",
            labels={
                "table": "Statistics and controls with intervals",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
        curve_csv="results/{renderer}/{estimator}/tables/seed_curve.csv",
        curve_md="results/{renderer}/{estimator}/tables/seed_curve.md",
        curve_tex="results/{renderer}/{estimator}/tables/seed_curve.tex",
        curve_html=report(
            "results/{renderer}/{estimator}/tables/seed_curve.html",
            caption="../report/seed_curve.rst",
            category="Tables",
            labels={
                "table": "rho against the number of seeds",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    params:
        spp=MAIN_SPP,
    log:
        "logs/{renderer}/{estimator}/tables/statistics.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/tables/statistics.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/statistics_table.py"


rule claims:
    input:
        correlations=expand(
            "{run}/correlation/{scene}/spp{spp}.csv", run=RUN, scene=SCENES, spp=MAIN_SPP
        ),
        curves=expand(
            "{run}/correlation/{scene}/spp{spp}_curve.csv", run=RUN, scene=SCENES, spp=MAIN_SPP
        ),
        sweep=f"{RUN}/tables/spp_sweep.csv",
        interventions=expand("{run}/intervention/{scene}.csv", run=INTERVENTION_RUN, scene=SCENES),
        # the mitigation table, when mitigations.names asks for one
        mitigations=mitigation_targets()[:1],
    output:
        csv="results/tables/claims.csv",
        md="results/tables/claims.md",
        tex="results/tables/claims.tex",
        html=report(
            "results/tables/claims.html",
            caption="../report/claims.rst",
            category="1. Claims",
            labels={"table": "Claims of the paper on this run"},
        ),
        summary="results/summary.json",
    params:
        spp=MAIN_SPP,
        # the paper's claims are package data: a changed file reruns the table
        claims_digest=claims_digest(),
    log:
        "logs/tables/claims.log",
    benchmark:
        "benchmarks/tables/claims.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/claims.py"


rule rho_vs_seeds_figure:
    input:
        "results/{renderer}/{estimator}/tables/seed_curve.csv",
    output:
        report(
            "results/{renderer}/{estimator}/figures/rho_vs_seeds.png",
            caption="../report/fig_rho_vs_seeds.rst",
            category="Figures",
            labels={
                "figure": "rho against the number of seeds",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    log:
        "logs/{renderer}/{estimator}/figures/rho_vs_seeds.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/figures/rho_vs_seeds.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/rho_vs_seeds_figure.py"


rule statistics_dot_figure:
    input:
        scene_files("{run}/correlation/{scene}/spp{spp}.csv"),
    output:
        report(
            "results/{renderer}/{estimator}/figures/statistics_dots.png",
            caption="../report/fig_statistics_dots.rst",
            category="Figures",
            labels={
                "figure": "every statistic and control per scene",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    params:
        spp=MAIN_SPP,
    log:
        "logs/{renderer}/{estimator}/figures/statistics_dots.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/figures/statistics_dots.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/statistics_dot_figure.py"
