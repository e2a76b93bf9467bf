# Inputs of an audit's per-frame rules and of the export (audit.smk).


def audit_frame_inputs(wildcards):
    """One imported frame's render stores (every seed of each view) and ground truth."""
    source = layout.audit_source(wildcards.name)
    return {
        **seed_stores(run_config(source), wildcards.scene, MAIN_SPP),
        "ground_truth": layout.ground_truth_store(source, wildcards.scene),
    }


def audit_verdict_stores(wildcards):
    """What the verdict page reads beyond the tables: the figure of every statistic against
    its controls, and each frame's variance, warped and ground-truth stores, where it ranks
    the frames and tiles in which the cue is strongest (:mod:`stereovar.audit.strongest`)."""
    source = layout.audit_source(wildcards.name)
    return {
        "statistics_figure": layout.run_figure(source, "seeds", "statistics_dots"),
        "variance": [layout.variance_store(source, "seeds", s, MAIN_SPP) for s in SCENES],
        "warped": [layout.warped_store(source, "seeds", s, MAIN_SPP) for s in SCENES],
        "ground_truth": [layout.ground_truth_store(source, s) for s in SCENES],
    }


AUDIT_FOUND = AUDIT_DISCOVERY.summary() if AUDIT else ""
EXPORT_FORMATS = config["export"]["formats"]


def export_inputs(wildcards):
    """One scene's render stores at the main SPP, its variance store and its ground truth,
    for ``export_scene``."""
    run = run_config(wildcards.renderer)
    stores = estimator_stores(run, wildcards.scene, MAIN_SPP, "seeds")
    variance = layout.variance_store(
        wildcards.renderer, wildcards.estimator, wildcards.scene, MAIN_SPP
    )
    return {
        **stores,
        "variance": variance,
        "ground_truth": ground_truth_input(wildcards),
    }


def export_targets():
    """``snakemake export``: every scene of this run in every ``export.formats`` format."""
    run = (get_renderer(), get_estimator())
    return [layout.export_dir(*run, fmt, s) for fmt in EXPORT_FORMATS for s in SCENES]
