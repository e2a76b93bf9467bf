"""Export this project's renders, variance fields and ground truth as files other tools read.

One scene goes to one directory (written atomically)::

    {out}/renders/{L,R}/seed_{k:03d}.{ext}   every render of each view
    {out}/disparity/{L,R}.{ext}               disparity magnitude in px (0 = invalid)
    {out}/glass/left.{ext}                    the left view's glass mask (1 = glass)
    {out}/variance/{left,right}.{ext}         Eq. 1's variance fields (.npy for PNG)
    {out}/audit.yaml                          an ``audit:`` section that reads the export

with ``ext`` one of ``exr`` (float32), ``pfm``, ``npy`` or ``png`` (renders 16-bit sRGB with
a full scale just above the brightest value; disparity in KITTI's encoding, value / 256).
The ``audit.yaml`` templates have ``{frame}`` in place of the scene's directory, so it audits
every scene exported to the same format (PNG: this scene only, whose full scale it names).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import yaml

from .. import layout
from ..errors import StereovarError
from ..io.renders import LazyRenders
from ..io.store import atomic_path, load_store
from ..io.writers import write_field, write_image
from ..rig import VIEWS

EXPORT_FORMATS = ("exr", "pfm", "npy", "png")
"""Formats of :func:`export_scene`."""

LETTERS = {"left": "L", "right": "R"}


def export_targets(config: dict, fmt: str) -> list[str]:
    """The scene directories ``snakemake export`` writes in format ``fmt`` for a validated
    workflow config: ``results/export/{renderer}/{estimator}/{fmt}/{scene}``."""
    render = config["render"]
    return [
        layout.export_dir(render["renderer"], render["estimator"], fmt, scene)
        for scene in config["scenes"]
    ]


def check_export_targets(targets) -> None:
    """Check that each export target is absent or an export this workflow wrote.

    Snakemake takes any file, folder or symbolic link at an output path for that output,
    and writes nothing when it is newer than the inputs. An export is a real directory
    holding its ``audit.yaml`` (written last, :func:`export_scene`); anything else at a
    target would pass for one.

    Parameters
    ----------
    targets : iterable of path-like
        Export scene directories (:func:`export_targets`).

    Raises
    ------
    StereovarError
        One line naming the first target that is a symbolic link, or that exists but holds
        no export, and how to fix it.
    """
    for target in map(Path, targets):
        if target.is_symlink():
            raise StereovarError(
                f"{target} is a symbolic link (to {os.readlink(target)}), which Snakemake "
                "takes for a finished export and writes nothing to; remove the link "
                f"(rm {target}) and export again (to keep exports on another disk, link "
                "results/export instead)"
            )
        if target.exists() and not (target / "audit.yaml").is_file():
            raise StereovarError(
                f"{target} exists but holds no export (no audit.yaml), and Snakemake would "
                f"take it for one; move it away (or remove it) and export again"
            )


def png_full_scale(renders: dict) -> float:
    """The PNG full scale of an export: the brightest finite render value over both views,
    rounded up to 2 significant digits (so nothing clips)."""
    peak = 0.0
    for paths in renders.values():
        for image in LazyRenders(paths):
            finite = np.asarray(image)[np.isfinite(image)]
            if finite.size:
                peak = max(peak, float(finite.max()))
    if peak <= 0:
        return 1.0
    digits = 10 ** (math.floor(math.log10(peak)) - 1)
    return float(math.ceil(peak / digits) * digits)


def export_scene(
    renders: dict, ground_truth, out, *, fmt: str, scene: str, variance=None, spp=None
) -> dict:
    """Write one scene's renders, disparity, glass mask and variance fields as files.

    Parameters
    ----------
    renders : dict
        View to the render store paths (:mod:`stereovar.io.renders`) of its seeds.
    ground_truth : path-like
        The scene's ground-truth store.
    out : path-like
        The scene's export directory (replaced atomically).
    fmt : {"exr", "pfm", "npy", "png"}, keyword-only
    scene : str, keyword-only
        The scene's name (its directory name is the audit's ``{frame}``).
    variance : path-like, optional
        The scene's variance store (Eq. 1).
    spp : int, optional
        Samples per pixel of the renders (``audit.spp``).

    Returns
    -------
    dict
        The ``audit:`` settings that read the export (also written to ``audit.yaml``).
    """
    if fmt not in EXPORT_FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; use one of {', '.join(EXPORT_FORMATS)}")
    out = Path(out)
    gt = load_store(ground_truth, "ground-truth store")
    scale = png_full_scale(renders) if fmt == "png" else 1.0
    image_options = {"transfer": "srgb", "scale": scale} if fmt == "png" else {}
    field_ext = "npy" if fmt == "png" else fmt
    with atomic_path(out) as tmp:
        for view in VIEWS:
            folder = tmp / "renders" / LETTERS[view]
            folder.mkdir(parents=True)
            for k, image in enumerate(LazyRenders(renders[view])):
                write_image(folder / f"seed_{k:03d}.{fmt}", image, **image_options)
            (tmp / "disparity").mkdir(exist_ok=True)
            write_field(
                tmp / "disparity" / f"{LETTERS[view]}.{fmt}", gt["disparity"].sel(view=view).values
            )
            if variance is not None:
                v = load_store(variance, "variance store", ["variance"])
                (tmp / "variance").mkdir(exist_ok=True)
                write_field(
                    tmp / "variance" / f"{view}.{field_ext}", v["variance"].sel(view=view).values
                )
        (tmp / "glass").mkdir()
        write_field(
            tmp / "glass" / f"left.{fmt}",
            gt["glass"].sel(view="left").values.astype(np.float32),
            png_scale=1.0,
        )
        base = out.parent.as_posix()
        settings = {
            "name": "-".join(out.parts[-4:-1]).replace("_", "-"),
            "renders": f"{base}/{{frame}}/renders/{{view}}/seed_{{seed}}.{fmt}",
            "views": dict(LETTERS),
            "disparity": f"{base}/{{frame}}/disparity/{{view}}.{fmt}",
            "glass_mask": f"{base}/{{frame}}/glass/left.{fmt}",
            "convention": str(gt.attrs.get("convention", "paper")),
        }
        if spp:
            settings["spp"] = int(spp)
        if fmt == "png":  # the full scale is this scene's: the config reads this scene only
            settings = {
                key: value.replace("{frame}", out.name) if isinstance(value, str) else value
                for key, value in settings.items()
            }
            settings.update(
                name=f"{settings['name']}-{scene}".replace("_", "-"),
                frame=scene,
                transfer="srgb",
                scale=scale,
                disparity_scale=256.0,
            )
        (tmp / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}, sort_keys=False))
    return settings
