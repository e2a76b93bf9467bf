"""Sec. 3.4 cost volumes and metrics against brute-force loops and an analytic shift."""

import math

import numpy as np
import pytest

from stereovar.intervention.scan import NO_PIXELS, disparity_slices

from .reference.costvolume import (
    gt_margin,
    peak_hit_rate,
    pixel_similarity_volume,
    residual_cost_volume,
    sad_cost_volume,
    variance_cost_volume,
    wta_accuracy,
)


def brute_sad(left, right, max_disparity, window, sign):
    height, width = left.shape
    r = window // 2
    cost = np.full((max_disparity + 1, height, width), np.nan)
    scored = np.zeros(cost.shape, dtype=bool)
    for d in range(max_disparity + 1):
        for y in range(height):
            for x in range(width):
                total = 0.0
                inside = True
                for v in range(-r, r + 1):
                    for u in range(-r, r + 1):
                        yy, xl, xr = y + v, x + u, x + sign * d + u
                        if not (0 <= yy < height and 0 <= xl < width and 0 <= xr < width):
                            inside = False
                            break
                        total += abs(float(left[yy, xl]) - float(right[yy, xr]))
                    if not inside:
                        break
                if inside:
                    cost[d, y, x] = total
                    scored[d, y, x] = True
    return cost, scored


def brute_similarity(left, right, max_disparity, sign):
    height, width = left.shape
    sim = np.full((max_disparity + 1, height, width), np.nan)
    scored = np.zeros(sim.shape, dtype=bool)
    for d in range(max_disparity + 1):
        for y in range(height):
            for x in range(width):
                xr = x + sign * d
                if 0 <= xr < width:
                    sim[d, y, x] = -abs(left[y, x] - right[y, xr])
                    scored[d, y, x] = True
    return sim, scored


def brute_margin(cost, scored, d_gt):
    n_disp, height, width = cost.shape
    out = np.full((height, width), np.nan)
    for y in range(height):
        for x in range(width):
            g = d_gt[y, x]
            if not math.isfinite(g):
                continue
            k = int(np.rint(g))
            if not (0 <= k < n_disp) or not scored[k, y, x]:
                continue
            others = [cost[d, y, x] for d in range(n_disp) if d != k and scored[d, y, x]]
            if others:
                out[y, x] = min(others) - cost[k, y, x]
    return out


def brute_rate(values, scored, d_gt, mask, maximise):
    n_disp, height, width = values.shape
    hits, chances = [], []
    for y in range(height):
        for x in range(width):
            cands = [d for d in range(n_disp) if scored[d, y, x]]
            if not mask[y, x] or not cands or not math.isfinite(d_gt[y, x]):
                continue
            if not any(abs(d - d_gt[y, x]) < 1 for d in cands):
                continue  # no hit possible: the pixel is not scoreable
            sgn = -1.0 if maximise else 1.0
            best = cands[0]
            for d in cands[1:]:  # strict <: the smallest d wins ties
                if sgn * values[d, y, x] < sgn * values[best, y, x]:
                    best = d
            hits.append(abs(best - d_gt[y, x]) < 1)
            chances.append(sum(abs(d - d_gt[y, x]) < 1 for d in cands) / len(cands))
    if not hits:
        return None
    return float(np.mean(hits)), len(hits), float(np.mean(chances))


@pytest.fixture
def pair():
    rng = np.random.default_rng(7)
    return rng.normal(size=(9, 13)), rng.normal(size=(9, 13))


