"""stereovar: cross-view Monte Carlo variance correlation in path-traced stereo.

Importing the package is cheap and pulls in no third-party module (numpy, Dr.Jit, Mitsuba),
so that set-up scripts can use :mod:`stereovar.backend` with the system Python before the
dependencies are installed. Import submodules explicitly, e.g. ``stereovar.backend``.
"""

__version__ = "0.1.0"

# Public API for notebooks, imported on first use so that `import stereovar` stays cheap.
_API = {
    "load_mitsuba": "backend",
    "select_variant": "backend",
    "load_scene_spec": "scenespec",
    "generate_scene": "scenegen",
    "load_scene": "mitsuba_scene",
    "make_rig": "rig",
    "StereoRig": "rig",
    "compute_ground_truth": "ground_truth",
    "summarize_ground_truth": "ground_truth",
    "MATERIAL_CLASSES": "ground_truth",
    "warp_right_to_left": "warp",
    "variance_field": "variance",
    "StreamingVariance": "variance",
    "variance_from_stores": "variance",
    "variance_dataset": "variance",
    "pearson_over_mask": "correlation",
    "align_variance": "correlation",
    "correlation_rows": "correlation",
    "region_masks": "correlation",
    "cross_scene_table": "summary",
    "spp_sweep_table": "summary",
    "teaser_figure": "figures",
    "rho_vs_spp_figure": "figures",
    "material_scatter_figure": "figures",
    "margin_distribution_figure": "figures",
    "block_permutation": "shuffle",
    "decorrelate_right": "shuffle",
    "sad_cost_volume": "costvolume",
    "scan_cost_volume": "costvolume",
    "scan_hit_rate": "costvolume",
    "gt_margin": "costvolume",
    "wta_accuracy": "costvolume",
    "peak_hit_rate": "costvolume",
    "wta_disparity": "costvolume",
    "intervention_metrics": "intervention",
    "intervention_table": "summary",
    "render_view": "render",
    "derive_seed": "render",
    "open_dataset": "store",
    "write_dataset": "store",
}

__all__ = ["__version__", *sorted(_API)]


def __getattr__(name):
    if name in _API:
        from importlib import import_module

        return getattr(import_module(f"stereovar.{_API[name]}"), name)
    raise AttributeError(f"module 'stereovar' has no attribute {name!r}")
