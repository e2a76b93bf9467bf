"""One function per workflow job: paths and parameters in, stored artefacts out.

The Snakemake scripts in ``workflow/scripts`` are thin adapters that call these functions, so
every job can also be run from a notebook or a shell without Snakemake.
"""

from __future__ import annotations

import hashlib
import json
import logging
import sys
import time
from pathlib import Path

from .errors import StereovarError

log = logging.getLogger("stereovar")


def run_job(log_path, job, **kwargs) -> None:
    """Run ``job(**kwargs)`` with logging to ``log_path`` and to stderr.

    A :class:`~stereovar.errors.StereovarError` becomes one ``error:`` line on stderr and in
    the log, and exit status 1, without a traceback; other exceptions propagate.
    """
    handlers = [logging.StreamHandler(sys.stderr)]
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(log_path, mode="w"))
    logging.basicConfig(
        level=logging.INFO,
        format="%(asctime)s %(levelname)s %(message)s",
        handlers=handlers,
        force=True,
    )
    start = time.perf_counter()
    try:
        job(**kwargs)
    except StereovarError as err:
        log.error("error: %s", err)
        raise SystemExit(1) from None
    log.info("done in %.2f s", time.perf_counter() - start)


def scene_digest(spec: dict) -> str:
    """SHA-256 of a scene: its canonical spec plus, for XML scenes, the file's bytes."""
    from .scenespec import scene_spec_digest

    h = hashlib.sha256(scene_spec_digest(spec).encode())
    if "mitsuba_xml" in spec:
        h.update(Path(spec["mitsuba_xml"]).read_bytes())
    return h.hexdigest()


def prepare_scene(
    spec_path,
    *,
    variant: str,
    width: int,
    height: int,
    baseline_m: float,
    convention: str,
    threads: int | None = None,
):
    """Load a spec, pick the backend, compile the scene and build the rig.

    Returns
    -------
    mi, spec, scene, rig, provenance : tuple
        ``provenance`` is a dict of attrs for stored artefacts.
    """
    from . import __version__
    from .backend import describe_backend, load_mitsuba
    from .mitsuba_scene import load_scene
    from .rig import make_rig
    from .scenespec import load_scene_spec

    spec = load_scene_spec(spec_path)
    mi = load_mitsuba(variant)
    if threads:
        import drjit as dr

        dr.set_thread_count(int(threads))
    scene, camera = load_scene(mi, spec)
    rig = make_rig(
        camera.to_world,
        camera.fov_deg,
        width=width,
        height=height,
        baseline_m=baseline_m,
        convention=convention,
    )
    backend = describe_backend()
    provenance = {
        "scene": spec["name"],
        "scene_digest": scene_digest(spec),
        "renderer": "mitsuba",
        "renderer_version": backend["mitsuba_version"],
        "drjit_version": backend["drjit_version"],
        "variant": backend["variant"],
        "stereovar_version": __version__,
    }
    log.info(
        "scene %s: variant %s, %dx%d, baseline %.4f m, convention %s",
        spec["name"],
        backend["variant"],
        width,
        height,
        baseline_m,
        convention,
    )
    return mi, spec, scene, rig, provenance


def ground_truth_job(
    spec, out, *, variant="auto", width, height, baseline_m, convention, threads=None
) -> None:
    """Trace and store the ground truth of one scene (``results/ground_truth/{scene}.zarr``)."""
    from .ground_truth import compute_ground_truth, summarize_ground_truth
    from .store import write_dataset

    mi, _, scene, rig, provenance = prepare_scene(
        spec,
        variant=variant,
        width=width,
        height=height,
        baseline_m=baseline_m,
        convention=convention,
        threads=threads,
    )
    ds = compute_ground_truth(mi, scene, rig, attrs=provenance)
    write_dataset(ds, out)
    summary = summarize_ground_truth(ds)
    log.info("ground truth: %s", json.dumps({k: round(v, 4) for k, v in summary.items()}))


