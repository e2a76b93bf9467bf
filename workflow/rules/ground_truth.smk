# Ground truth per scene: one ray per pixel centre of each view (paper Sec. 3.1).


rule ground_truth:
    input:
        unpack(scene_inputs),
    output:
        directory(layout.traced_ground_truth("{scene}")),
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
        [layout.traced_ground_truth(s) for s in SCENES],
    output:
        **table_outputs(
            layout.scene_tables(),
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
