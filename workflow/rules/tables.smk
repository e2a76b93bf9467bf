# Table 1 (cross-scene correlation) and Table 2 (SPP sweep), paper Sec. 3.2-3.3, per renderer
# and estimator.


rule cross_scene_table:
    input:
        scene_files("{run}/correlation/{scene}/spp{spp}.csv"),
    output:
        csv="results/{renderer}/{estimator}/tables/cross_scene.csv",
        md="results/{renderer}/{estimator}/tables/cross_scene.md",
        tex="results/{renderer}/{estimator}/tables/cross_scene.tex",
        html=report(
            "results/{renderer}/{estimator}/tables/cross_scene.html",
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
        correlations=sweep_inputs("{run}/correlation/{scene}/spp{spp}.csv"),
        variances=sweep_inputs("{run}/variance/{scene}/spp{spp}.zarr"),
        warped=sweep_inputs("{run}/warped/{scene}/spp{spp}.zarr"),
    output:
        csv="results/{renderer}/{estimator}/tables/spp_sweep.csv",
        md="results/{renderer}/{estimator}/tables/spp_sweep.md",
        tex="results/{renderer}/{estimator}/tables/spp_sweep.tex",
        html=report(
            "results/{renderer}/{estimator}/tables/spp_sweep.html",
            caption="../report/spp_sweep.rst",
            category="Tables",
            labels={
                "table": "Table 2: SPP sweep",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
        fit_csv="results/{renderer}/{estimator}/tables/spp_sweep_fit.csv",
        fit_md="results/{renderer}/{estimator}/tables/spp_sweep_fit.md",
        fit_tex="results/{renderer}/{estimator}/tables/spp_sweep_fit.tex",
        fit_html=report(
            "results/{renderer}/{estimator}/tables/spp_sweep_fit.html",
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
        **cross_renderer_inputs("{run}/correlation/{scene}/spp{spp}.csv", SCENES),
    output:
        csv="results/tables/cross_renderer.csv",
        md="results/tables/cross_renderer.md",
        tex="results/tables/cross_renderer.tex",
        html=report(
            "results/tables/cross_renderer.html",
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
