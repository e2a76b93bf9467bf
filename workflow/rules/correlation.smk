# Eq. 2 (warp by the ground-truth disparity) and Eq. 3 (every registered statistic and control
# over the valid set and its regions, with bootstrap intervals and split-half reliability).


rule warp:
    input:
        variance="results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr",
        ground_truth=ground_truth_input,
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
        ground_truth=ground_truth_input,
    output:
        rows="results/{renderer}/{estimator}/correlation/{scene}/spp{spp}.csv",
        curve="results/{renderer}/{estimator}/correlation/{scene}/spp{spp}_curve.csv",
    params:
        analysis=config["analysis"],
        controls=config["controls"],
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
