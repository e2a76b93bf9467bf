# Inputs, options, cluster requests and targets of the calibration (calibration.smk).


# The calibration (stereovar.calibration): each scene of the run's source, at the main SPP,
# through "none" and every store transform of the mitigation rows.

CALIBRATION_TRANSFORMS = [
    "none",
    *dict.fromkeys(r.transform for r in MITIGATION_RUNS if r.mitigation.kind == "transform"),
]
# The variance store it is drawn like: the seeds estimator's where the mitigation rows (or an
# audit) have one, else the run's own estimator's (a moments run renders no seeds for it).
CALIBRATION_ESTIMATOR = (
    MITIGATION_ESTIMATOR if (AUDIT or MITIGATION_RUNS) else get_estimator()
)
# The frames per view of every replicate: N seeds, or the moments estimator's samples.
CALIBRATION_DRAWS = N_SEEDS if CALIBRATION_ESTIMATOR == "seeds" else MAIN_SPP
CALIBRATION_TABLES = layout.calibration_tables(MITIGATION_SOURCE)
CALIBRATION_NULLS = layout.calibration_nulls(MITIGATION_SOURCE)
CALIBRATION_FIGURE = layout.calibration_figure(MITIGATION_SOURCE)


def calibration_options():
    """Each calibrated transform's options, as the transform rule passes them."""
    return {
        t: transform_options(SimpleNamespace(transform=t))
        for t in CALIBRATION_TRANSFORMS
        if t != "none"
    }


def calibration_resources():
    """Memory and runtime requests of one scene's calibration
    (:func:`stereovar.workflow_inputs.resources.calibration_resources`)."""
    return job_requests.calibration_resources(
        WIDTH, HEIGHT, config["calibration"], CALIBRATION_DRAWS, CALIBRATION_TRANSFORMS
    )


def calibration_scene_inputs(wildcards):
    """One scene's seeds variance store and ground truth, each view's auxiliary passes when a
    calibrated transform reads them and the source renders them, and the seed renders (their
    channel correlation, and what a seed-mean transform ships)."""
    source = wildcards.renderer
    inputs = {
        "variance": layout.variance_store(
            source, wildcards.estimator, wildcards.scene, wildcards.spp
        ),
        "ground_truth": ground_truth_input(wildcards),
    }
    if mitigation_inputs.reads_aux(CALIBRATION_TRANSFORMS[1:], source):
        for view in VIEWS:
            inputs[f"aux_{view}"] = layout.aux_store(source, wildcards.scene, view)
    if wildcards.estimator == "seeds":  # their channel correlation, and what ships
        stores = seed_stores(run_config(source), wildcards.scene, wildcards.spp)
        inputs.update({f"renders_{view}": paths for view, paths in stores.items()})
    return inputs


def calibration_table_inputs():
    """Every scene's calibration replicates."""
    return [
        layout.calibration_rows(MITIGATION_SOURCE, CALIBRATION_ESTIMATOR, s, MAIN_SPP)
        for s in SCENES
    ]


def calibration_targets():
    """`snakemake calibration`: the calibration table, its matched nulls and figure."""
    return [*CALIBRATION_TABLES, CALIBRATION_NULLS, CALIBRATION_FIGURE]
