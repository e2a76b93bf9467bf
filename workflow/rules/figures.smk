# Figures 1-3 of the paper on the representative (sweep) scene.


rule teaser_figure:
    input:
        variance=f"results/variance/{SWEEP_SCENE}/spp{MAIN_SPP}.zarr",
        warped=f"results/warped/{SWEEP_SCENE}/spp{MAIN_SPP}.zarr",
    output:
        report(
            "results/figures/fig1_teaser.png",
            caption="../report/fig1_teaser.rst",
            category="Figures",
            labels={"figure": "Fig. 1: variance fields and joint histogram"},
        ),
    log:
        "logs/figures/fig1_teaser.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/teaser_figure.py"


rule rho_vs_spp_figure:
    input:
        sweep_inputs("results/correlation/{scene}/spp{spp}.csv"),
    output:
        report(
            "results/figures/fig2_rho_vs_spp.png",
            caption="../report/fig2_rho_vs_spp.rst",
            category="Figures",
            labels={"figure": "Fig. 2: rho against SPP"},
        ),
    log:
        "logs/figures/fig2_rho_vs_spp.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/rho_vs_spp_figure.py"


rule material_scatter_figure:
    input:
        variance=f"results/variance/{SWEEP_SCENE}/spp{MAIN_SPP}.zarr",
        warped=f"results/warped/{SWEEP_SCENE}/spp{MAIN_SPP}.zarr",
        ground_truth=f"results/ground_truth/{SWEEP_SCENE}.zarr",
    output:
        report(
            "results/figures/fig3_material_scatter.png",
            caption="../report/fig3_material_scatter.rst",
            category="Figures",
            labels={"figure": "Fig. 3: material-separated scatter"},
        ),
    log:
        "logs/figures/fig3_material_scatter.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/material_scatter_figure.py"
