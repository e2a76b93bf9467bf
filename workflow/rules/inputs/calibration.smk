# Inputs, options, cluster requests and targets of the calibration (calibration.smk).


# The calibration (stereovar.calibration): each scene of the run's source, at the main SPP,
# through "none" and every store transform of the mitigation rows.
from stereovar.calibration.replicates import reads_seed_mean

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
    """Memory (every frame of both views, the transformed stacks and the renders: 4N + 16
    images, N the frames drawn per view) and runtime
    (:func:`stereovar.resources.calibration_runtime`) of one scene's calibration."""
    cal = config["calibration"]
    denoisers = [
        t for t in CALIBRATION_TRANSFORMS[1:] if get_transform(t).expensive
    ]
    runtime = lambda wildcards, attempt: sizing.calibration_runtime(
        WIDTH,
        HEIGHT,
        CALIBRATION_DRAWS,
        replicates=int(cal["replicates"]),
        designs=2 + len(cal["strengths"]),
        transforms=len(CALIBRATION_TRANSFORMS) - len(denoisers),
        denoised_replicates=int(cal["denoised_replicates"]),
        denoisers=len(denoisers),
        attempt=attempt,
    )
    return {
        **analysis_resources(images=4 * CALIBRATION_DRAWS + 16, n_reads=2 * CALIBRATION_DRAWS),
        "runtime": runtime,
    }


def calibration_scene_inputs(wildcards):
    """One scene's seeds variance store and ground truth, and each view's auxiliary passes
    when a calibrated transform reads them and the source renders them."""
    source = wildcards.renderer
    inputs = {
        "variance": layout.variance_store(
            source, wildcards.estimator, wildcards.scene, wildcards.spp
        ),
        "ground_truth": ground_truth_input(wildcards),
    }
    wants = set()
    for t in CALIBRATION_TRANSFORMS[1:]:
        transform = get_transform(t)
        wants |= {"albedo", "normal"} & {*transform.reads, *transform.optional_reads}
    if wants and wants <= set(source_aux_passes(source)):
        for view in VIEWS:
            inputs[f"aux_{view}"] = layout.aux_store(source, wildcards.scene, view)
    if wildcards.estimator == "seeds" and any(reads_seed_mean(t) for t in CALIBRATION_TRANSFORMS):
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
