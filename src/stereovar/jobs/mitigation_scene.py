"""Job ``mitigation_scene`` of ``workflow/rules/mitigations.smk``: one scene's mitigation
measurements, the cross-view residual correlation and the image quality against a converged
reference."""

from __future__ import annotations

import numpy as np

from .common import log, view_stack
from .reference import _reference

MITIGATION_SCENE_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "region",
    "quantity",
    "value",
    "low",
    "high",
    "n_pixels",
    "reason",
]
"""Columns of ``results/{source}[/{transform}]/seeds/mitigation/{scene}/spp{spp}.csv``: one
row per region and quantity (:data:`SCENE_QUANTITIES`)."""

RESIDUAL_QUANTITIES = {"ground_truth": "residual_rho_gt", "zero": "residual_rho_zero"}
"""The quantity of each alignment's residual correlation over every disparity; a band's is
``{quantity}_{band}`` (:func:`stereovar.statistics.residuals.band_label`, e.g.
``residual_rho_gt_d0-2``)."""


SCENE_QUANTITIES = (
    "residual_rho_gt",
    "residual_rho_zero",
    # per band of stereovar.statistics.residuals.DISPARITY_BANDS (literal: this module imports
    # no statistics at import time)
    "residual_rho_gt_d0-2",
    "residual_rho_gt_d2-8",
    "residual_rho_gt_d8-inf",
    "residual_rho_zero_d0-2",
    "residual_rho_zero_d2-8",
    "residual_rho_zero_d8-inf",
    "psnr",
    "mse",
    "relative_mse",
    "bias",
    "relative_bias",
    "reference_noise",
    "transform_ms_per_mpix",
)
"""What one scene's mitigation rows measure: the cross-view residual correlation, each pixel
standardised, at the ground-truth alignment and at zero disparity over every disparity (with
block-bootstrap intervals) and per disparity band
(:data:`stereovar.statistics.residuals.DISPARITY_BANDS`), the image quality of the images
against the converged reference (both views pooled), and the store transform's time per
megapixel (NaN for renders that were not transformed)."""


