# Figures 1-3 of the paper on the representative (sweep) scene, per renderer and estimator.


rule teaser_figure:
    input:
        variance=main_scene_file("{run}/variance/{scene}/spp{spp}.zarr"),
        warped=main_scene_file("{run}/warped/{scene}/spp{spp}.zarr"),
    output:
        report(
            "results/{renderer}/{estimator}/figures/fig1_teaser.png",
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
        sweep_inputs("{run}/correlation/{scene}/spp{spp}.csv"),
    output:
        report(
            "results/{renderer}/{estimator}/figures/fig2_rho_vs_spp.png",
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
        variance=main_scene_file("{run}/variance/{scene}/spp{spp}.zarr"),
        warped=main_scene_file("{run}/warped/{scene}/spp{spp}.zarr"),
        ground_truth=lambda wc: ground_truth_store(wc.renderer, SWEEP_SCENE),
    output:
        report(
            "results/{renderer}/{estimator}/figures/fig3_material_scatter.png",
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
                "{run}/variance/{scene}/spp{spp}.zarr", [SWEEP_SCENE]
            ).items()
        },
        **{
            f"correlation_{r}": paths[0]
            for r, paths in cross_renderer_inputs(
                "{run}/correlation/{scene}/spp{spp}.csv", [SWEEP_SCENE]
            ).items()
        },
    output:
        report(
            "results/figures/cross_renderer.png",
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
