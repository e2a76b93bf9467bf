"""Jobs of ``workflow/rules/figures.smk`` (Figures 1-3 on the representative scene) and of the
uncertainty figures in ``workflow/rules/claims.smk`` (rho against seeds, the dot plot)."""

from __future__ import annotations

from .common import left_right, log, run_label


def _title(attrs, text: str) -> str:
    return f"{text} ({run_label(attrs.get('renderer', '?'), attrs.get('estimator'))})"


DPI = 120
"""Resolution of the saved figures (pixels per inch)."""


def _spp(spp) -> str:
    """``", SPP 32"``; nothing where the SPP is not known (an audit's renders: 0 or None).

    Examples
    --------
    >>> _spp(32), _spp(0), _spp(None)
    (', SPP 32', '', '')
    """
    try:
        return f", SPP {int(spp)}" if spp and int(spp) > 0 else ""
    except (TypeError, ValueError):
        return ""


def _scenes(n: int) -> str:
    return f"{n} scene{'' if n == 1 else 's'}"


def _save(fig, out) -> None:
    """Save a figure as PNG atomically (as :func:`~stereovar.jobs.common.save_figure`) and
    log a warning per text it cuts off or draws over another
    (:func:`stereovar.figures.layout.layout_problems`), measured on the saving draw: the
    figure is saved at its own dpi, so the check needs no second draw."""
    import matplotlib.pyplot as plt

    from ..figures.layout import layout_problems
    from ..io.store import write_file

    fig.set_dpi(DPI)
    write_file(out, lambda tmp: fig.savefig(tmp, format="png", dpi=DPI))
    for problem in layout_problems(fig, draw=False):
        log.warning("figure %s: %s", out, problem)
    plt.close(fig)


def _estimate(attrs) -> str:
    """How the variance was estimated: ``N = 8`` seeds, or one render (two halves)."""
    from ..estimators import reads_moments

    if reads_moments(attrs.get("estimator")):
        return "one render per view"
    return f"N = {attrs['n_seeds']}"


def teaser_figure_job(variance, warped, out) -> None:
    """Fig. 1: sigma_L^2, sigma_R^2, the warped field and their joint histogram over Omega."""
    from ..figures.teaser import teaser_figure
    from ..io.store import load_store

    v = load_store(variance, "variance store")
    w = load_store(warped, "warped store")
    sigma_l, sigma_r = left_right(v, "variance")
    text = f"{v.attrs['scene']}{_spp(v.attrs.get('spp'))}, {_estimate(v.attrs)}"
    title = _title(v.attrs, text)
    _save(teaser_figure(sigma_l, sigma_r, w["warped_variance"], w["omega"], title=title), out)


def rho_vs_spp_figure_job(correlations, out) -> None:
    """Fig. 2: rho against SPP per region with bootstrap intervals, and the robust statistics
    (Spearman, log-Pearson) beside Pearson."""
    from ..figures.rho_vs_spp import rho_vs_spp_figure
    from ..io.tables import read_rows
    from ..statistics.registry import PRIMARY_METHOD

    rows = [r for path in correlations for r in read_rows(path)]
    scene = rows[0]["scene"] if rows else ""
    attrs = rows[0] if rows else {}
    fig = rho_vs_spp_figure(
        rows, title=_title(attrs, f"{scene}: rho against SPP"), primary=PRIMARY_METHOD
    )
    _save(fig, out)


def material_scatter_figure_job(variance, warped, ground_truth, out) -> None:
    """Fig. 3: (sigma_L^2, warped sigma_R^2) over Omega, glass against non-glass."""
    from ..figures.material_scatter import material_scatter_figure
    from ..io.store import load_store

    v = load_store(variance, "variance store")
    w = load_store(warped, "warped store")
    gt = load_store(ground_truth, "ground-truth store")
    fig = material_scatter_figure(
        v["variance"].sel(view="left"),
        w["warped_variance"],
        w["omega"],
        gt["glass"].sel(view="left").values,
        title=_title(v.attrs, f"{v.attrs['scene']}{_spp(v.attrs.get('spp'))}"),
    )
    _save(fig, out)


def margin_figure_job(margins, out) -> None:
    """The intervention's GT-margin distributions per region, normal against decorrelated."""
    from ..figures.margins import margin_distribution_figure
    from ..io.tables import read_rows

    rows = [r for path in margins for r in read_rows(path)]
    n_scenes = len({r["scene"] for r in rows})
    title = f"GT margins, normal vs decorrelated ({_scenes(n_scenes)}, sampled pixels)"
    if rows and rows[0].get("renderer"):
        title += f"\n{run_label(rows[0]['renderer'], rows[0].get('estimator'))}"
    _save(margin_distribution_figure(rows, title=title), out)


def rho_vs_seeds_figure_job(curve_table, out) -> None:
    """rho against the number of seeds N' per region, with the reliability-corrected
    asymptote (``tables/seed_curve.csv``)."""
    from ..figures.uncertainty import HALVES_AXIS, SEEDS_AXIS, rho_vs_seeds_figure
    from ..io.tables import read_rows

    rows = read_rows(curve_table)
    attrs = rows[0] if rows else {}
    from ..estimators import reads_moments

    moments = reads_moments(attrs.get("estimator"))
    fig = rho_vs_seeds_figure(
        rows,
        title=_title(attrs, "rho against half renders" if moments else "rho against seeds N'"),
        xlabel=HALVES_AXIS if moments else SEEDS_AXIS,
        drop_empty=True,
    )
    _save(fig, out)


def statistics_dot_figure_job(correlations, out, *, spp) -> None:
    """Every statistic and control per scene with its bootstrap interval, at the main SPP."""
    from ..figures.uncertainty import statistics_dot_figure
    from ..io.tables import read_rows

    rows = [r for path in correlations for r in read_rows(path)]
    attrs = rows[0] if rows else {}
    n_scenes = len({r["scene"] for r in rows})
    audit = str(attrs.get("renderer", "")).startswith("audit/")
    count = f"{n_scenes} frame{'' if n_scenes == 1 else 's'}" if audit else _scenes(n_scenes)
    title = _title(attrs, f"every statistic and control, {count}{_spp(spp)}")
    _save(statistics_dot_figure(rows, spp=spp, title=title, drop_empty=True), out)


def cross_renderer_figure_job(variances: dict, correlations: dict, out) -> None:
    """Each renderer's left and right sigma^2 fields of one scene side by side, with its
    warped rho and interval."""
    from ..figures.cross_renderer import cross_renderer_figure
    from ..io.store import load_store
    from ..io.tables import read_rows
    from ..statistics.registry import PRIMARY_METHOD

    fields, rho, attrs = {}, {}, {}
    for renderer, path in variances.items():
        v = load_store(path, "variance store")
        fields[renderer] = left_right(v, "variance")
        attrs = v.attrs
        for row in read_rows(correlations[renderer]):
            if row["region"] == "all" and row["method"] == PRIMARY_METHOD:
                rho[renderer] = (row["rho"], row["boot_low"], row["boot_high"])
    title = f"{attrs.get('scene', '')}{_spp(attrs.get('spp'))}: sigma^2 by renderer"
    _save(cross_renderer_figure(fields, rho=rho, title=title), out)
