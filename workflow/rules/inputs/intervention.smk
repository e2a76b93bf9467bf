# Inputs and cluster requests of the intervention (intervention.smk).


def intervention_inputs(wildcards):
    """The intervention's seeds (``intervention.n_seeds`` at ``intervention.spp``) of both
    views of one scene, and its ground truth."""
    return {
        **seed_stores(
            run_config(wildcards.renderer),
            wildcards.scene,
            INTERVENTION_SPP,
            INTERVENTION_N_SEEDS,
        ),
        "ground_truth": ground_truth_input(wildcards),
    }


def intervention_resources():
    """Memory and runtime requests of one scene's intervention
    (:func:`stereovar.workflow_inputs.resources.intervention_resources`)."""
    return job_requests.intervention_resources(
        WIDTH, HEIGHT, config["intervention"], INTERVENTION_N_SEEDS
    )
