# Per-scene preview: both views at a modest SPP, the disparity and the material map.


rule preview:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
    input:
        unpack(scene_inputs),
        ground_truth=layout.traced_ground_truth("{scene}"),
    output:
        report(
            layout.preview("{renderer}", "{scene}"),
            caption="../report/preview.rst",
            category="Scenes",
            subcategory="Previews",
            labels={"scene": "{scene}", "renderer": "{renderer}", "figure": "preview"},
        ),
    params:
        spp=config["preview"]["spp"],
        renderer=lambda wc: wc.renderer,
        **render_params(),
    log:
        "logs/{renderer}/previews/{scene}.log",
    benchmark:
        "benchmarks/{renderer}/previews/{scene}.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(spp=config["preview"]["spp"]),
    group:
        "scene_setup"
    conda:
        ENV
    script:
        "../scripts/preview.py"