def preview_job(
    spec,
    ground_truth,
    out,
    *,
    variant="auto",
    spp,
    integrator="path",
    max_depth=8,
    rfilter="box",
    sampler="independent",
    threads=None,
) -> None:
    """Render both views at a modest SPP and save the preview figure as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .preview import preview_figure
    from .render import derive_seed, integrator_dict, render_view
    from .store import open_dataset, write_file

    gt = open_dataset(ground_truth).load()
    mi, spec_d, scene, rig, _ = prepare_scene(
        spec,
        variant=variant,
        width=int(gt.attrs["width"]),
        height=int(gt.attrs["height"]),
        baseline_m=float(gt.attrs["baseline_m"]),
        convention=str(gt.attrs["convention"]),
        threads=threads,
    )
    images = {}
    for view in ("left", "right"):
        start = time.perf_counter()
        images[view] = render_view(
            mi,
            scene,
            rig,
            view,
            spp=spp,
            seed=derive_seed(spec_d["name"], view, spp, "preview"),
            integrator=integrator_dict(integrator, max_depth),
            rfilter=rfilter,
            sampler=sampler,
        )
        log.info("rendered %s view at %d spp in %.2f s", view, spp, time.perf_counter() - start)
    fig = preview_figure(images["left"], images["right"], gt, title=spec_d["name"], spp=spp)
    write_file(out, lambda tmp: fig.savefig(tmp, format="png", dpi=110))
    plt.close(fig)


def render_job(
    spec,
    outputs,
    *,
    seeds,
    spp,
    variant="auto",
    width,
    height,
    baseline_m,
    convention,
    integrator="path",
    max_depth=8,
    rfilter="box",
    sampler="independent",
    threads=None,
) -> None:
    """Render both views of a scene once per seed index; one store per render.

    ``outputs`` lists the left view's stores for ``seeds`` followed by the right view's. Each
    store is a DataArray ``radiance`` on (y, x, channel) written atomically, with the seed
    value actually passed to Mitsuba, derived from (scene, view, spp, seed index), in its
    attrs. The scene is compiled once per job, so the per-render cost is the render itself.
    """
    import numpy as np
    import xarray as xr

    from .experiment import VIEWS
    from .render import derive_seed, integrator_dict, render_view
    from .store import write_dataset

    jobs = [(view, index) for view in VIEWS for index in seeds]
    if len(outputs) != len(jobs):
        raise StereovarError(
            f"render job got {len(outputs)} outputs for {len(seeds)} seeds of {len(VIEWS)} views"
        )
    mi, spec_d, scene, rig, provenance = prepare_scene(
        spec,
        variant=variant,
        width=width,
        height=height,
        baseline_m=baseline_m,
        convention=convention,
        threads=threads,
    )
    integ = integrator_dict(integrator, max_depth)
    name = spec_d["name"]
    for k, ((view, index), out) in enumerate(zip(jobs, outputs, strict=True)):
        seed = derive_seed(name, view, spp, index)
        start = time.perf_counter()
        image = render_view(
            mi,
            scene,
            rig,
            view,
            spp=spp,
            seed=seed,
            integrator=integ,
            rfilter=rfilter,
            sampler=sampler,
        )
        elapsed = time.perf_counter() - start
        n_bad = int((~np.isfinite(image)).any(axis=-1).sum())
        da = xr.DataArray(
            image,
            dims=("y", "x", "channel"),
            coords={"channel": ["R", "G", "B"]},
            name="radiance",
            attrs={
                **provenance,
                "view": view,
                "spp": int(spp),
                "seed_index": int(index),
                "seed": int(seed),
                "integrator": integrator,
                "max_depth": int(max_depth),
                "rfilter": rfilter,
                "sampler": sampler,
                "width": int(width),
                "height": int(height),
                "baseline_m": float(baseline_m),
                "convention": convention,
                "n_nonfinite_pixels": n_bad,
            },
        )
        write_dataset(da, out)
        rate = width * height * spp / max(elapsed, 1e-9) / 1e6
        log.info(
            "%s spp %d: %s seed %d (%d/%d) rendered in %.2f s, %.2f Msamples/s%s",
            name,
            spp,
            view,
            index,
            k + 1,
            len(jobs),
            elapsed,
            rate,
            f", {n_bad} non-finite pixels" if n_bad else "",
        )


CORRELATION_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "region",
    "method",
    "rho",
    "n_pixels",
    "ci_low",
    "ci_high",
    "p_value",
    "log10_p_value",
    "n_nonfinite",
    "reason",
]


def _left_right(ds, name):
    return ds[name].sel(view="left"), ds[name].sel(view="right")


def variance_job(left, right, out) -> None:
    """Stream one scene's renders at one SPP into ``results/variance/{scene}/spp{spp}.zarr``."""
    from .store import open_dataset, write_dataset
    from .variance import variance_dataset

    ds = variance_dataset(list(left), list(right))
    first = open_dataset(left[0])["radiance"].attrs
    keep = (
        "scene",
        "scene_digest",
        "spp",
        "renderer",
        "renderer_version",
        "variant",
        "width",
        "height",
        "integrator",
        "max_depth",
        "rfilter",
        "sampler",
    )
    ds.attrs.update({k: first[k] for k in keep if k in first})
    n_bad = {v: int((~ds["finite"].sel(view=v).values).sum()) for v in ("left", "right")}
    write_dataset(ds, out)
    log.info(
        "variance over %d seeds; pixels with a non-finite render: left %d, right %d",
        ds.attrs["n_seeds"],
        n_bad["left"],
        n_bad["right"],
    )


