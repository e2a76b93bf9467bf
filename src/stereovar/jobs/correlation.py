"""Jobs of ``workflow/rules/correlation.smk``: the Eq. 2 warp and the Eq. 3 rows of one scene."""

from __future__ import annotations

from .common import left_right, log


def warp_job(variance, ground_truth, out) -> None:
    """Warp the right variance field into the left view (Eq. 2) and store Ω and the regions."""
    import numpy as np

    from ..io.contracts import warped_store
    from ..io.store import open_dataset, write_dataset
    from ..statistics.regions import region_masks
    from ..statistics.warp import align_variance

    v = open_dataset(variance)[["variance", "finite"]].load()
    gt = open_dataset(ground_truth)
    gl = gt[["disparity", "valid", "glass"]].sel(view="left").load()
    sigma_l, sigma_r = left_right(v, "variance")
    fin_l, fin_r = left_right(v, "finite")
    aligned = align_variance(
        sigma_l,
        sigma_r,
        gl,
        sign=int(gt.attrs["disparity_sign"]),
        finite_left=fin_l,
        finite_right=fin_r,
    )
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


def correlation_job(variance, warped, ground_truth, out, *, min_pixels=30) -> list[dict]:
    """Every registered statistic over every region (Eq. 3), to one CSV per scene and SPP."""
    from ..io.contracts import read_alignment
    from ..io.store import open_dataset
    from ..io.tables import write_tables
    from ..statistics.rows import CORRELATION_COLUMNS, correlation_rows

    v = open_dataset(variance)[["variance", "finite"]].load()
    gt = open_dataset(ground_truth)
    sigma_l, sigma_r = left_right(v, "variance")
    rows = correlation_rows(
        sigma_l,
        sigma_r,
        read_alignment(open_dataset(warped)),
        gt["glass"].sel(view="left").values,
        finite_right=v["finite"].sel(view="right"),
        min_pixels=min_pixels,
    )
    for row in rows:
        row.update(
            scene=v.attrs["scene"],
            spp=int(v.attrs["spp"]),
            n_seeds=int(v.attrs["n_seeds"]),
            renderer=v.attrs.get("renderer", ""),
            estimator=v.attrs.get("estimator", ""),
        )
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
