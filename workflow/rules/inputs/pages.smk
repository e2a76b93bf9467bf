# Inputs of the results page (claims.smk): its captions, figures and tables, and the probe's
# and the generators' outputs when a run made them.


def probe_if_run():
    """The probe's outputs when they exist (they are not part of `all`; a run that made them
    has its report and summary include them)."""
    targets = probe_targets()
    return targets if targets and all(Path(p).exists() for p in targets) else []


def generators_if_run():
    """The generator tables and figure when they exist (`snakemake generators` is not part
    of `all`; a run that made them has its results page show them)."""
    targets = [*layout.generator_tables(), layout.generator_figure()]
    return targets if all(Path(p).exists() for p in targets) else []


# The results page (results/index.html, made in claims.smk; stereovar.pages.results): the
# claims, the headline with its controls and every figure and table of `all`, each figure
# with its report caption.
PAGE_CAPTIONS = {
    "fig1_teaser": "fig1_teaser.rst",
    "fig2_rho_vs_spp": "fig2_rho_vs_spp.rst",
    "fig3_material_scatter": "fig3_material_scatter.rst",
    "fig4_intervention_margins": "fig4_intervention_margins.rst",
    "rho_vs_seeds": "fig_rho_vs_seeds.rst",
    "statistics_dots": "fig_statistics_dots.rst",
    "cross_renderer": "fig_cross_renderer.rst",
    "mitigations": "mitigations_figure.rst",
    "probe": "probe_figure.rst",
    "generators": "generators.rst",
    "calibration": "calibration.rst",
    "claims": "claims.rst",
    "workflow": "workflow.rst",
}


def page_captions():
    """The results page's captions by figure name (and ``claims``, ``workflow``): the
    report's captions with their Jinja filled from this config, as the report fills them
    (:func:`stereovar.pages.captions.render_caption`)."""
    from stereovar.pages.captions import render_caption

    return {
        name: render_caption(
            Path(workflow.source_path(f"../../report/{rst}")).read_text(encoding="utf-8"), config
        )
        for name, rst in PAGE_CAPTIONS.items()
    }


def page_results():
    """(figures, tables) of the results page: every figure (PNG) and every table file of
    `all`; the mitigations' and the probe's figures are their sections' inputs
    (:func:`stereovar.workflow_inputs.run.page_results`)."""
    own = {MITIGATION_FIGURE, PROBE_FIGURE, layout.results_page()}
    return run_inputs.page_results(all_targets(), own, layout.TABLE_FORMATS)
