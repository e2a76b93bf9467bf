"""stereovar: cross-view Monte Carlo variance correlation in path-traced stereo.

Importing the package is cheap and pulls in no third-party module (numpy, Dr.Jit, Mitsuba),
so that set-up scripts can use :mod:`stereovar.renderers.mitsuba.backend` with the system
Python before the dependencies are installed.

The names of :data:`__all__` (Eq. 1 :func:`variance_field`, Eq. 2 :func:`warp_right_to_left`,
Eq. 3 :func:`pearson_over_mask`, the stores, the registries, the tables and the figures) are
attributes of the package, each imported from its module on first access; ``dir(stereovar)``
lists them, and ``__init__.pyi`` declares them for type checkers and editors. Everything else
is imported from its module, e.g. ``stereovar.statistics.bootstrap``.

The Mitsuba-only names ``load_mitsuba``, ``select_variant``, ``load_scene``,
``render_view`` and ``MitsubaScene`` live in :mod:`stereovar.renderers.mitsuba`; their old
top-level names still resolve, with a :class:`DeprecationWarning`, until the next release.

A workflow job runs without dask: the ``Snakefile`` sets ``STEREOVAR_DASK=0`` for its jobs,
and importing the package before xarray then marks dask absent, so that xarray, which reads
every store numpy-backed here, does not import it (about 0.3 CPU-s a job,
``bench/job_overhead.py``). Set ``STEREOVAR_DASK=1`` before a run to keep it.
"""

import os as _os
import sys as _sys

__version__ = "0.1.0"

if (_os.environ.get("STEREOVAR_DASK") == "0"
        and not {"dask", "xarray"} & set(_sys.modules)):  # xarray decides at its import
    _sys.modules["dask"] = None  # importlib.util.find_spec("dask") is then None

# Public API for notebooks, imported on first use so that `import stereovar` stays cheap.
_API = {
    "get_renderer": "renderers",
    "RENDERERS": "renderers",
    "load_scene_spec": "scenes.spec",
    "generate_scene": "scenes.generate",
    "make_rig": "rig",
    "StereoRig": "rig",
    "compute_ground_truth": "ground_truth",
    "summarize_ground_truth": "ground_truth",
    "MATERIAL_CLASSES": "ground_truth",
    "derive_seed": "seeding",
    "render_seed": "seeding",
    "SEED_POLICIES": "seeding",
    "get_estimator": "estimators",
    "ESTIMATORS": "estimators",
    "variance_field": "estimators.seeds",
    "StreamingVariance": "estimators.seeds",
    "variance_from_stores": "estimators.seeds",
    "variance_dataset": "estimators.seeds",
    "warp_right_to_left": "statistics.warp",
    "align_variance": "statistics.warp",
    "valid_set": "statistics.regions",
    "region_masks": "statistics.regions",
    "REGIONS": "statistics.regions",
    "pearson_over_mask": "statistics.correlation",
    "METHODS": "statistics.registry",
    "register_method": "statistics.registry",
    "correlation_rows": "statistics.rows",
    "cross_scene_table": "statistics.summary",
    "spp_sweep_table": "statistics.summary",
    "intervention_table": "statistics.summary",
    "block_permutation": "intervention.shuffle",
    "apply_block_permutation": "intervention.shuffle",
    "scan_cost_volume": "intervention.scan",
    "scan_hit_rate": "intervention.scan",
    "wta_disparity": "intervention.scan",
    "intervention_metrics": "intervention.metrics",
    "teaser_figure": "figures.teaser",
    "rho_vs_spp_figure": "figures.rho_vs_spp",
    "material_scatter_figure": "figures.material_scatter",
    "margin_distribution_figure": "figures.margins",
    "open_dataset": "io.store",
    "write_dataset": "io.store",
    "RenderStore": "io.renders",
}

_DEPRECATED = {
    name: "renderers.mitsuba"
    for name in ("MitsubaScene", "load_mitsuba", "load_scene", "render_view", "select_variant")
}
"""Old top-level names kept for one release: each resolves to the same object in its new
module, with a :class:`DeprecationWarning` that names it."""

__all__ = ["__version__", *sorted(_API)]


def __getattr__(name: str):
    if name in _API:
        from importlib import import_module

        return getattr(import_module(f"stereovar.{_API[name]}"), name)
    if name in _DEPRECATED:
        import warnings
        from importlib import import_module

        new = f"stereovar.{_DEPRECATED[name]}"
        warnings.warn(
            f"stereovar.{name} is deprecated and will be removed in the next release; "
            f"use {new}.{name}",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(import_module(new), name)
    raise AttributeError(f"module 'stereovar' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