def mitigation_scene_job(
    left, right, ground_truth, reference: dict, out, *, analysis=None, controls=None
) -> list[dict]:
    """One scene's mitigation measurements (:data:`MITIGATION_SCENE_COLUMNS`).

    ``left`` and ``right`` are the view's render stores (transformed or not), ``reference``
    maps each view to its converged reference: a moment store
    (:func:`stereovar.statistics.utility.image_quality`), or the source's untransformed render
    stores (an audit's, Cycles'), split in half
    (:func:`~stereovar.jobs.reference.split_half_images`,
    :func:`stereovar.statistics.utility.split_half_quality`). The residual correlation
    (:func:`stereovar.statistics.residuals.residual_correlation`, each pixel standardised) is
    over the left view's regions of the valid set :math:`\\Omega`, over every disparity and
    per band of :data:`~stereovar.statistics.residuals.DISPARITY_BANDS`; the image quality over
    each view's own regions (its ground-truth glass mask), both views pooled by pixel count.
    """
    from ..io.store import load_store
    from ..io.tables import write_tables
    from ..statistics.regions import REGIONS, region_masks, valid_set
    from ..statistics.residuals import ALL_BANDS, DISPARITY_BANDS, residual_correlation
    from .settings import analysis_settings

    settings, _ = analysis_settings(analysis, controls)
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    stacks, attrs, seed_order, loaded = {}, {}, {}, {}
    paths_of = {"left": left, "right": right}
    for view, paths in paths_of.items():
        stacks[view], seeds, _, attrs[view] = view_stack(paths)
        loaded[tuple(str(p) for p in paths)] = (stacks[view], seeds)
        order = np.argsort(seeds, kind="stable")
        stacks[view], seed_order[view] = stacks[view][order], seeds[order]
    gl = gt.sel(view="left")
    sign = int(gt.attrs.get("disparity_sign", 1))
    disparity = gl["disparity"].transpose("y", "x").values
    omega = valid_set(disparity, sign=sign, valid=gl["valid"].transpose("y", "x").values)
    masks = region_masks(gl, omega)
    material = gt.attrs.get("material_mask") != "none"
    regions = REGIONS if material else ("all",)
    masks = {r: masks[r] for r in regions}
    scene, spp = attrs["left"].get("scene", ""), int(attrs["left"].get("spp", 0))
    n_seeds = int(stacks["left"].shape[0])
    rows = []

    def add(region, quantity, value, low=np.nan, high=np.nan, n_pixels=0, reason=""):
        rows.append(
            {
                "scene": scene,
                "spp": spp,
                "n_seeds": n_seeds,
                "region": region,
                "quantity": quantity,
                "value": float(value),
                "low": float(low),
                "high": float(high),
                "n_pixels": int(n_pixels),
                "reason": reason,
            }
        )

    residual = residual_correlation(
        stacks["left"],
        stacks["right"],
        disparity,
        sign=sign,
        masks=masks,
        valid=gl["valid"].transpose("y", "x").values,
        bands=DISPARITY_BANDS,
        settings=settings.bootstrap,
        min_pixels=settings.min_pixels,
    )
    for r in residual:
        quantity = RESIDUAL_QUANTITIES[r["alignment"]]
        if r["band"] != ALL_BANDS:
            quantity = f"{quantity}_{r['band']}"
        add(r["region"], quantity, r["rho"], r["low"], r["high"], r["n_pixels"], r["reason"])
    refs = {
        view: _reference(
            reference[view],
            loaded,
            images=stacks[view],
            seeds=seed_order[view],
            attrs=attrs[view],
            paths=paths_of[view],
            view=view,
        )
        for view in ("left", "right")
    }
    for region in regions:
        per_view = []
        for view in ("left", "right"):
            glass = gt.sel(view=view)["glass"].transpose("y", "x").values.astype(bool)
            mask = {"all": None, "glass": glass, "non_glass": ~glass}[region]
            per_view.append(refs[view](mask))
        pooled = _pooled_quality(per_view)
        for quantity in ("psnr", "mse", "relative_mse", "bias", "relative_bias"):
            add(
                region,
                quantity,
                pooled[quantity],
                n_pixels=pooled["n_pixels"],
                reason=pooled["reason"] if quantity == "psnr" else "",
            )
        add(region, "reference_noise", pooled["reference_noise"], n_pixels=pooled["n_pixels"])
    seconds = sum(float(a.get("transform_seconds", np.nan)) for a in attrs.values())
    mpix = sum(float(a.get("transform_megapixels", np.nan)) for a in attrs.values())
    add(
        "all",
        "transform_ms_per_mpix",
        1e3 * seconds / mpix if mpix > 0 else np.nan,
        reason="" if np.isfinite(seconds) else "renders not transformed",
    )
    write_tables(rows, MITIGATION_SCENE_COLUMNS, {"csv": out})
    for r in rows:
        if r["quantity"] in ("residual_rho_gt", "residual_rho_zero", "psnr"):
            log.info(
                "%s spp %d %-9s %-17s %.4f [%.4f, %.4f]%s",
                scene,
                spp,
                r["region"],
                r["quantity"],
                r["value"],
                r["low"],
                r["high"],
                f" [{r['reason']}]" if r["reason"] else "",
            )
    return rows


def _pooled_quality(per_view: list[dict]) -> dict:
    """Image quality of several views pooled by pixel count.

    MSE, relative MSE, bias, the reference noise and the reference mean are pixel-weighted
    means of the views'; the relative bias is the pooled bias over the pooled reference mean,
    and PSNR follows from the pooled MSE (:func:`stereovar.statistics.utility.image_quality`'s
    peak).
    """
    from ..statistics.utility import NOT_ABOVE_NOISE, PEAK

    nan = float("nan")
    weights = np.array([float(q["n_pixels"]) for q in per_view])
    keys = ("mse", "relative_mse", "bias", "reference_noise", "reference_mean")
    if weights.sum() == 0:
        return {
            **dict.fromkeys((*keys, "psnr", "relative_bias"), nan),
            "n_pixels": 0,
            "reason": per_view[0]["reason"],
        }
    w = weights / weights.sum()
    used = [(wi, q) for wi, q in zip(w, per_view, strict=True) if wi > 0]
    out = {k: float(sum(wi * float(q[k]) for wi, q in used)) for k in keys}
    ref = out["reference_mean"]
    out["relative_bias"] = out["bias"] / ref if ref else nan
    out.update(n_pixels=int(weights.sum()), reason="")
    if out["mse"] > 0:
        out["psnr"] = float(10 * np.log10(PEAK**2 / out["mse"]))
    else:
        out["psnr"] = nan
        out["reason"] = NOT_ABOVE_NOISE
    return out
