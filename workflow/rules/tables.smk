# Table 1 (cross-scene correlation) and Table 2 (SPP sweep), paper Sec. 3.2-3.3.


rule cross_scene_table:
    input:
        expand("results/correlation/{scene}/spp{spp}.csv", scene=SCENES, spp=MAIN_SPP),
    output:
        csv=report(
            "results/tables/cross_scene.csv",
            caption="../report/cross_scene.rst",
            category="Tables",
            labels={"table": "Table 1: cross-scene correlation"},
        ),
        md="results/tables/cross_scene.md",
        tex="results/tables/cross_scene.tex",
    params:
        spp=MAIN_SPP,
    log:
        "logs/tables/cross_scene.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/cross_scene_table.py"


rule spp_sweep_table:
    input:
        correlations=sweep_inputs("results/correlation/{scene}/spp{spp}.csv"),
        variances=sweep_inputs("results/variance/{scene}/spp{spp}.zarr"),
        warped=sweep_inputs("results/warped/{scene}/spp{spp}.zarr"),
    output:
        csv=report(
            "results/tables/spp_sweep.csv",
            caption="../report/spp_sweep.rst",
            category="Tables",
            labels={"table": "Table 2: SPP sweep"},
        ),
        md="results/tables/spp_sweep.md",
        tex="results/tables/spp_sweep.tex",
        fit_csv=report(
            "results/tables/spp_sweep_fit.csv",
            caption="../report/spp_sweep_fit.rst",
            category="Tables",
            labels={"table": "Table 2: log-log slope"},
        ),
        fit_md="results/tables/spp_sweep_fit.md",
        fit_tex="results/tables/spp_sweep_fit.tex",
    log:
        "logs/tables/spp_sweep.log",
    localrule: True
    conda:
        ENV
    script:
        "../scripts/spp_sweep_table.py"