def warp_job(variance, ground_truth, out) -> None:
    """Warp the right variance field into the left view (Eq. 2) and store Ω and the regions."""
    import numpy as np
    import xarray as xr

    from .correlation import align_variance, region_masks
    from .store import open_dataset, write_dataset

    v = open_dataset(variance)[["variance", "finite"]].load()
    gt = open_dataset(ground_truth)
    gl = gt[["disparity", "valid", "glass"]].sel(view="left").load()
    sigma_l, sigma_r = _left_right(v, "variance")
    fin_l, fin_r = _left_right(v, "finite")
    aligned = align_variance(
        sigma_l,
        sigma_r,
        gl,
        sign=int(gt.attrs["disparity_sign"]),
        finite_left=fin_l,
        finite_right=fin_r,
    )
    masks = region_masks(gl, aligned["omega"])
    dims = ("y", "x")
    ds = xr.Dataset(
        {
            "warped_variance": (
                dims,
                aligned["warped"],
                {
                    "long_name": "right variance field in left coordinates (Eq. 2); 0 outside"
                    " omega_geometry"
                },
            ),
            "omega": (dims, aligned["omega"], {"long_name": "valid set of Eq. 3"}),
            "omega_geometry": (
                dims,
                aligned["omega_geometry"],
                {"long_name": "valid set of the warp from the ground truth alone"},
            ),
            "usable": (
                dims,
                aligned["usable"],
                {"long_name": "left value and warped right value built from finite renders"},
            ),
            **{
                f"region_{k}": (dims, np.asarray(m), {"long_name": f"omega restricted to {k}"})
                for k, m in masks.items()
            },
        },
        coords={
            "y": v["y"].values if "y" in v.coords else np.arange(sigma_l.shape[0]),
            "x": v["x"].values if "x" in v.coords else np.arange(sigma_l.shape[1]),
        },
        attrs={
            **v.attrs,
            "disparity_sign": int(gt.attrs["disparity_sign"]),
            "convention": gt.attrs["convention"],
        },
    )
    write_dataset(ds, out)
    log.info(
        "omega: %d of %d pixels (%d glass)",
        int(aligned["omega"].sum()),
        aligned["omega"].size,
        int(np.asarray(masks["glass"]).sum()),
    )


def correlation_job(variance, warped, ground_truth, out, *, min_pixels=30) -> list[dict]:
    """Eq. 3 over the regions, with and without the warp, to one CSV per scene and SPP."""
    from .correlation import rows_from_alignment
    from .store import open_dataset
    from .tables import write_tables

    v = open_dataset(variance)[["variance", "finite"]].load()
    w = open_dataset(warped)
    gt = open_dataset(ground_truth)
    sigma_l, sigma_r = _left_right(v, "variance")
    aligned = {k: w[k].values for k in ("warped_variance", "omega", "omega_geometry", "usable")}
    aligned["warped"] = aligned.pop("warped_variance")
    rows = rows_from_alignment(
        sigma_l,
        sigma_r,
        aligned,
        gt["glass"].sel(view="left").values,
        finite_right=v["finite"].sel(view="right"),
        min_pixels=min_pixels,
    )
    for row in rows:
        row.update(scene=v.attrs["scene"], spp=int(v.attrs["spp"]), n_seeds=int(v.attrs["n_seeds"]))
        log.info(
            "%s spp %s %-9s %-7s rho %.4f (n=%d)%s",
            row["scene"],
            row["spp"],
            row["region"],
            row["method"],
            row["rho"],
            row["n_pixels"],
            f" [{row['reason']}]" if row["reason"] else "",
        )
    write_tables(rows, CORRELATION_COLUMNS, {"csv": out})
    return rows


def cross_scene_job(correlations, outputs: dict, *, spp) -> list[dict]:
    """Table 1: rho across scenes per region at the main SPP, plus the no-warp mean."""
    from .summary import CROSS_SCENE_COLUMNS, cross_scene_table
    from .tables import read_rows, write_tables

    rows = [r for path in correlations for r in read_rows(path)]
    table = cross_scene_table(rows, spp=int(spp))
    write_tables(
        table,
        CROSS_SCENE_COLUMNS,
        outputs,
        caption=f"Cross-scene correlation at SPP={spp} (Table 1)",
    )
    return table


