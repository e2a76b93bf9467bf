# Multi-seed renders (paper Sec. 2.1): one store per scene, view, SPP and seed index. A job
# renders both views for one aligned batch of `render.seeds_per_job` seeds, so process
# start-up and scene compilation are paid once per batch; each render keeps its own store.


for _batch in seed_batches(N_SEEDS, config["render"]["seeds_per_job"]):
    _first, _last = _batch[0], _batch[-1]

    rule:
        name:
            f"render_seeds_{_first}_{_last}"
        input:
            unpack(scene_inputs),
        output:
            [
                directory(render_store("{scene}", view, "{spp}", n))
                for view in ("left", "right")
                for n in _batch
            ],
        params:
            seeds=_batch,
            spp=lambda wc: int(wc.spp),
            **rig_params(),
            **{k: v for k, v in render_params().items() if k != "variant"},
        log:
            f"logs/renders/{{scene}}/spp{{spp}}/seeds{_first}-{_last}.log",
        benchmark:
            f"benchmarks/renders/{{scene}}/spp{{spp}}/seeds{_first}-{_last}.tsv"
        threads: RENDER_THREADS
        resources:
            **render_resources(2 * len(_batch)),
        conda:
            ENV
        script:
            "../scripts/render.py"
