# Figures 1-3 of the paper on the representative (sweep) scene, per renderer and estimator.


rule teaser_figure:
    input:
        variance=main_scene_file(layout.variance_store),
        warped=main_scene_file(layout.warped_store),
    output:
        report(
            layout.run_figure("{renderer}", "{estimator}", "fig1_teaser"),
            caption="../report/fig1_teaser.rst",
            category="Figures",
            labels={
                "figure": "Fig. 1: variance fields and joint histogram",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    log:
        "logs/{renderer}/{estimator}/figures/fig1_teaser.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/figures/fig1_teaser.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/teaser_figure.py"


rule rho_vs_spp_figure:
    input:
        sweep_inputs(layout.correlation_rows),
    output:
        report(
            layout.run_figure("{renderer}", "{estimator}", "fig2_rho_vs_spp"),
            caption="../report/fig2_rho_vs_spp.rst",
            category="Figures",
            labels={
                "figure": "Fig. 2: rho against SPP",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    log:
        "logs/{renderer}/{estimator}/figures/fig2_rho_vs_spp.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/figures/fig2_rho_vs_spp.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/rho_vs_spp_figure.py"


rule material_scatter_figure:
    input:
        variance=main_scene_file(layout.variance_store),
        warped=main_scene_file(layout.warped_store),
        ground_truth=lambda wc: ground_truth_store(wc.renderer, SWEEP_SCENE),
    output:
        report(
            layout.run_figure("{renderer}", "{estimator}", "fig3_material_scatter"),
            caption="../report/fig3_material_scatter.rst",
            category="Figures",
            labels={
                "figure": "Fig. 3: material-separated scatter",
                "renderer": "{renderer}",
                "estimator": "{estimator}",
            },
        ),
    log:
        "logs/{renderer}/{estimator}/figures/fig3_material_scatter.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/figures/fig3_material_scatter.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/material_scatter_figure.py"


rule cross_renderer_figure:
    input:
        **{
            f"variance_{r}": paths[0]
            for r, paths in cross_renderer_inputs(
                layout.variance_store, [SWEEP_SCENE]
            ).items()
        },
        **{
            f"correlation_{r}": paths[0]
            for r, paths in cross_renderer_inputs(
                layout.correlation_rows, [SWEEP_SCENE]
            ).items()
        },
    output:
        report(
            layout.cross_renderer_figure(),
            caption="../report/fig_cross_renderer.rst",
            category="Figures",
            labels={"figure": "variance fields by renderer"},
        ),
    params:
        renderers=RENDERER_RUNS,
    log:
        "logs/figures/cross_renderer.log",
    benchmark:
        "benchmarks/figures/cross_renderer.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/cross_renderer_figure.py"
