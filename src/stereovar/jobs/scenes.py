"""Jobs of ``workflow/rules/scenes.smk`` and the scene table: generate specs, tabulate scenes."""

from __future__ import annotations

from pathlib import Path

from ..errors import StereovarError

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
"""Columns of ``results/tables/scenes.{csv,md,tex}``."""


def generate_scene_job(out, *, seed: int) -> None:
    """Generate scene ``scene_NNN`` (index from the file name) with the generator seed."""
    from ..scenes.generate import generate_scene
    from ..scenes.spec import write_scene_spec

    name = Path(out).stem
    try:
        index = int(name.rsplit("_", 1)[1])
    except (IndexError, ValueError):
        raise StereovarError(
            f"cannot generate '{name}': generated scenes are named scene_NNN; "
            "write a spec for it in scenes/ instead"
        ) from None
    write_scene_spec(generate_scene(index, seed), out)


def scene_summary_job(ground_truths, outputs: dict) -> list[dict]:
    """Tabulate glass fraction and disparity range of each scene's left view."""
    from ..ground_truth import summarize_ground_truth
    from ..io.store import load_store
    from ..io.tables import write_tables

    rows = []
    for path in ground_truths:
        ds = load_store(path, "ground-truth store")
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
