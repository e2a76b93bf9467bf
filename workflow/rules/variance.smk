# Eq. 1 (paper Sec. 2.1): the configured estimator's per-pixel variance of both views.


rule variance:
    input:
        unpack(estimator_inputs),
    output:
        directory(layout.variance_store("{renderer}", "{estimator}", "{scene}", "{spp}")),
    params:
        estimator=lambda wc: wc.estimator,
    log:
        "logs/{renderer}/{estimator}/variance/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/variance/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=12, n_reads=2 * ESTIMATOR_READS),
    group:
        "analysis"
    conda:
        ENV
    script:
        "../scripts/variance.py"