@pytest.mark.parametrize("window", [1, 3, 5])
@pytest.mark.parametrize("sign", [1, -1])
def test_sad_matches_brute_force(pair, window, sign):
    left, right = pair
    cost, scored = sad_cost_volume(left, right, max_disparity=4, window=window, sign=sign)
    ref_cost, ref_scored = brute_sad(left, right, 4, window, sign)
    assert cost.shape == (5, 9, 13) and cost.dtype == np.float64
    np.testing.assert_array_equal(scored, ref_scored)
    np.testing.assert_array_equal(np.isnan(cost), ~ref_scored)
    np.testing.assert_allclose(cost[scored], ref_cost[ref_scored], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("window", [3, 5, 13])
@pytest.mark.parametrize("sign", [1, -1])
def test_running_sum_path_matches_brute_force(monkeypatch, window, sign):
    """Force the integral-image box sums (used for windows above the shifted-add limit)."""
    import stereovar.intervention.scan as cv

    monkeypatch.setattr(cv, "_SHIFTED_ADD_MAX", 1)
    rng = np.random.default_rng(5)
    left, right = rng.normal(size=(16, 24)), rng.normal(size=(16, 24))
    cost, scored = sad_cost_volume(left, right, max_disparity=5, window=window, sign=sign)
    ref_cost, ref_scored = brute_sad(left, right, 5, window, sign)
    np.testing.assert_array_equal(scored, ref_scored)
    np.testing.assert_allclose(cost[scored], ref_cost[ref_scored], rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize("sign", [1, -1])
def test_wrappers_float32_and_streaming_agree(pair, sign):
    left, right = pair
    ref, ref_scored = brute_sad(left, right, 4, 3, sign)
    for fn in (residual_cost_volume, variance_cost_volume):
        cost, scored = fn(left, right, max_disparity=4, window=3, sign=sign)
        np.testing.assert_array_equal(scored, ref_scored)
        np.testing.assert_allclose(cost[scored], ref[scored], rtol=1e-12)
    c32, s32 = sad_cost_volume(left, right, max_disparity=4, window=3, sign=sign, dtype="f4")
    assert c32.dtype == np.float32
    np.testing.assert_array_equal(s32, ref_scored)
    np.testing.assert_allclose(c32[s32], ref[s32].astype(np.float32), rtol=1e-6)
    for d, block, where in disparity_slices(left, right, max_disparity=4, window=3, sign=sign):
        full = np.full(left.shape, np.nan)
        full[where] = block
        np.testing.assert_allclose(full, ref[d], rtol=1e-12, equal_nan=True)


def test_disparity_beyond_image_and_tall_window_score_nothing():
    rng = np.random.default_rng(0)
    left, right = rng.normal(size=(4, 6)), rng.normal(size=(4, 6))
    cost, scored = sad_cost_volume(left, right, max_disparity=8, window=3, sign=1)
    np.testing.assert_array_equal(scored, brute_sad(left, right, 8, 3, 1)[1])
    assert not scored[4:].any() and np.isnan(cost[4:]).all()
    cost, scored = sad_cost_volume(left, right, max_disparity=2, window=5)
    assert not scored.any()


@pytest.mark.parametrize("window", [0, 2, 4, -1, 3.5, True])
def test_bad_window_raises(pair, window):
    with pytest.raises(ValueError, match="window"):
        sad_cost_volume(*pair, max_disparity=2, window=window)


def test_bad_arguments_raise(pair):
    left, right = pair
    with pytest.raises(ValueError, match="sign"):
        sad_cost_volume(left, right, max_disparity=2, sign=0)
    with pytest.raises(ValueError, match="max_disparity"):
        sad_cost_volume(left, right, max_disparity=-1)
    with pytest.raises(ValueError, match="shape"):
        sad_cost_volume(left, right[:, :-1], max_disparity=2)
    with pytest.raises(ValueError, match="dtype"):
        sad_cost_volume(left, right, max_disparity=2, dtype=np.int32)


@pytest.mark.parametrize("sign", [1, -1])
def test_pixel_similarity_matches_brute_force(pair, sign):
    left, right = pair
    sim, scored = pixel_similarity_volume(left, right, max_disparity=4, sign=sign)
    ref, ref_scored = brute_similarity(left, right, 4, sign)
    np.testing.assert_array_equal(scored, ref_scored)
    np.testing.assert_array_equal(sim[scored], ref[scored])
    assert np.isnan(sim[~scored]).all()


def _gt(rng, shape, max_disparity):
    d_gt = rng.uniform(-1.2, max_disparity + 1.2, size=shape)
    d_gt[0, 0] = np.nan
    d_gt[1, 1] = 2.5  # rint -> 2
    d_gt[1, 2] = 3.5  # rint -> 4
    return d_gt


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("window", [3, 5])
def test_metrics_match_brute_force(pair, sign, window):
    rng = np.random.default_rng(11)
    left, right = pair
    cost, scored = sad_cost_volume(left, right, max_disparity=4, window=window, sign=sign)
    ref_cost, ref_scored = brute_sad(left, right, 4, window, sign)
    d_gt = _gt(rng, left.shape, 4)
    mask = rng.random(left.shape) < 0.7
    np.testing.assert_allclose(
        gt_margin(cost, scored, d_gt),
        brute_margin(ref_cost, ref_scored, d_gt),
        rtol=1e-10,
        atol=1e-10,
        equal_nan=True,
    )
    got = wta_accuracy(cost, scored, d_gt, mask)
    ref = brute_rate(ref_cost, ref_scored, d_gt, mask, maximise=False)
    assert got["reason"] == ""
    assert (got["accuracy"], got["n_pixels"]) == (pytest.approx(ref[0]), ref[1])
    assert got["chance"] == pytest.approx(ref[2])
    assert got["n_hits"] == round(ref[0] * ref[1])

    sim, s_scored = pixel_similarity_volume(left, right, max_disparity=4, sign=sign)
    got = peak_hit_rate(sim, s_scored, d_gt, mask)
    ref = brute_rate(sim, s_scored, d_gt, mask, maximise=True)
    assert (got["accuracy"], got["n_pixels"]) == (pytest.approx(ref[0]), ref[1])
    assert got["chance"] == pytest.approx(ref[2])


def test_margin_rounds_half_to_even_and_is_nan_outside_range():
    cost = np.array([5.0, 1.0, 0.0, 4.0, 3.0, 9.0])[:, None, None] * np.ones((1, 1, 4))
    scored = np.ones(cost.shape, dtype=bool)
    d_gt = np.array([[2.5, 3.5, -0.6, 5.6]])
    m = gt_margin(cost, scored, d_gt)
    assert m[0, 0] == 1.0 - 0.0  # d_GT = 2
    assert m[0, 1] == 0.0 - 3.0  # d_GT = 4
    assert np.isnan(m[0, 2]) and np.isnan(m[0, 3])  # rint -> -1 and 6, outside [0, 5]
    scored[2, 0, 0] = False  # d_GT itself not scored
    scored[:, 0, 1] = False
    scored[4, 0, 1] = True  # only d_GT scored: no other d
    m = gt_margin(cost, scored, d_gt)
    assert np.isnan(m[0, 0]) and np.isnan(m[0, 1])


@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("window", [1, 5])
def test_known_integer_shift_is_recovered(sign, window):
    rng = np.random.default_rng(3)
    height, width, d0, max_disparity = 20, 48, 3, 8
    left = rng.uniform(size=(height, width))
    right = rng.uniform(size=(height, width))
    # R(x + s d0) = L(x) wherever both are in the image.
    if sign == 1:
        right[:, d0:] = left[:, : width - d0]
    else:
        right[:, : width - d0] = left[:, d0:]
    cost, scored = sad_cost_volume(
        left, right, max_disparity=max_disparity, window=window, sign=sign
    )
    d_gt = np.full((height, width), d0 + 0.3)
    ok = scored[d0]
    assert ok.sum() > 0
    margin = gt_margin(cost, scored, d_gt)
    assert np.all(margin[ok] > 0)
    assert np.isnan(margin[~ok]).all()
    res = wta_accuracy(cost, scored, d_gt, ok)
    assert res["accuracy"] == 1.0 and res["n_pixels"] == ok.sum()
    assert 0 < res["chance"] < 1
    sim, s_scored = pixel_similarity_volume(left, right, max_disparity=max_disparity, sign=sign)
    assert peak_hit_rate(sim, s_scored, d_gt, s_scored[d0])["accuracy"] == 1.0


def test_empty_region_gives_nan_with_reason(pair):
    cost, scored = sad_cost_volume(*pair, max_disparity=3, window=3)
    for fn in (wta_accuracy, peak_hit_rate):
        res = fn(cost, scored, np.ones(cost.shape[1:]), np.zeros(cost.shape[1:], bool))
        assert math.isnan(res["accuracy"]) and math.isnan(res["chance"])
        assert res["n_pixels"] == 0 and res["reason"] == NO_PIXELS


def test_chance_is_one_over_scored_count_for_integer_gt(pair):
    cost, scored = sad_cost_volume(*pair, max_disparity=4, window=1)
    d_gt = np.full(cost.shape[1:], 2.0)
    res = wta_accuracy(cost, scored, d_gt)
    expected = np.mean(1.0 / scored.sum(axis=0)[scored[2]])
    res_in = wta_accuracy(cost, scored, d_gt, scored[2])
    assert res_in["chance"] == pytest.approx(expected)
    # With an integer d_gt a pixel is scoreable exactly when d_gt itself is scored.
    assert res["n_pixels"] == int(scored[2].sum())
    assert res_in["n_pixels"] == res["n_pixels"]


@pytest.mark.parametrize("workers", [1, 2, 3])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("sign", [1, -1])
def test_streamed_wta_equals_argmin_of_the_full_volume(workers, dtype, sign):
    from stereovar.intervention.scan import wta_disparity

    rng = np.random.default_rng(7)
    # Small integers make many exact ties, which must go to the smallest d as in argmin.
    left = rng.integers(0, 4, size=(11, 17)).astype(np.float64)
    right = rng.integers(0, 4, size=(11, 17)).astype(np.float64)
    cost, scored = sad_cost_volume(left, right, max_disparity=6, window=3, sign=sign)
    expected = np.full(left.shape, -1)
    best = np.full(left.shape, np.inf)
    for d in range(cost.shape[0]):  # brute-force running argmin, first minimum wins
        for y in range(left.shape[0]):
            for x in range(left.shape[1]):
                if scored[d, y, x] and cost[d, y, x] < best[y, x]:
                    best[y, x] = cost[d, y, x]
                    expected[y, x] = d
    disparity, winning = wta_disparity(
        left, right, max_disparity=6, window=3, sign=sign, dtype=dtype, workers=workers
    )
    np.testing.assert_array_equal(disparity, expected)
    np.testing.assert_allclose(winning, best, rtol=1e-6)


def _scan_case(rng, shape, max_disparity, *, with_nan):
    left = rng.normal(size=shape)
    right = rng.normal(size=shape)
    left[::3] = np.round(left[::3])  # exact ties on some rows
    right[::3] = np.round(right[::3])
    if with_nan:
        left[2, 4] = np.nan
        right[5, 1] = np.inf
    d_gt = _gt(rng, shape, max_disparity)
    d_gt[0, 0], d_gt[1, 1], d_gt[1, 2] = np.nan, 2.5, max_disparity + 3.0
    return left, right, d_gt


@pytest.mark.parametrize("workers", [1, 2])
@pytest.mark.parametrize("window", [1, 3, 5])
@pytest.mark.parametrize("sign", [1, -1])
@pytest.mark.parametrize("with_nan", [False, True])
def test_scan_equals_brute_force_margins_and_wta(monkeypatch, workers, window, sign, with_nan):
    import stereovar.intervention.scan as cv

    monkeypatch.setattr(cv, "_STRIP_BYTES", 1)  # 8-row strips: several strips per image
    rng = np.random.default_rng(window + 10 * workers)
    left, right, d_gt = _scan_case(rng, (21, 15), 5, with_nan=with_nan)
    mask = rng.random(left.shape) < 0.8
    ref_cost, ref_scored = brute_sad(left, right, 5, window, sign)
    ref_scored &= np.isfinite(ref_cost)
    scan = cv.scan_cost_volume(
        left, right, max_disparity=5, window=window, sign=sign, d_gt=d_gt, workers=workers
    )
    np.testing.assert_allclose(
        scan.margin, brute_margin(ref_cost, ref_scored, d_gt), rtol=1e-12, atol=1e-12,
        equal_nan=True,
    )  # fmt: skip
    np.testing.assert_array_equal(scan.n_scored, ref_scored.sum(axis=0))
    got = cv.scan_hit_rate(scan, d_gt, mask)
    ref = brute_rate(ref_cost, ref_scored, d_gt, mask, maximise=False)
    assert (got["accuracy"], got["n_pixels"]) == (pytest.approx(ref[0]), ref[1])
    assert got["chance"] == pytest.approx(ref[2])
    # The winning disparity is the first minimum of the brute-force volume.
    masked = np.where(ref_scored, ref_cost, np.inf)
    expected = np.where(ref_scored.any(axis=0), masked.argmin(axis=0), -1)
    np.testing.assert_array_equal(scan.disparity, expected)
    np.testing.assert_allclose(scan.cost, masked.min(axis=0), rtol=1e-12)


@pytest.mark.parametrize("sign", [1, -1])
def test_window_one_scan_is_the_variance_peak_hit_rate(sign):
    from stereovar.intervention.scan import scan_cost_volume, scan_hit_rate

    rng = np.random.default_rng(3)
    left, right, d_gt = _scan_case(rng, (12, 16), 4, with_nan=False)
    sim, s_scored = brute_similarity(left, right, 4, sign)
    scan = scan_cost_volume(left, right, max_disparity=4, window=1, sign=sign, d_gt=d_gt)
    got = scan_hit_rate(scan, d_gt)
    ref = brute_rate(sim, s_scored, d_gt, np.ones(left.shape, bool), maximise=True)
    assert (got["accuracy"], got["n_pixels"]) == (pytest.approx(ref[0]), ref[1])
    assert got["chance"] == pytest.approx(ref[2])


@pytest.mark.parametrize(
    ("high", "window", "expected"), [(255, 5, np.int16), (255, 13, np.int32), (60000, 3, np.int32)]
)
def test_integer_images_are_summed_exactly_in_integers(monkeypatch, high, window, expected):
    import stereovar.intervention.scan as cv

    rng = np.random.default_rng(high + window)
    dtype = np.uint8 if high < 256 else np.uint16
    left = rng.integers(0, high + 1, size=(18, 24)).astype(dtype)
    right = rng.integers(0, high + 1, size=(18, 24)).astype(dtype)
    left[:, :4] = right[:, :4] = high  # extreme differences are reachable
    left[:, 4:8], right[:, 4:8] = 0, high
    assert cv._compute_dtype(left, right, window, None) == expected
    monkeypatch.setattr(cv, "_STRIP_BYTES", 1)
    ref_cost, ref_scored = brute_sad(left, right, 3, window, 1)
    disparity, cost = cv.wta_disparity(
        left, right, max_disparity=3, window=window, sign=1, dtype=None
    )
    masked = np.where(ref_scored, ref_cost, np.inf)
    np.testing.assert_array_equal(cost, masked.min(axis=0))  # exact, not approximately
    np.testing.assert_array_equal(
        disparity, np.where(ref_scored.any(axis=0), masked.argmin(axis=0), -1)
    )


def test_scan_hit_rate_needs_the_ground_truth_counts(pair):
    from stereovar.intervention.scan import scan_cost_volume, scan_hit_rate

    scan = scan_cost_volume(*pair, max_disparity=2, window=3)
    assert scan.margin is None
    with pytest.raises(ValueError, match="pass d_gt"):
        scan_hit_rate(scan, np.zeros(pair[0].shape))
    with pytest.raises(ValueError, match="dtype"):
        scan_cost_volume(*pair, max_disparity=2, dtype=np.int8)
