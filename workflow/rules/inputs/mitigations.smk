# Inputs, params and targets of the mitigations (mitigations.smk).


# Mitigations (stereovar.mitigations): each row of results/tables/mitigations.* is a source
# key (the renderer, or the renderer and a transform or seed policy), an SPP and its scenes,
# measured by the seeds estimator, the intervention and the per-scene mitigation rows. What
# an image reads and costs: stereovar.workflow_inputs.mitigations.
from stereovar.workflow_inputs import mitigations as mitigation_inputs

MITIGATIONS = config["mitigations"]
if AUDIT:
    with exit_with_one_line():
        MITIGATION_RUNS = audit_mitigation_runs(config) if AUDIT.get("mitigations") else []
else:
    MITIGATION_RUNS = mitigation_runs(config) if MITIGATIONS["names"] else []
MITIGATION_SOURCE = get_renderer()  # the renderer, or the audit's source
MITIGATION_TABLES = layout.mitigation_tables(MITIGATION_SOURCE)
MITIGATION_HEADLINE = layout.mitigation_headline_tables(MITIGATION_SOURCE)
MITIGATION_FIGURE = layout.mitigation_figure(MITIGATION_SOURCE)
REFERENCE_SPP = MITIGATIONS["reference_spp"]
AUX_SPP = MITIGATIONS["aux_spp"]
# What a seed-mean mitigation ships over its budget and the camera (an audit predicts from
# its own frames and measures at its own budget only)
with exit_with_one_line():
    DOSE = mitigation_inputs.dose_response_plan(config, MITIGATION_RUNS)
DOSE_TABLES = layout.dose_response_tables(MITIGATION_SOURCE)



def reference_from_moments(source):
    """Whether a source's converged reference is a moments render of each view at
    ``mitigations.reference_spp``, else a split-half reference of its own renders
    (:func:`stereovar.workflow_inputs.mitigations.reference_from_moments`)."""
    return mitigation_inputs.reference_from_moments(source, config["render"])


def transform_inputs(wildcards):
    """Every render store of the wildcards' view of the source (all seeds: the seed mean and
    variance are over them) and, when the transform reads albedo or normal and the source
    renders them, the view's auxiliary passes."""
    inputs = {
        "renders": seed_stores(run_config(wildcards.renderer), wildcards.scene, wildcards.spp)[
            wildcards.view
        ]
    }
    if mitigation_inputs.reads_aux([wildcards.transform], wildcards.renderer):
        inputs["aux"] = layout.aux_store(wildcards.renderer, wildcards.scene, wildcards.view)
    return inputs


def transform_options(wildcards):
    """The options of the wildcards' transform that the config sets: the camera model of
    ``controls.sensor`` (:func:`stereovar.workflow_inputs.mitigations.transform_options`)."""
    return mitigation_inputs.transform_options(wildcards.transform, config["controls"]["sensor"])


def mitigation_scene_inputs(wildcards):
    """One scene's render stores of the wildcards' source key at its SPP, its ground truth
    and each view's converged reference (:func:`reference_from_moments`)."""
    source, _ = layout.split_source_key(wildcards.renderer)
    if reference_from_moments(source):
        reference = {
            view: layout.moment_store(source, wildcards.scene, view, REFERENCE_SPP)
            for view in VIEWS
        }
    else:
        reference = seed_stores(run_config(source), wildcards.scene, wildcards.spp)
    return {
        **seed_stores(run_config(wildcards.renderer), wildcards.scene, wildcards.spp),
        "ground_truth": ground_truth_input(wildcards),
        **{f"reference_{view}": paths for view, paths in reference.items()},
    }


def mitigation_files(run):
    """The per-scene files one mitigation row is summarised from."""
    estimator = MITIGATION_ESTIMATOR
    files = {
        "correlation": [
            layout.correlation_rows(run.source, estimator, s, run.spp, run.transform)
            for s in run.scenes
        ],
        "scene_rows": [
            layout.mitigation_rows(run.source, estimator, s, run.spp, run.transform)
            for s in run.scenes
        ],
        # the intervention runs at intervention.spp only
        "intervention": (
            [layout.intervention_metrics(run.source, estimator, s, run.transform) for s in run.scenes]
            if run.spp == INTERVENTION_SPP
            else []
        ),
    }
    return files


def mitigation_table_inputs(wildcards):
    """Every mitigation row's per-scene files, and the calibration's matched nulls."""
    return {
        "files": [
            p for run in MITIGATION_RUNS for paths in mitigation_files(run).values() for p in paths
        ],
        "nulls": layout.calibration_nulls(MITIGATION_SOURCE),
        "calibration": calibration_table_inputs(),
    }


def image_cost(run):
    """Samples per pixel behind one mitigated image and the SPP of the auxiliary pass it reads
    (:func:`stereovar.workflow_inputs.mitigations.image_cost`)."""
    return mitigation_inputs.image_cost(run, N_SEEDS, AUX_SPP)


def mitigation_table_params():
    """What the table job needs per row beside the files: name, kind, description, SPP."""
    return [
        {
            "mitigation": run.name,
            "kind": run.mitigation.kind,
            "description": run.mitigation.description,
            "spp": run.spp,
            "calibration_transform": run.transform if run.mitigation.kind == "transform" else "none",
            **image_cost(run),
            **mitigation_files(run),
        }
        for run in MITIGATION_RUNS
    ]


def dose_response_inputs(wildcards):
    """One scene's seeds variance store at the run's SPP, its ground truth and each view's
    render stores at every budget the run rendered (``renders_{multiple}_{view}``)."""
    inputs = {
        "variance": layout.variance_store(wildcards.renderer, "seeds", wildcards.scene, MAIN_SPP),
        "ground_truth": ground_truth_input(wildcards),
    }
    for m in DOSE["rendered"]:
        stores = seed_stores(run_config(wildcards.renderer), wildcards.scene, m * MAIN_SPP)
        inputs.update({f"renders_{m}_{view}": paths for view, paths in stores.items()})
    return inputs


def dose_response_targets():
    """The dose-response table (nothing without ``mitigations.dose_response.transforms``)."""
    return DOSE_TABLES if DOSE["transforms"] else []


def mitigation_targets():
    """`snakemake mitigations`: the mitigation table and its trade-off figure, the run's or
    the audit's (nothing when ``mitigations.names``, or ``audit.mitigations``, is empty),
    and the dose-response table; the table's CSV first and the figure last."""
    if not MITIGATION_RUNS:
        return []
    return [*MITIGATION_TABLES, *MITIGATION_HEADLINE, *dose_response_targets(), MITIGATION_FIGURE]
