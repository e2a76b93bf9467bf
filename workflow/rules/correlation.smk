# Eq. 2 (warp by the ground-truth disparity) and Eq. 3 (every registered statistic over the
# valid set and its regions).


rule warp:
    input:
        variance="results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr",
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        directory("results/{renderer}/{estimator}/warped/{scene}/spp{spp}.zarr"),
    log:
        "logs/{renderer}/{estimator}/warped/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/warped/{scene}/spp{spp}.tsv"
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
        variance="results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr",
        warped="results/{renderer}/{estimator}/warped/{scene}/spp{spp}.zarr",
        ground_truth="results/ground_truth/{scene}.zarr",
    output:
        "results/{renderer}/{estimator}/correlation/{scene}/spp{spp}.csv",
    params:
        min_pixels=config["analysis"]["min_pixels"],
    log:
        "logs/{renderer}/{estimator}/correlation/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/correlation/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=8, n_reads=0),
    group:
        "analysis"
    conda:
        ENV
    script:
        "../scripts/correlation.py"
