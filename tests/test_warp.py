"""Eq. 2: bilinear warp along x against analytic and brute-force references."""

import numpy as np
import pytest
import xarray as xr

from stereovar.statistics.warp import warp_right_to_left


@pytest.mark.parametrize("sign", [1, -1])
def test_linear_field_shifted_by_subpixel_disparity_is_exact(sign):
    """Bilinear interpolation reproduces a field linear in x exactly."""
    height, width = 6, 40
    x = np.arange(width, dtype=np.float64)
    right = np.broadcast_to(3.0 + 0.7 * x, (height, width)).copy()
    d = np.full((height, width), 2.37)
    warped, omega = warp_right_to_left(right, d, sign=sign)
    expected = 3.0 + 0.7 * (x + sign * 2.37)
    inside = (x + sign * 2.37 >= 0) & (x + sign * 2.37 <= width - 1)
    np.testing.assert_array_equal(omega, np.broadcast_to(inside, (height, width)))
    np.testing.assert_allclose(warped[omega], np.broadcast_to(expected, (height, width))[omega])


def test_matches_brute_force_loop_and_masks():
    rng = np.random.default_rng(1)
    height, width = 5, 17
    right = rng.normal(size=(height, width, 3))
    d = rng.uniform(-1, 6, size=(height, width))
    d[0, 0] = np.nan
    d[1, 1] = np.inf
    valid = rng.random((height, width)) > 0.2
    warped, omega = warp_right_to_left(right, d, sign=1, valid=valid)
    for j in range(height):
        for i in range(width):
            xs = i + d[j, i]
            ok = bool(valid[j, i]) and np.isfinite(d[j, i]) and d[j, i] > 0 and 0 <= xs <= width - 1
            assert omega[j, i] == ok
            if ok:
                x0 = min(int(np.floor(xs)), width - 2)
                t = xs - x0
                ref = (1 - t) * right[j, x0] + t * right[j, x0 + 1]
                np.testing.assert_allclose(warped[j, i], ref)
            else:
                assert (warped[j, i] == 0).all()


def test_xarray_inputs_keep_dims_and_coords():
    right = xr.DataArray(np.arange(24.0).reshape(2, 4, 3), dims=("y", "x", "channel"))
    right = right.transpose("channel", "y", "x")
    d = xr.DataArray(np.full((2, 4), 1.0), dims=("y", "x"))
    warped, omega = warp_right_to_left(right, d)
    assert warped.dims == ("channel", "y", "x")
    assert omega.dims == ("y", "x")
    np.testing.assert_allclose(warped.isel(x=0).values, right.isel(x=1).values)
    assert not bool(omega.isel(x=3).any())
