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
    """Memory and runtime requests of one scene's intervention (D estimated before the
    ground truth exists: the configured one, else 5% of the width plus the margin)."""
    iv = config["intervention"]
    d = iv["max_disparity"] or math.ceil(0.05 * WIDTH) + iv["disparity_margin"]
    return {
        "mem_mb": lambda wildcards, attempt: sizing.analysis_mem_mb(
            WIDTH, HEIGHT, 24, attempt=attempt
        ),
        "runtime": lambda wildcards, attempt: sizing.intervention_runtime(
            WIDTH, HEIGHT, INTERVENTION_N_SEEDS, d + 1, attempt=attempt
        ),
        "cpus_per_task": 2,
    }
