"""Where the cue is strongest: on a frame with a cue planted in known tiles the ranking finds
those tiles, and on its matched null no ranked tile stands out."""

import math

import numpy as np
import pytest

from stereovar.audit.strongest import (
    TILE,
    frame_ranking,
    rank_tiles,
    residual_fields,
    tile_correlation,
)
from stereovar.audit.synthetic import shift_rows, synthetic_frame
from stereovar.calibration.synthesis import draw_frames, smooth_field
from stereovar.estimators.seeds import variance_field
from stereovar.statistics.fields import channel_mean
from stereovar.statistics.warp import warp_right_to_left

PLANTED = [(1, 2), (3, 5), (4, 0)]
"""(tile row, tile column) of the planted cue in a 6 x 8 grid of 32-pixel tiles."""


def planted_frame(tiles, *, strength=0.8, seed=0, n_seeds=16):
    """A 192 x 256 frame from ``N`` noisy renders per view whose noise follows a camera law
    :math:`a\\mu + b` times :math:`e^{s z_V - s^2/2}`, with :math:`z_V` a smooth pattern of
    each view (stereovar.calibration.synthesis.smooth_field): independent between the views
    everywhere except in ``tiles`` (left coordinates), where the right view sees the left
    pattern carried by the disparity, as a Monte Carlo pattern tied to the scene would be.
    Returns the Eq. 1 fields and the Eq. 2 warp as the audit's stores hold them."""
    frame = synthetic_frame(width=256, height=192, n_seeds=2, seed=seed)
    rng = np.random.default_rng(100 + seed)
    height, width = frame.disparity.shape
    shift = -frame.disparity[:, 0].astype(int)  # sign -1: x_R = x_L - d
    inside = np.zeros((height, width), bool)
    for ty, tx in tiles:
        inside[ty * TILE : (ty + 1) * TILE, tx * TILE : (tx + 1) * TILE] = True
    z_left = smooth_field((height, width), rng)
    z_right = np.where(
        shift_rows(inside.astype(float), shift) > 0.5,
        shift_rows(z_left, shift),
        smooth_field((height, width), rng),
    )
    a, b = 0.01, 1e-4
    fields = {}
    for view, z in (("left", z_left), ("right", z_right)):
        law = a * frame.clean[view] + b
        variance = law * np.exp(strength * z - strength**2 / 2)[..., None]
        stack = draw_frames(frame.clean[view], variance, n_seeds, rng, channel_correlation=0.9)
        fields[view] = variance_field(stack)
    warped, omega = warp_right_to_left(fields["right"][1], frame.disparity, sign=-1)
    mu_warped, _ = warp_right_to_left(channel_mean(fields["right"][0]), frame.disparity, sign=-1)
    return residual_fields(
        fields["left"][1], warped, omega, channel_mean(fields["left"][0]), mu_warped
    )


def test_tile_correlation_against_a_loop():
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((2, 50, 70))
    b += a * np.linspace(0, 2, 70)[None, :]
    mask = rng.random((50, 70)) > 0.2
    rho, n = tile_correlation(a, b, mask, tile=16, min_pixels=30)
    assert rho.shape == (4, 5)
    for ty in range(4):
        for tx in range(5):
            sl = np.s_[ty * 16 : (ty + 1) * 16, tx * 16 : (tx + 1) * 16]
            m = mask[sl]
            assert n[ty, tx] == m.sum()
            if m.sum() < max(30, 0.25 * 256):
                assert math.isnan(rho[ty, tx])
            else:
                assert rho[ty, tx] == pytest.approx(np.corrcoef(a[sl][m], b[sl][m])[0, 1])


def test_the_planted_tiles_are_the_strongest_and_stand_out():
    e_left, e_right, controlled = planted_frame(PLANTED)
    assert controlled
    rows, summary = rank_tiles(e_left, e_right, frame="f00", top=5)
    found = [(r["y0"] // TILE, r["x0"] // TILE) for r in rows]
    assert set(found[:3]) == set(PLANTED)
    assert all(r["stands_out"] for r in rows[:3])
    assert all(r["low"] > r["null_high"] for r in rows[:3])  # beyond the null, interval too
    assert summary["n_stand_out"] >= 3
    # the tiles that follow are what ranking alone gives: about the null at their rank
    assert not any(r["stands_out"] for r in rows[3:])


def test_no_tile_stands_out_on_the_matched_null():
    e_left, e_right, _ = planted_frame([], seed=1)
    rows, summary = rank_tiles(e_left, e_right, frame="f00", top=5)
    assert len(rows) == 5 and summary["n_tiles"] >= 40
    # the top tile of a frame without aligned structure reaches the null's top, not beyond
    assert sum(r["stands_out"] for r in rows) <= 1
    assert summary["n_stand_out"] <= 0.1 * summary["n_tiles"]
    assert abs(rows[0]["rho"] - rows[0]["null"]) < 3 * summary["null_sd"]


def test_frames_without_a_matched_null_rank_after_those_with_one():
    corr = [
        {"scene": s, "region": "all", "method": "partial", "rho": r, "boot_low": r - 0.05,
         "boot_high": r + 0.05, "chance_se": 0.04}
        for s, r in (("a", 0.3), ("b", 0.9), ("c", 0.6))
    ] + [{"scene": "b", "region": "all", "method": "warp", "rho": 1.0}]
    nulls = [
        {"scene": s, "transform": "none", "region": "all", "method": "partial",
         "null_rho": n, "null_se": 0.01, "chance_sd": 0.02}
        for s, n in (("a", 0.0), ("c", 0.5))
    ]
    ranked = frame_ranking(corr, nulls)
    assert [r["frame"] for r in ranked] == ["a", "c", "b"]
    assert [r["statistic"] for r in ranked] == ["difference", "difference", "partial"]
    a = ranked[0]
    # the chance standard error 0.04 is above the bootstrap's 0.1 / (2 z) = 0.026
    half = 1.959964 * math.sqrt(0.04**2 + 0.01**2)
    assert (a["value"], a["low"], a["high"]) == pytest.approx((0.3, 0.3 - half, 0.3 + half))
