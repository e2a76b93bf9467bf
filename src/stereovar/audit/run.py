"""An audit as a workflow run: import, the run's config, and its targets.

``workflow/rules/common.smk`` calls :func:`prepare_audit` when the config has an ``audit:``
section, then replaces the run's scenes, renderer, N and SPP with the audit's
(:func:`audit_run_config`), so every rule downstream of the renders (Eq. 1-3, the controls,
the intervention, the tables) runs unchanged on the imported stores; ``all`` then builds
:func:`audit_targets`, ending in the verdict page.
"""

from __future__ import annotations

import sys

from ..experiment import audit_source, ground_truth_store, run_prefix
from ..io.images import image_size
from ..rig import VIEWS
from .importer import audit_spp, check_settings, import_audit
from .layout import Discovery, discover

TABLE_FORMATS = ("csv", "md", "tex", "html")


def prepare_audit(settings: dict, *, do_import: bool = True, stream=None) -> Discovery:
    """Import the audit's files (``do_import``; else only discover them, as a cluster job
    does) and print the import's summary lines to ``stream`` (stderr)."""
    check_settings(settings)
    if not do_import:
        return discover(settings)
    report = import_audit(settings)
    for line in report.lines():
        print(f"stereovar: {line}", file=stream or sys.stderr)
    return report.discovery


def audit_run_config(config: dict, discovery: Discovery) -> dict:
    """The config keys an audit replaces: ``scenes`` (its frames), ``resolution``, the rig's
    convention, and ``render`` (source ``audit/{name}``, the seeds estimator, N and SPP
    from the files, one store per view and frame, no render cache); the intervention uses
    all N seeds."""
    settings = config["audit"]
    frames = [f.name for f in discovery.frames]
    n, spp = discovery.n_seeds, audit_spp(settings)
    height, width = image_size(next(iter(discovery.frames[0].renders[VIEWS[0]].values())))
    return {
        "scenes": frames,
        "resolution": {"width": width, "height": height},
        "rig": {**config["rig"], "convention": settings.get("convention") or "conventional"},
        "render": {
            **config["render"],
            "renderer": audit_source(settings["name"]),
            "estimator": "seeds",
            "n_seeds": n,
            "seeds_per_job": n,
            "spp": spp,
            "spp_sweep": {"scene": frames[0], "spp": [spp]},
            "cache": None,
        },
        "intervention": {**config["intervention"], "n_seeds": None, "spp": None},
    }


def audit_paths(name: str) -> dict:
    """The verdict page, its summary and the per-frame teaser pattern of an audit."""
    base = f"results/{audit_source(name)}"
    return {
        "verdict_md": f"{base}/verdict.md",
        "verdict_html": f"{base}/verdict.html",
        "summary": f"{base}/summary.json",
        "teaser": base + "/figures/teaser_{scene}.png",
    }


def audit_targets(config: dict) -> list[str]:
    """What ``all`` builds for an audit: the imported ground truth, every frame's
    correlation rows and intervention, the pooled tables and figures, one teaser per frame,
    and the verdict page with its summary."""
    source = config["render"]["renderer"]
    spp = config["render"]["spp"]
    run = run_prefix(source, "seeds")
    frames = list(config["scenes"])
    paths = audit_paths(config["audit"]["name"])
    tables = ["statistics", "seed_curve", "cross_scene", "intervention"]
    return [
        *[ground_truth_store(source, f) for f in frames],
        *[f"{run}/correlation/{f}/spp{spp}.csv" for f in frames],
        *[f"{run}/intervention/{f}.csv" for f in frames],
        *[f"{run}/tables/{t}.{ext}" for t in tables for ext in TABLE_FORMATS],
        f"{run}/figures/statistics_dots.png",
        f"{run}/figures/rho_vs_seeds.png",
        *[paths["teaser"].format(scene=f) for f in frames],
        paths["verdict_md"],
        paths["verdict_html"],
        paths["summary"],
    ]
