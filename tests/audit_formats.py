"""Shared by the tests of the generators' formats (tests/test_audit_formats_*.py): one
synthetic stereo frame with a known disparity, the same frame written as EXR renders and an
EXR planar depth (the reference audit), and the comparison of two imports: their render
and ground-truth stores and the cross-view correlation computed from them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stereovar.audit.synthetic import synthetic_frame
from stereovar.estimators.seeds import variance_field
from stereovar.io.store import open_dataset
from stereovar.io.writers import write_field, write_image
from stereovar.rig import VIEWS
from stereovar.statistics.correlation import pearson_over_mask
from stereovar.statistics.warp import warp_right_to_left

WIDTH, HEIGHT, SEEDS = 48, 32, 4
FOCAL_PX, BASELINE_M = 120.0, 0.1


MARGIN_PX = 1e-3
"""The depth's disparity is the synthetic integer disparity less this much: a match then
never lands exactly on the right image's border, where the rounding of a depth conversion
(float32, Kubric's ray distance) would decide whether the pixel is valid."""


def frame(seed: int = 0):
    """A synthetic frame (conventional rig, x_R = x_L - d, d of 3..8 px), the disparity its
    depth gives and that planar depth z = f B / d."""
    f = synthetic_frame(width=WIDTH, height=HEIGHT, n_seeds=SEEDS, sign=-1, seed=seed)
    disparity = f.disparity.astype(np.float64) - MARGIN_PX
    depth = (FOCAL_PX * BASELINE_M / disparity).astype(np.float32)
    return f, depth, disparity


def write_exr_reference(root: Path, renders: dict, depth: np.ndarray, *, frame_name="f00",
                        name="exr") -> dict:
    """The frame's renders (view to (N, H, W, 3) float32) as EXR and its left planar depth as
    a one-channel EXR; returns the ``audit:`` settings that read them."""
    for view, letter in zip(VIEWS, "LR", strict=True):
        folder = root / "renders" / frame_name / letter
        folder.mkdir(parents=True, exist_ok=True)
        for s, image in enumerate(renders[view]):
            write_image(folder / f"seed_{s:03d}.exr", image)
    (root / "depth").mkdir(parents=True, exist_ok=True)
    write_field(root / "depth" / f"{frame_name}.exr", depth)
    return {
        "name": name,
        "renders": f"{root}/renders/{{frame}}/{{view}}/seed_{{seed}}.exr",
        "views": {"left": "L", "right": "R"},
        "depth": f"{root}/depth/{{frame}}.exr",
        "focal_px": FOCAL_PX,
        "baseline_m": BASELINE_M,
        "convention": "conventional",
    }


def stores(name: str, frame_name: str) -> dict:
    """The imported stores of one frame: view to its render dataset, and ``ground_truth``."""
    base = Path("results/audit") / name
    out = {
        view: open_dataset(next((base / "renders" / frame_name / view).glob("spp*/seeds*.zarr")))
        for view in VIEWS
    }
    out["ground_truth"] = open_dataset(base / "ground_truth" / f"{frame_name}.zarr")
    return out


def correlation(imported: dict) -> dict:
    """Eq. 1-3 on imported stores: each view's seed variance field, the right one warped into
    the left by the ground truth, and Pearson's rho over the valid pixels."""
    gt = imported["ground_truth"]
    left = gt.sel(view="left")
    fields = {
        view: variance_field(imported[view]["radiance"].values.astype(np.float64))[1]
        for view in VIEWS
    }
    warped, omega = warp_right_to_left(
        fields["right"], left["disparity"].values, sign=int(gt.attrs["disparity_sign"]),
        valid=left["valid"].values,
    )
    return pearson_over_mask(fields["left"], warped, omega)


def assert_same_import(a: dict, b: dict, *, renders_rtol=0.0, disparity_rtol=1e-5) -> None:
    """Two imports of the same frames hold the same renders (exactly unless ``renders_rtol``),
    the same ground truth (disparity and depth to ``disparity_rtol``; valid, occluded and
    glass equal) and give the same rho (to the arithmetic of the disparities' rounding)."""
    for view in VIEWS:
        np.testing.assert_allclose(
            a[view]["radiance"].values, b[view]["radiance"].values, rtol=renders_rtol, atol=0
        )
    ga, gb = a["ground_truth"], b["ground_truth"]
    for var in ("valid", "occluded", "glass"):
        np.testing.assert_array_equal(ga[var].values, gb[var].values, err_msg=var)
    for var in ("disparity", "depth"):
        np.testing.assert_allclose(ga[var].values, gb[var].values, rtol=disparity_rtol,
                                   atol=0, err_msg=var)
    ra, rb = correlation(a), correlation(b)
    assert ra["n_pixels"] == rb["n_pixels"] > 100
    assert abs(ra["rho"] - rb["rho"]) < 1e-4 + renders_rtol
