# Eq. 2 (warp by the ground-truth disparity) and Eq. 3 (Pearson over the valid set).


rule warp:
    input:
        variance="results/variance/{scene}/spp{spp}.zarr",
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        directory("results/warped/{scene}/spp{spp}.zarr"),
    log:
        "logs/warped/{scene}/spp{spp}.log",
    threads: 1
    resources:
        **analysis_resources(images=8, n_reads=0),
    group:
        "analysis"
    conda:
        ENV
    script:
        "../scripts/warp.py"


rule correlation:
    input:
        variance="results/variance/{scene}/spp{spp}.zarr",
        warped="results/warped/{scene}/spp{spp}.zarr",
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        "results/correlation/{scene}/spp{spp}.csv",
    params:
        min_pixels=config["analysis"]["min_pixels"],
    log:
        "logs/correlation/{scene}/spp{spp}.log",
    threads: 1
    resources:
        **analysis_resources(images=8, n_reads=0),
    group:
        "analysis"
    conda:
        ENV
    script:
        "../scripts/correlation.py"
