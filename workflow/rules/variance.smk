# Eq. 1 (paper Sec. 2.1): per-pixel population variance over the N seeds, streamed.


rule variance:
    input:
        unpack(scene_renders),
    output:
        directory("results/variance/{scene}/spp{spp}.zarr"),
    log:
        "logs/variance/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/variance/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=12, n_reads=2 * N_SEEDS),
    group:
        "analysis"
    conda:
        ENV
    script:
        "../scripts/variance.py"