def spp_sweep_job(correlations, variances, warped, outputs: dict, fit_outputs: dict) -> dict:
    """Table 2: mean left variance by region and rho by region at each SPP, plus the
    log-log slope of mean variance against SPP."""
    from .store import open_dataset
    from .summary import SPP_SWEEP_COLUMNS, mean_variance_by_region, spp_sweep_table, sweep_entry
    from .tables import read_rows, write_tables

    entries = []
    for csv_path, var_path, warp_path in zip(correlations, variances, warped, strict=True):
        v = open_dataset(var_path)
        w = open_dataset(warp_path)
        masks = {k: w[f"region_{k}"].values for k in ("all", "non_glass", "glass")}
        means = mean_variance_by_region(v["variance"].sel(view="left").values, masks)
        entries.append(sweep_entry(int(v.attrs["spp"]), read_rows(csv_path), means))
    rows, fit = spp_sweep_table(entries)
    write_tables(rows, SPP_SWEEP_COLUMNS, outputs, caption="SPP sweep (Table 2)")
    fit_rows = [{"region": k, **f} for k, f in fit.items()]
    write_tables(
        fit_rows,
        ["region", "slope", "intercept", "r2", "n_points", "reason"],
        fit_outputs,
        caption="Log-log slope of mean variance against SPP",
    )
    for row in fit_rows:
        log.info("log-log slope of mean variance vs SPP, %s: %.4f", row["region"], row["slope"])
    return fit


def _save_figure(fig, out) -> None:
    import matplotlib.pyplot as plt

    from .store import write_file

    write_file(out, lambda tmp: fig.savefig(tmp, format="png", dpi=120))
    plt.close(fig)


def teaser_figure_job(variance, warped, out) -> None:
    """Fig. 1: sigma_L^2, sigma_R^2, the warped field and their joint histogram over Omega."""
    from .figures import teaser_figure
    from .store import open_dataset

    v = open_dataset(variance).load()
    w = open_dataset(warped).load()
    sigma_l, sigma_r = _left_right(v, "variance")
    title = f"{v.attrs['scene']}, SPP {v.attrs['spp']}, N = {v.attrs['n_seeds']}"
    _save_figure(
        teaser_figure(sigma_l, sigma_r, w["warped_variance"], w["omega"], title=title), out
    )


def rho_vs_spp_figure_job(correlations, out) -> None:
    """Fig. 2: rho against SPP per region, with Fisher-z intervals (warp rows)."""
    from .figures import rho_vs_spp_figure
    from .tables import read_rows

    rows = [r for path in correlations for r in read_rows(path) if r["method"] == "warp"]
    scene = rows[0]["scene"] if rows else ""
    _save_figure(rho_vs_spp_figure(rows, title=f"{scene}: rho against SPP"), out)


def material_scatter_figure_job(variance, warped, ground_truth, out) -> None:
    """Fig. 3: (sigma_L^2, warped sigma_R^2) over Omega, glass against non-glass."""
    from .figures import material_scatter_figure
    from .store import open_dataset

    v = open_dataset(variance).load()
    w = open_dataset(warped).load()
    gt = open_dataset(ground_truth)
    title = f"{v.attrs['scene']}, SPP {v.attrs['spp']}"
    fig = material_scatter_figure(
        v["variance"].sel(view="left"),
        w["warped_variance"],
        w["omega"],
        gt["glass"].sel(view="left").values,
        title=title,
    )
    _save_figure(fig, out)


def margin_figure_job(margins, out) -> None:
    """The intervention's GT-margin distributions per region, normal against decorrelated."""
    from .figures import margin_distribution_figure
    from .tables import read_rows

    rows = [r for path in margins for r in read_rows(path)]
    n_scenes = len({r["scene"] for r in rows})
    title = f"GT margins, normal vs decorrelated ({n_scenes} scenes, sampled pixels)"
    _save_figure(margin_distribution_figure(rows, title=title), out)


INTERVENTION_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "max_disparity",
    "window",
    "block",
    "cost",
    "metric",
    "region",
    "condition",
    "value",
    "chance",
    "n_pixels",
    "reason",
]


MARGIN_COLUMNS = ["scene", "cost", "region", "condition", "seed", "y", "x", "margin"]


class _LazyRenders:
    """The renders of one view as a sequence that reads one store per item (never all)."""

    def __init__(self, paths):
        self.paths = list(paths)

    def __len__(self):
        return len(self.paths)

    def __getitem__(self, k):
        from .variance import RenderStore

        return RenderStore(self.paths[k]).rows(slice(None))


