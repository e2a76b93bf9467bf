# Per-scene preview: both views at a modest SPP, the disparity and the material map.


rule preview:
    input:
        unpack(scene_inputs),
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        report(
            "results/figures/previews/{scene}.png",
            caption="../report/preview.rst",
            category="Scenes",
            subcategory="Previews",
            labels={"scene": "{scene}", "figure": "preview"},
        ),
    params:
        spp=config["preview"]["spp"],
        **render_params(),
    log:
        "logs/previews/{scene}.log",
    benchmark:
        "benchmarks/previews/{scene}.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(2, spp=config["preview"]["spp"]),
    group:
        "scene_setup"
    conda:
        ENV
    script:
        "../scripts/preview.py"
