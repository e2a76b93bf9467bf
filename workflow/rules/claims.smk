# Every statistic and control across scenes, rho against the number of seeds, the claims
# table with results/summary.json (the run's headline numbers with their intervals), and the
# results page results/index.html that shows them with every figure.
from stereovar.statistics.claims import claims_digest


rule statistics_table:
    input:
        correlations=scene_files(layout.correlation_rows),
        curves=scene_files(layout.correlation_curve),
    output:
        **table_outputs(
            layout.run_tables("{renderer}", "{estimator}", "statistics"),
            caption="../report/statistics.rst",
            category="Tables",
            labels={
                "table": "Statistics and controls with intervals",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
        **table_outputs(
            layout.run_tables("{renderer}", "{estimator}", "seed_curve"),
            prefix="curve_",
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
        correlations=[
            layout.correlation_rows(get_renderer(), get_estimator(), s, MAIN_SPP) for s in SCENES
        ],
        curves=[
            layout.correlation_curve(get_renderer(), get_estimator(), s, MAIN_SPP) for s in SCENES
        ],
        sweep=layout.run_tables(get_renderer(), get_estimator(), "spp_sweep")[0],
        interventions=[
            layout.intervention_metrics(get_renderer(), INTERVENTION_ESTIMATOR, s) for s in SCENES
        ],
        # the mitigation table, when mitigations.names asks for one
        mitigations=mitigation_targets()[:1],
        # the probe's verdict, once `snakemake probe` has made it
        probe=probe_if_run()[-1:],
    output:
        **table_outputs(
            layout.claims_tables(),
            caption="../report/claims.rst",
            category="1. Claims",
            labels={"table": "Claims of the paper on this run"},
        ),
        summary=layout.summary_json(),
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
        layout.run_tables("{renderer}", "{estimator}", "seed_curve")[0],
    output:
        report(
            layout.run_figure("{renderer}", "{estimator}", "rho_vs_seeds"),
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
        scene_files(layout.correlation_rows),
    output:
        report(
            layout.run_figure("{renderer}", "{estimator}", "statistics_dots"),
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


rule results_page:
    input:
        claims=layout.claims_tables()[0],
        summary=layout.summary_json(),
        figures=page_results()[0],
        tables=page_results()[1],
        # the mitigation table and its figure, when mitigations.names asks for them
        mitigations=mitigation_targets()[:1],
        mitigation_figure=mitigation_targets()[-1:],
        # what removes it: the dose-response's budget and camera
        dose=dose_response_targets()[:1],
        # the probe's verdict and figure, once `snakemake probe` has made them
        probe=probe_if_run()[-1:],
        probe_figure=probe_if_run()[-2:-1],
        # the generator table and figure, once `snakemake generators` has made them
        generators=generators_if_run()[:-1],
        generators_figure=generators_if_run()[-1:],
        # the calibration's table: its sentence goes under the headline
        calibration=CALIBRATION_TABLES[0],
    output:
        layout.results_page(),
    params:
        captions=page_captions(),
        report=layout.snakemake_report(),
    log:
        "logs/results_page.log",
    benchmark:
        "benchmarks/results_page.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/results_page.py"