def intervention_job(
    left,
    right,
    ground_truth,
    out,
    margins,
    *,
    window=5,
    block=16,
    seed=0,
    max_disparity=None,
    disparity_margin=4,
    margin_samples=2000,
    workers=1,
) -> list[dict]:
    """Table 3's metrics of one scene, normal against decorrelated (paper Sec. 3.4), and a
    sample of the per-pixel GT margins for the distribution figure."""
    import math

    from .intervention import intervention_metrics
    from .store import open_dataset
    from .tables import write_tables

    gt = open_dataset(ground_truth)
    gl = {k: gt[k].sel(view="left").values for k in ("disparity", "valid", "glass")}
    largest = float(gl["disparity"][gl["valid"]].max()) if gl["valid"].any() else 0.0
    if max_disparity is None:
        max_disparity = int(math.ceil(largest)) + int(disparity_margin)
    elif max_disparity < largest:
        n_lost = int((gl["valid"] & (gl["disparity"] >= max_disparity + 1)).sum())
        log.warning(
            "intervention.max_disparity = %d is below the largest ground-truth disparity %.1f"
            " px: %d valid left pixels become unscoreable; raise it or set it to null",
            max_disparity,
            largest,
            n_lost,
        )
    result = intervention_metrics(
        _LazyRenders(left),
        _LazyRenders(right),
        gl,
        sign=int(gt.attrs["disparity_sign"]),
        max_disparity=int(max_disparity),
        window=window,
        block=block,
        seed=seed,
        margin_samples=margin_samples,
        workers=workers,
    )
    attrs = open_dataset(left[0])["radiance"].attrs
    scene = attrs.get("scene", gt.attrs.get("scene"))
    for row in result.rows:
        row.update(
            scene=scene,
            spp=attrs.get("spp"),
            n_seeds=len(left),
            max_disparity=int(max_disparity),
            window=window,
            block=block,
        )
        log.info(
            "%-13s %-13s %-9s %-12s %.4g (chance %.4g, n=%d)%s",
            row["cost"],
            row["metric"],
            row["region"],
            row["condition"],
            row["value"],
            row["chance"],
            row["n_pixels"],
            f" [{row['reason']}]" if row["reason"] else "",
        )
    for sample in result.margins:
        sample["scene"] = scene
    write_tables(result.margins, MARGIN_COLUMNS, {"csv": margins})
    write_tables(result.rows, INTERVENTION_COLUMNS, {"csv": out})
    return result.rows


def intervention_table_job(inputs, outputs: dict) -> list[dict]:
    """Table 3: mean ± std across scenes of each metric, normal and decorrelated, with the
    relative change (normal - decorrelated) / |decorrelated|."""
    from .summary import intervention_table
    from .tables import read_rows, write_tables

    rows = [r for path in inputs for r in read_rows(path)]
    table = intervention_table(rows)
    columns = list(table[0]) if table else ["cost", "metric", "region"]
    write_tables(table, columns, outputs, caption="Residual-shuffle intervention (Table 3)")
    return table


SUMMARY_COLUMNS = [
    "scene",
    "width",
    "height",
    "baseline_m",
    "convention",
    "glass_fraction",
    "valid_fraction",
    "occluded_fraction",
    "disparity_min_px",
    "disparity_median_px",
    "disparity_max_px",
    "diffuse_fraction",
    "glossy_fraction",
    "conductor_fraction",
    "emitter_fraction",
    "background_fraction",
]


def scene_summary_job(ground_truths, outputs: dict) -> list[dict]:
    """Tabulate glass fraction and disparity range of each scene's left view."""
    from .ground_truth import summarize_ground_truth
    from .store import open_dataset
    from .tables import write_tables

    rows = []
    for path in ground_truths:
        ds = open_dataset(path).load()
        rows.append(
            {
                "scene": ds.attrs["scene"],
                "width": int(ds.attrs["width"]),
                "height": int(ds.attrs["height"]),
                "baseline_m": float(ds.attrs["baseline_m"]),
                "convention": ds.attrs["convention"],
                **summarize_ground_truth(ds),
            }
        )
    write_tables(
        rows,
        SUMMARY_COLUMNS,
        outputs,
        caption="Scenes: left-view glass fraction and disparity range",
    )
    return rows


def generate_scene_job(out, *, seed: int) -> None:
    """Generate scene ``scene_NNN`` (index from the file name) with the generator seed."""
    from .scenegen import generate_scene
    from .scenespec import write_scene_spec

    name = Path(out).stem
    try:
        index = int(name.rsplit("_", 1)[1])
    except (IndexError, ValueError):
        raise StereovarError(
            f"cannot generate '{name}': generated scenes are named scene_NNN; "
            "write a spec for it in scenes/ instead"
        ) from None
    write_scene_spec(generate_scene(index, seed), out)
