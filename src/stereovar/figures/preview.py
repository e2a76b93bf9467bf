"""Preview figure of one scene: both renders, the disparity and the material map."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..ground_truth import MATERIAL_CLASSES
from .layout import wrap_to_width

MATERIAL_COLOURS = {
    "background": "#000000",
    "diffuse": "#b0b0b0",
    "glossy": "#4c72b0",
    "conductor": "#dd8452",
    "glass": "#c44e52",
    "emitter": "#f2e14c",
}


def auto_exposure(rgb) -> float:
    """Scale that maps the 99th percentile of luminance (RGB mean) to 1 (1 for a black image)."""
    lum = np.nan_to_num(np.asarray(rgb, dtype=np.float64)).mean(axis=-1)
    p99 = float(np.percentile(lum, 99)) if lum.size else 0.0
    return 1.0 / p99 if p99 > 0 else 1.0


def to_display(rgb, *, exposure: float | None = None) -> np.ndarray:
    """Linear radiance to 8-bit-ready sRGB in [0, 1].

    The exposure maps the 99th percentile of luminance to 1 unless given.

    .. math::

        c_{\\mathrm{sRGB}} = \\begin{cases} 1.055\\,c^{1/2.4} - 0.055 & c > 0.0031308 \\\\
        12.92\\,c & \\text{otherwise} \\end{cases}
    """
    rgb = np.nan_to_num(np.asarray(rgb, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    if exposure is None:
        exposure = auto_exposure(rgb)
    c = np.clip(rgb * exposure, 0.0, 1.0)
    return np.where(c > 0.0031308, 1.055 * np.power(c, 1 / 2.4) - 0.055, 12.92 * c)


def preview_figure(left, right, gt: xr.Dataset, *, title: str = "", spp: int | None = None):
    """A 2x2 matplotlib figure: left render, right render, left disparity, left material map.

    Parameters
    ----------
    left, right : numpy.ndarray, shape (H, W, 3)
        Linear RGB renders of the two views.
    gt : xarray.Dataset
        Ground truth of the scene (:func:`stereovar.ground_truth.compute_ground_truth`).
    title : str
        Figure title.
    spp : int, optional
        Samples per pixel of the renders, shown in the panel titles.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    g = gt.sel(view="left")
    height, width = g.sizes["y"], g.sizes["x"]
    aspect = height / width
    fig, axes = plt.subplots(2, 2, figsize=(11, 11 * aspect + 1.6), constrained_layout=True)
    exposure = auto_exposure(left)  # shared by both views
    suffix = f" ({spp} spp)" if spp else ""
    for ax, img, name in ((axes[0, 0], left, "left"), (axes[0, 1], right, "right")):
        ax.imshow(to_display(img, exposure=exposure), interpolation="nearest")
        ax.set_title(f"{name} render{suffix}")
    disp = np.where(g["valid"].values, g["disparity"].values, np.nan)
    cmap = plt.get_cmap("viridis").with_extremes(bad="#808080")
    im = axes[1, 0].imshow(np.ma.masked_invalid(disp), cmap=cmap, interpolation="nearest")
    sign = "+" if gt.attrs.get("disparity_sign", 1) > 0 else "-"
    axes[1, 0].set_title(f"left disparity [px], x_R = x_L {sign} d (grey: invalid)")
    fig.colorbar(im, ax=axes[1, 0], shrink=0.8, label="disparity [px]")
    colours = ListedColormap([MATERIAL_COLOURS[m] for m in MATERIAL_CLASSES])
    axes[1, 1].imshow(
        g["material"].values,
        cmap=colours,
        vmin=-0.5,
        vmax=len(MATERIAL_CLASSES) - 0.5,
        interpolation="nearest",
    )
    glass = float(g["glass"].values.mean())
    axes[1, 1].set_title(f"left material classes (glass {100 * glass:.1f}% of pixels)")
    axes[1, 1].legend(
        handles=[Patch(color=MATERIAL_COLOURS[m], label=m) for m in MATERIAL_CLASSES],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.02),
        ncol=3,
        fontsize="small",
        frameon=False,
    )
    for ax in axes.ravel():
        ax.set_xticks([])
        ax.set_yticks([])
    if title:
        fig.suptitle(title)
    return fig


def thumbnail_figure(render, gt: xr.Dataset, *, title: str = ""):
    """One imported frame at a glance: a render of the left view, its disparity and, with a
    material mask, the glass region: the reader of an audit sees that the right files (and
    channels) were read.

    Parameters
    ----------
    render : numpy.ndarray, shape (H, W, 3)
        Linear RGB (one seed of the left view).
    gt : xarray.Dataset
        The frame's ground truth (imported: ``disparity``, ``valid``, ``glass``).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = gt.sel(view="left")
    masked = gt.attrs.get("material_mask", "none") != "none"
    height, width = g.sizes["y"], g.sizes["x"]
    panels = 3 if masked else 2
    fig, axes = plt.subplots(
        1, panels, figsize=(3.6 * panels, 3.6 * height / width + 0.9), constrained_layout=True
    )
    axes[0].imshow(to_display(render), interpolation="nearest")
    axes[0].set_title("left render (seed 0)", fontsize="medium")
    valid = g["valid"].transpose("y", "x").values
    disp = np.where(valid, g["disparity"].transpose("y", "x").values, np.nan)
    cmap = plt.get_cmap("viridis").with_extremes(bad="#808080")
    im = axes[1].imshow(np.ma.masked_invalid(disp), cmap=cmap, interpolation="nearest")
    axes[1].set_title(f"left disparity [px] ({100 * valid.mean():.0f}% valid)", fontsize="medium")
    fig.colorbar(im, ax=axes[1], shrink=0.8)
    if masked:
        glass = g["glass"].transpose("y", "x").values.astype(bool)
        shade = to_display(render) * 0.35
        shade[glass] = (0.77, 0.31, 0.32)
        axes[2].imshow(shade, interpolation="nearest")
        axes[2].set_title(f"glass ({100 * glass.mean():.1f}% of pixels)", fontsize="medium")
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    if title:  # file paths run long: the title wraps to the figure's width
        fig.suptitle(wrap_to_width(title, fig.get_figwidth(), fontsize=10.0), fontsize="medium")
    return fig
