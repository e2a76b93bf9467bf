"""The verdict page's figure of where the cue is strongest (:mod:`stereovar.audit.strongest`).

One row per frame: the frame with its top tiles outlined and numbered by rank, the map of
the tiles' local intensity-controlled correlation :math:`\\rho_t`, and the top tile's two
residual fields :math:`e_L` and :math:`e_{R\\to L}` side by side, so the reader sees the
pattern the two views share.
"""

from __future__ import annotations

import numpy as np

from .preview import to_display


def _outline(ax, rows, *, scale: float = 1.0, color="#ffd400"):
    from matplotlib.patches import Rectangle

    for r in rows:
        x0, y0 = r["x0"] * scale - 0.5, r["y0"] * scale - 0.5
        w, h = (r["x1"] - r["x0"]) * scale, (r["y1"] - r["y0"]) * scale
        edge = color if r.get("stands_out") else "#ffffff"
        ax.add_patch(Rectangle((x0, y0), w, h, fill=False, edgecolor=edge, linewidth=1.6,
                               linestyle="-" if r.get("stands_out") else "--"))
        ax.text(x0 + 2 * scale, y0 + 2 * scale, str(r["rank"]), color="black", fontsize=8,
                va="top", ha="left", bbox={"facecolor": edge, "edgecolor": "none", "pad": 1})


def strongest_figure(frames: list[dict], *, tile: int):
    """The figure (see the module docstring).

    Parameters
    ----------
    frames : list of dict
        One per row: ``frame`` (name), ``image`` (H, W, 3 linear RGB: the left seed mean),
        ``rho`` (the tiles' :math:`\\rho_t` map), ``rows`` (the ranked tiles,
        :data:`stereovar.audit.strongest.TILE_COLUMNS`), ``e_left`` and ``e_right`` (H, W).
        None: a figure that says so (the workflow declares the file).
    tile : int
        The tile side in pixels.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not frames:
        fig, ax = plt.subplots(figsize=(6.0, 1.2), constrained_layout=True)
        ax.axis("off")
        ax.text(0.5, 0.5, "no frame with a defined intensity-controlled ρ to rank tiles in",
                ha="center", va="center")
        return fig
    n = len(frames)
    height, width = frames[0]["image"].shape[:2]
    aspect = height / width
    fig, axes = plt.subplots(
        n, 4, figsize=(12.0, n * max(2.2, 2.9 * aspect) + 0.4), squeeze=False,
        constrained_layout=True, gridspec_kw={"width_ratios": [1, 1, 0.5, 0.5]},
    )
    cmap = plt.get_cmap("RdBu_r").with_extremes(bad="#d0d0d0")
    im = None
    for row, f in zip(axes, frames, strict=False):
        rows = f["rows"]
        row[0].imshow(to_display(f["image"]), interpolation="nearest")
        _outline(row[0], rows)
        row[0].set_title(f"frame {f['frame']}: top {len(rows)} tiles", fontsize="medium")
        im = row[1].imshow(np.ma.masked_invalid(f["rho"]), cmap=cmap, vmin=-1, vmax=1,
                           interpolation="nearest")
        _outline(row[1], rows, scale=1.0 / tile)
        row[1].set_title(f"local ρ per {tile}×{tile} px tile", fontsize="medium")
        if rows:
            top = rows[0]
            box = np.s_[top["y0"] : top["y1"], top["x0"] : top["x1"]]
            crops = [f["e_left"][box], f["e_right"][box]]
            finite = np.concatenate([c[np.isfinite(c)] for c in crops]) if crops else []
            lim = float(np.percentile(np.abs(finite), 98)) if len(finite) else 1.0
            for ax, crop, name in zip(row[2:], crops, ("left", "right → left"), strict=True):
                ax.imshow(np.ma.masked_invalid(crop), cmap="PuOr_r", vmin=-lim, vmax=lim,
                          interpolation="nearest")
                ax.set_title(f"{f['frame']}\ntile 1, {name}", fontsize="medium")
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
    if im is not None:
        fig.colorbar(im, ax=axes[:, 1], shrink=0.8, label="local ρ")
    return fig
