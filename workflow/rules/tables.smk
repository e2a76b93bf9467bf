# Table 1 (cross-scene correlation) and Table 2 (SPP sweep), paper Sec. 3.2-3.3, per renderer
# and estimator.


rule cross_scene_table:
    input:
        scene_files(layout.correlation_rows),
    output:
        **table_outputs(
            layout.run_tables("{renderer}", "{estimator}", "cross_scene"),
            caption="../report/cross_scene.rst",
            category="Tables",
            labels={
                "table": "Table 1: cross-scene correlation",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    params:
        spp=MAIN_SPP,
    log:
        "logs/{renderer}/{estimator}/tables/cross_scene.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/tables/cross_scene.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/cross_scene_table.py"


rule spp_sweep_table:
    input:
        correlations=sweep_inputs(layout.correlation_rows),
        variances=sweep_inputs(layout.variance_store),
        warped=sweep_inputs(layout.warped_store),
    output:
        **table_outputs(
            layout.run_tables("{renderer}", "{estimator}", "spp_sweep"),
            caption="../report/spp_sweep.rst",
            category="Tables",
            labels={
                "table": "Table 2: SPP sweep",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
        **table_outputs(
            layout.run_tables("{renderer}", "{estimator}", "spp_sweep_fit"),
            prefix="fit_",
            caption="../report/spp_sweep_fit.rst",
            category="Tables",
            labels={
                "table": "Table 2: log-log slope",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    log:
        "logs/{renderer}/{estimator}/tables/spp_sweep.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/tables/spp_sweep.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/spp_sweep_table.py"


# The renderers of `renderers:` side by side (one scene list, the main SPP, the configured
# estimator).


rule cross_renderer_table:
    input:
        **cross_renderer_inputs(layout.correlation_rows, SCENES),
    output:
        **table_outputs(
            layout.cross_renderer_tables(),
            caption="../report/cross_renderer.rst",
            category="Tables",
            labels={"table": "cross-renderer comparison"},
        ),
    params:
        spp=MAIN_SPP,
        renderers=RENDERER_RUNS,
    log:
        "logs/tables/cross_renderer.log",
    benchmark:
        "benchmarks/tables/cross_renderer.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/cross_renderer_table.py"
