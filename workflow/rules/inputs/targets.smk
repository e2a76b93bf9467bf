# What `snakemake all` builds (rule `all` in the Snakefile; the results page lists it).


def all_targets():
    """Everything `snakemake all` builds, for the configured renderer and estimator (for an
    audit: its verdict page and everything behind it, :func:`stereovar.audit.run.audit_targets`)."""
    if AUDIT:
        return [
            *render_stores(),
            *audit_targets(config),
            *mitigation_targets(),
            *calibration_targets(),
            *probe_targets(),
            *(layout.probe_model_tables(get_renderer()) if AUDIT.get("probe_model") else []),
        ]
    shared = [
        *[layout.traced_ground_truth(s) for s in SCENES],
        *layout.scene_tables(),
        *layout.claims_tables(),
        layout.summary_json(),
        *mitigation_targets(),
        *calibration_targets(),
        *probe_if_run(),
        layout.results_page(),
    ]
    if len(RENDERER_RUNS) > 1:
        shared += [
            *layout.cross_renderer_tables(),
            layout.cross_renderer_figure(),
        ]
    per_renderer = [p for r in RENDERER_RUNS for p in renderer_targets(r)]
    return list(dict.fromkeys([*per_renderer, *shared]))


def renderer_targets(renderer):
    """Everything `snakemake all` builds for one renderer."""
    run = (renderer, get_estimator())
    intervention = (renderer, INTERVENTION_ESTIMATOR)
    return [
        # The renders are targets too, so a render store lost after its analysis finished is
        # rebuilt (from the render cache) instead of silently missing.
        *render_stores(renderer),
        *[layout.preview(renderer, s) for s in SCENES],
        *[layout.correlation_rows(*run, s, spp) for s, spp in scene_spp_pairs(config)],
        *[
            p
            for name in ["cross_scene", "spp_sweep", "spp_sweep_fit"]
            for p in layout.run_tables(*run, name)
        ],
        *[layout.intervention_metrics(*intervention, s) for s in SCENES],
        *layout.run_tables(*intervention, "intervention"),
        layout.run_figure(*run, "fig1_teaser"),
        layout.run_figure(*run, "fig2_rho_vs_spp"),
        layout.run_figure(*run, "fig3_material_scatter"),
        layout.run_figure(*intervention, "fig4_intervention_margins"),
        layout.run_figure(*run, "rho_vs_seeds"),
        layout.run_figure(*run, "statistics_dots"),
        *[p for name in ["statistics", "seed_curve"] for p in layout.run_tables(*run, name)],
    ]
