"""Jobs of ``workflow/rules/correlation.smk``: the Eq. 2 warp and the Eq. 3 rows of one scene."""

from __future__ import annotations

from .common import left_right, log
from .settings import analysis_settings


def align(v, gt) -> dict:
    """Eq. 2 on a variance dataset (the variance contract) with its ground truth:
    :func:`stereovar.statistics.warp.align_variance` of the right field into the left."""
    from ..statistics.warp import align_variance

    sigma_l, sigma_r = left_right(v, "variance")
    fin_l, fin_r = left_right(v, "finite")
    return align_variance(
        sigma_l,
        sigma_r,
        gt.sel(view="left"),
        sign=int(gt.attrs["disparity_sign"]),
        finite_left=fin_l,
        finite_right=fin_r,
    )


def warp_job(variance, ground_truth, out) -> None:
    """Warp the right variance field into the left view (Eq. 2) and store Ω and the regions."""
    import numpy as np

    from ..io.contracts import warped_store
    from ..io.store import load_store, write_dataset
    from ..statistics.regions import region_masks

    v = load_store(variance, "variance store", ["variance", "finite"])
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    gl = gt.sel(view="left")
    aligned = align(v, gt)
    masks = region_masks(gl, aligned["omega"])
    attrs = {
        **v.attrs,
        "disparity_sign": int(gt.attrs["disparity_sign"]),
        "convention": gt.attrs["convention"],
    }
    write_dataset(warped_store(aligned, masks, attrs=attrs), out)
    log.info(
        "omega: %d of %d pixels (%d glass)",
        int(aligned["omega"].sum()),
        aligned["omega"].size,
        int(np.asarray(masks["glass"]).sum()),
    )


def scene_inputs(v, gt, sensor):
    """:class:`~stereovar.statistics.rows.SceneInputs` of a variance dataset (the variance
    contract) and its ground truth: the left ground truth, the seed mean, the split halves
    and the sensor model."""
    from ..statistics.rows import SceneInputs
    from .calibration import stored_encoding

    gl = gt.sel(view="left")
    views = ("left", "right")
    return SceneInputs(
        ground_truth_left={k: gl[k].values for k in ("disparity", "valid")},
        sign=int(gt.attrs["disparity_sign"]),
        mean={k: v["mean"].sel(view=k).transpose("y", "x", "channel").values for k in views}
        if "mean" in v
        else None,
        halves={k: v["half_variance"].sel(view=k).transpose("half", "y", "x").values for k in views}
        if "half_variance" in v
        else None,
        # the simulated sensor draws as many frames as the estimator drew samples per
        # pixel: N seeds, or the SPP of the moments estimator
        n_seeds=int(v.attrs.get("n_draws", v.attrs["n_seeds"])),
        sensor=sensor,
        label=f"{v.attrs['scene']}|spp{int(v.attrs['spp'])}",
        encoding=stored_encoding(v.attrs),
    )


def blank_material_regions(rows: list[dict]) -> None:
    """Make the glass and non_glass rows of a scene without a material mask NaN, with the
    reason (an audit without ``audit.glass_mask``: every pixel would count as non-glass)."""
    from ..audit.ground_truth import NO_MATERIAL_MASK
    from ..statistics.correlation import undefined_result
    from ..statistics.rows import RELIABILITY_KEYS

    for row in rows:
        if row["region"] != "all":
            row.update(undefined_result(0, row.get("n_nonfinite", 0), NO_MATERIAL_MASK))
            row.update(dict.fromkeys(RELIABILITY_KEYS, float("nan")))


def correlation_job(
    variance,
    warped,
    ground_truth,
    out,
    *,
    curve=None,
    min_pixels=30,
    analysis=None,
    controls=None,
) -> list[dict]:
    """Every registered statistic and control over every region (Eq. 3), to one CSV per scene
    and SPP, and :math:`\\rho` against the number of seeds to ``curve``."""
    from concurrent.futures import ThreadPoolExecutor

    from ..io.contracts import read_alignment
    from ..io.store import load_store
    from ..io.tables import write_tables
    from ..statistics.rows import (
        CORRELATION_COLUMNS,
        CURVE_COLUMNS,
        correlation_rows,
        seed_curve_rows,
        subset_rhos,
    )

    analysis = {"min_pixels": min_pixels, **dict(analysis or {})}
    settings, sensor = analysis_settings(analysis, controls)
    v = load_store(variance, "variance store")
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    gl = gt.sel(view="left")
    sigma_l, sigma_r = left_right(v, "variance")
    n_seeds = int(v.attrs["n_seeds"])
    scene, spp = v.attrs["scene"], int(v.attrs["spp"])
    views = ("left", "right")
    inputs = scene_inputs(v, gt, sensor)
    aligned = read_alignment(load_store(warped, "warped store"))
    glass = gl["glass"].values
    subsets = None
    if curve is not None and "subset_variance" in v:
        sv = v["subset_variance"]
        subsets = {
            k: (
                sv["subset_size"].values,
                sv["subset_index"].values,
                sv.sel(view=k).transpose("subset", "y", "x").values,
            )
            for k in views
        }
    _ = inputs.plan  # built once, before the two threads share it
    # The seed-subset curve is independent of the rows: compute it on the second core.
    with ThreadPoolExecutor(max_workers=1) as pool:
        values = pool.submit(subset_rhos, subsets, aligned, glass, settings=settings, inputs=inputs)
        rows = correlation_rows(
            sigma_l,
            sigma_r,
            aligned,
            glass,
            finite_right=v["finite"].sel(view="right"),
            settings=settings,
            inputs=inputs,
        )
        values = values.result()
    run = {
        "renderer": v.attrs.get("renderer", ""),
        "estimator": v.attrs.get("estimator", ""),
    }
    if gt.attrs.get("material_mask") == "none":
        blank_material_regions(rows)
    for row in rows:
        row.update(scene=scene, spp=spp, n_seeds=n_seeds, **run)
        log.info(
            "%s spp %s %-9s %-10s rho %.4f [boot %.3f, %.3f] (n=%d)%s",
            row["scene"],
            row["spp"],
            row["region"],
            row["method"],
            row["rho"],
            row["boot_low"],
            row["boot_high"],
            row["n_pixels"],
            f" [{row['reason']}]" if row["reason"] else "",
        )
    write_tables(rows, CORRELATION_COLUMNS, {"csv": out})
    if curve is not None:
        curve_rows = seed_curve_rows(
            subsets,
            aligned,
            glass,
            rows,
            n_seeds=n_seeds,
            settings=settings,
            inputs=inputs,
            values=values,
        )
        if gt.attrs.get("material_mask") == "none":
            curve_rows = [r for r in curve_rows if r["region"] == "all"]
        for row in curve_rows:
            row.update(scene=scene, spp=spp, **run)
        write_tables(curve_rows, CURVE_COLUMNS, {"csv": curve})
    return rows
