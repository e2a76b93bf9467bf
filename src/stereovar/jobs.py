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
