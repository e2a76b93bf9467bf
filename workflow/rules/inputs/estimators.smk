# Input functions of the variance estimators (variance.smk, estimators.smk): the stores an
# estimator reads, and the moments check's seeds and moment stores.


def estimator_inputs(wildcards):
    """The stores the estimator reads for one scene at one SPP: all N seeds' render
    stores (``seeds``) or the moment store (``moments``) of each view."""
    return estimator_stores(
        run_config(wildcards.renderer), wildcards.scene, wildcards.spp, wildcards.estimator
    )


def estimator_check_inputs(wildcards):
    """One scene's moment stores, its ``validation.n_seeds`` seed renders at the same SPP
    and its ground truth (``estimator_check``)."""
    run = run_config(wildcards.renderer)
    moments = estimator_stores(run, wildcards.scene, wildcards.spp, "moments")
    seeds = seed_stores(run, wildcards.scene, wildcards.spp, VALIDATION_N_SEEDS)
    return {
        **{f"moments_{view}": paths[0] for view, paths in moments.items()},
        **{f"seeds_{view}": paths for view, paths in seeds.items()},
        "ground_truth": ground_truth_input(wildcards),
    }
