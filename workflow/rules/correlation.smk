# Eq. 2 (warp by the ground-truth disparity) and Eq. 3 (every registered statistic and control
# over the valid set and its regions, with bootstrap intervals and split-half reliability).


rule warp:
    input:
        variance=layout.variance_store("{renderer}", "{estimator}", "{scene}", "{spp}"),
        ground_truth=ground_truth_input,
    output:
        directory(layout.warped_store("{renderer}", "{estimator}", "{scene}", "{spp}")),
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
        variance=layout.variance_store("{renderer}", "{estimator}", "{scene}", "{spp}"),
        warped=layout.warped_store("{renderer}", "{estimator}", "{scene}", "{spp}"),
        ground_truth=ground_truth_input,
    output:
        rows=layout.correlation_rows("{renderer}", "{estimator}", "{scene}", "{spp}"),
        curve=layout.correlation_curve("{renderer}", "{estimator}", "{scene}", "{spp}"),
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
