# Multi-seed renders (paper Sec. 2.1). One job renders both views of one aligned batch of
# `render.seeds_per_job` seed indices (the {batch} wildcard, "first-last"), so process start-up
# and scene compilation are paid once per batch; each view's batch is one render store.


rule render:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
    input:
        unpack(scene_inputs),
    output:
        left=directory(layout.render_store("{renderer}", "{scene}", "left", "{spp}", "{batch}")),
        right=directory(layout.render_store("{renderer}", "{scene}", "right", "{spp}", "{batch}")),
    params:
        seeds=lambda wc: batch_seeds(wc.batch),
        spp=lambda wc: int(wc.spp),
        **rig_params(),
        **{k: v for k, v in render_params().items() if k != "variant"},
    log:
        "logs/{renderer}/renders/{scene}/spp{spp}/seeds{batch}.log",
    benchmark:
        "benchmarks/{renderer}/renders/{scene}/spp{spp}/seeds{batch}.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(),
    conda:
        ENV
    script:
        "../scripts/render.py"


# The moments estimator: one job per scene, view and SPP renders the view as two
# independent half renders and stores their per-pixel sample moments.


rule render_moments:
    wildcard_constraints:
        renderer=RENDERER_NAMES,
    input:
        unpack(scene_inputs),
    output:
        directory(layout.moment_store("{renderer}", "{scene}", "{view}", "{spp}")),
    params:
        view=lambda wc: wc.view,
        spp=lambda wc: int(wc.spp),
        **rig_params(),
        **{k: v for k, v in render_params().items() if k != "variant"},
    log:
        "logs/{renderer}/renders/{scene}/{view}/spp{spp}/moments.log",
    benchmark:
        "benchmarks/{renderer}/renders/{scene}/{view}/spp{spp}/moments.tsv"
    threads: RENDER_THREADS
    resources:
        **render_resources(n_views=1, moments=True),
    conda:
        ENV
    script:
        "../scripts/render_moments.py"
