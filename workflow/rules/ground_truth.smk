# Ground truth per scene: one ray per pixel centre of each view (paper Sec. 3.1).


rule ground_truth:
    input:
        unpack(scene_inputs),
    output:
        directory("results/ground_truth/{scene}.zarr"),
    params:
        # one ground truth per scene, traced on the Mitsuba-compiled geometry for every
        # renderer (the Cycles compiler builds the same geometry; tests/test_cycles.py)
        **{**rig_params(), "renderer": "mitsuba"},
    log:
        "logs/ground_truth/{scene}.log",
    benchmark:
        "benchmarks/ground_truth/{scene}.tsv"
    threads: 1
    resources:
        **render_resources(spp=1, gpu=False, cpus=1),
    group:
        "scene_setup"
    conda:
        ENV
    script:
        "../scripts/ground_truth.py"


rule scene_summary:
    input:
        expand("results/ground_truth/{scene}.zarr", scene=SCENES),
    output:
        csv="results/tables/scenes.csv",
        md="results/tables/scenes.md",
        tex="results/tables/scenes.tex",
        html=report(
            "results/tables/scenes.html",
            caption="../report/scenes.rst",
            category="Scenes",
            labels={"table": "scene summary"},
        ),
    log:
        "logs/tables/scenes.log",
    benchmark:
        "benchmarks/tables/scenes.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/scene_summary.py"
