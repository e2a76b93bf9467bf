# Rig and render settings, cluster requests and the render stores of the rules that render
# (render.smk, ground_truth.smk, preview.smk, mitigations.smk, generators.smk).


def rig_params():
    """Renderer, resolution and rig settings shared by every job that builds the stereo rig."""
    return {
        "renderer": wildcard_renderer,
        "width": config["resolution"]["width"],
        "height": config["resolution"]["height"],
        "baseline_m": config["rig"]["baseline_m"],
        "convention": config["rig"]["convention"],
        "variant": config["render"]["variant"],
    }


def render_params():
    """Integrator, filter, sampler and seed-policy settings of every render."""
    r = config["render"]
    return {
        "variant": r["variant"],
        "integrator": r["integrator"],
        "max_depth": r["max_depth"],
        "rfilter": r["rfilter"],
        "sampler": r["sampler"],
        "seed_policy": r["seed_policy"],
        **renderer_options(),
    }


def renderer_options():
    """The options only a job's renderer reads (``render.cycles`` for Cycles, with every
    default filled in, so each render records them); a param function of the wildcards."""

    def options(wildcards):
        if wildcard_renderer(wildcards) != "cycles":
            return {}
        from stereovar.renderers.cycles.settings import cycles_options

        return cycles_options(config["render"].get("cycles"))

    # a run without Cycles keeps the params (and so the DAG) it always had
    return {"renderer_options": options} if "cycles" in RENDERER_RUNS else {}


# Cluster requests, from each job's size (stereovar.resources). Account, partition and the
# GPU model stay out of the rules: they come from the profile (profiles/slurm*).


def render_resources(n_views=2, spp=None, gpu=True, cpus=None, moments=False):
    """Memory, runtime and (with ``gpu``) GPU requests of a job rendering ``n_views`` views
    of each seed of its ``{batch}`` at ``spp`` (the job's ``spp`` wildcard when None);
    ``moments``: one view's two half renders
    (:func:`stereovar.workflow_inputs.resources.render_resources`)."""
    return job_requests.render_resources(
        WIDTH, HEIGHT, CLUSTER, n_views=n_views, spp=spp, gpu=gpu, cpus=cpus, moments=moments
    )


def render_stores(renderer=None):
    """Every render and moment store the configured tables pool (all scenes, SPPs and
    batches, and the intervention's seeds) of ``renderer`` (default: every renderer run)."""
    if renderer is not None:
        return configured_stores(renderer_config(renderer))
    if AUDIT:
        return configured_stores(config)
    return [p for r in RENDERER_RUNS for p in configured_stores(renderer_config(r))]
