"""The stages a run is reported in: which workflow rules make up which stage, in order.

``stereovar run`` and ``stereovar audit`` print one line per stage
(:class:`stereovar.progress.Progress`), and their ``--help`` lists the same stages
(:func:`stage_list`): both read the maps here, so the help names exactly the lines a run
prints. A job counts in the stage of its rule (:func:`rule_stage`), so every stage's total is
fixed by Snakemake's plan of the run.
"""

from __future__ import annotations

#: The rules of the intervention (Sec. 3.4) and of the mitigations, stages of both maps.
INTERVENTION_RULES = ("intervention", "intervention_table", "margin_figure")
MITIGATION_RULES = (
    "render_policy",
    "render_aux",
    "transform",
    "mitigation_scene",
    "mitigations_table",
    "dose_response_scene",
    "dose_response_table",
    "mitigations",
)

#: The stages ``stereovar run`` reports, in order, and the workflow rules of each. A rule
#: named nowhere counts as ``statistics``; ``all`` (the target, no work) counts nowhere.
RUN_STAGES = {
    "scenes": ("generate_scene", "scene_summary", "preview"),
    "render": ("render", "render_moments", "render_profile"),
    "ground truth": ("ground_truth",),
    "statistics": ("variance", "warp", "correlation"),
    "controls": ("estimator_check", "estimator_tables", "estimators"),
    "intervention": INTERVENTION_RULES,
    "mitigations": MITIGATION_RULES,
    "calibration": (
        "calibration_scene",
        "calibration_table",
        "calibration",
        "generator_calibration",
        "generators_table",
        "generators",
    ),
    "probe": (
        "probe_model_frames",
        "probe_model",
        "probe_planted",
        "probe_train",
        "probe_train_control",
        "probe_test",
        "probe_table",
        "probe",
    ),
    "tables": (
        "statistics_table",
        "cross_scene_table",
        "spp_sweep_table",
        "cross_renderer_table",
        "claims",
    ),
    "pages": (
        "teaser_figure",
        "rho_vs_spp_figure",
        "rho_vs_seeds_figure",
        "statistics_dot_figure",
        "material_scatter_figure",
        "cross_renderer_figure",
        "results_page",
    ),
    "export": ("export_scene", "export"),
}

#: The stages ``stereovar audit`` reports, in order, and the workflow rules of each.
AUDIT_STAGES = {
    "import": ("audit_import",),
    "statistics": ("variance", "warp", "correlation"),
    "controls": ("audit_seeding", "estimator_check", "estimator_tables", "estimators"),
    "intervention": INTERVENTION_RULES,
    "calibration": ("calibration_scene", "calibration_table", "calibration"),
    "mitigations": MITIGATION_RULES,
    "probe": (
        "probe_model_frames",
        "probe_model",
        "probe_planted",
        "probe_train",
        "probe_train_control",
        "probe_test",
        "probe_table",
        "probe",
    ),
    "tables and figures": (
        "statistics_table",
        "cross_scene_table",
        "spp_sweep_table",
        "statistics_dot_figure",
        "rho_vs_seeds_figure",
        "audit_teaser",
        "audit_thumbnail",
    ),
    "verdict": ("audit_verdict",),
}

#: The stage maps by the name the logger plugin's ``stages`` setting gives.
STAGE_MAPS = {"run": RUN_STAGES, "audit": AUDIT_STAGES}

#: The stage a rule named in no stage counts in.
DEFAULT_STAGE = "statistics"

#: Rules that are targets only: their jobs count in no stage.
TARGET_RULES = ("all",)


def stage_map(name: str) -> dict:
    """The stages of ``name`` (``run`` or ``audit``): :data:`STAGE_MAPS`.

    Parameters
    ----------
    name : str
        ``run`` or ``audit``.

    Returns
    -------
    dict
        Stage name: its rules, in the order the stages are reported.

    Raises
    ------
    ValueError
        For another name, naming the ones there are.
    """
    try:
        return STAGE_MAPS[name]
    except KeyError:
        raise ValueError(f"unknown stages {name!r}; use one of {sorted(STAGE_MAPS)}") from None


def stage_list(name: str) -> str:
    """The stages of ``name`` as a command's help names them, in order.

    Parameters
    ----------
    name : str
        ``run`` or ``audit``.

    Returns
    -------
    str
        The stage names, comma-separated.

    Examples
    --------
    >>> stage_list("audit")  # doctest: +ELLIPSIS
    'import, statistics, controls, ..., tables and figures, verdict'
    """
    return ", ".join(stage_map(name))


def rule_stage(rule, stages: dict):
    """The stage of ``rule`` in ``stages``; None for a target rule (``all``) or no rule.

    Parameters
    ----------
    rule : str or None
        A workflow rule's name.
    stages : dict
        A stage map (:data:`RUN_STAGES`, :data:`AUDIT_STAGES`).

    Returns
    -------
    str or None
        The stage; :data:`DEFAULT_STAGE` for a rule the map does not name.

    Examples
    --------
    >>> rule_stage("audit_import", AUDIT_STAGES), rule_stage("new_rule", AUDIT_STAGES)
    ('import', 'statistics')
    >>> rule_stage("all", RUN_STAGES) is None
    True
    """
    if not rule or rule in TARGET_RULES:
        return None
    for stage, rules in stages.items():
        if rule in rules:
            return stage
    return DEFAULT_STAGE if DEFAULT_STAGE in stages else None
