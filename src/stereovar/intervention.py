"""The residual-shuffle intervention of paper Sec. 3.4 (Table 3) for one scene.

For the normal pair and for the decorrelated pair (right residuals block-shuffled by one fixed
permutation :math:`\\Pi`), three costs are scored against the ground-truth disparity on the
grey (RGB-mean) fields: the per-seed residual SAD :math:`C_\\epsilon`, the variance cost
:math:`C_\\sigma` and the pixel-level variance similarity.
"""

from __future__ import annotations

import math

import numpy as np

from .costvolume import (
    gt_margin,
    peak_hit_rate,
    pixel_similarity_volume,
    residual_cost_volume,
    variance_cost_volume,
    wta_accuracy,
)
from .shuffle import apply_block_permutation, block_permutation

CONDITIONS = ("normal", "decorrelated")
REGIONS = ("non_glass", "glass")


def _grey(stack) -> np.ndarray:
    """(N, H, W[, C]) renders to float64 grey (N, H, W)."""
    a = np.asarray(stack, dtype=np.float64)
    return a.mean(axis=-1) if a.ndim == 4 else a


def _margin_entry(margins: list[np.ndarray], n_seeds: int) -> tuple[float, float, int]:
    """Mean GT margin pooled over seeds; pixel count per seed."""
    values = np.concatenate(margins) if margins else np.empty(0)
    return (float(values.mean()) if values.size else math.nan), math.nan, values.size // n_seeds


def _accuracy_entry(results: list[dict]) -> tuple[float, float, int]:
    """Accuracy pooled over seeds (weighted by scoreable pixels), mean chance, pixels/seed."""
    n = sum(r["n_pixels"] for r in results)
    if not n:
        return math.nan, math.nan, 0
    accuracy = sum(r["accuracy"] * r["n_pixels"] for r in results if r["n_pixels"]) / n
    chance = float(np.mean([r["chance"] for r in results if r["n_pixels"]]))
    return accuracy, chance, n // len(results)


def intervention_metrics(
    left,
    right,
    ground_truth_left,
    *,
    sign: int,
    max_disparity: int,
    window: int = 5,
    block: int = 16,
    seed: int = 0,
) -> list[dict]:
    """Table 3's metrics of one scene, normal against decorrelated (paper Sec. 3.4).

    With :math:`I_V^{(n)} = \\bar I_V + \\epsilon_V^{(n)}` on grey fields and
    :math:`\\tilde I_R^{(n)} = \\bar I_R + \\Pi(\\epsilon_R^{(n)})`,

    .. math::

        C_\\epsilon^{(n)}(x, d) = \\sum_{u \\in W}
            \\bigl|\\epsilon_L^{(n)}(x+u) - \\epsilon_R^{(n)}(x+s d+u)\\bigr|, \\qquad
        C_\\sigma(x, d) = \\sum_{u \\in W} \\bigl|\\sigma_L^2(x+u) - \\sigma_R^2(x+s d+u)\\bigr|,

    scored by the GT margin :math:`m(x) = \\min_{d \\ne d_{GT}} C(x, d) - C(x, d_{GT})`
    (:math:`d_{GT}` the integer nearest the subpixel ground truth), the winner-take-all
    accuracy :math:`\\Pr[|\\arg\\min_d C - d_{GT}| < 1]` and, for the variance, the peak hit
    rate of :math:`\\arg\\max_d -|\\sigma_L^2(x) - \\sigma_R^2(x + s d)|`. Decorrelation only
    permutes residual blocks, so :math:`\\sigma_R^2` becomes :math:`\\Pi(\\sigma_R^2)`.

    Parameters
    ----------
    left, right : array_like, shape (N, H, W, C) or (N, H, W)
        The N seeds' renders of each view.
    ground_truth_left : mapping
        Left view of the ground truth: ``disparity`` (subpixel), ``valid``, ``glass``.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    max_disparity : int, keyword-only
        :math:`D`; disparities :math:`0..D` are scored.
    window, block, seed : int, keyword-only
        Patch side, residual block side and the seed of :math:`\\Pi`.

    Returns
    -------
    list of dict
        One row per (cost, metric, region, condition): ``value`` (mean margin over the
        region's scored pixels and seeds, or the accuracy pooled over seeds), ``chance`` (for
        accuracies, the mean chance level), ``n_pixels`` and ``reason`` (why ``value`` is NaN).
    """
    grey_l, grey_r = _grey(left), _grey(right)
    if grey_l.shape != grey_r.shape or grey_l.ndim != 3:
        raise ValueError(f"left and right stacks differ: {grey_l.shape} vs {grey_r.shape}")
    n, height, width = grey_l.shape
    perm = block_permutation(height, width, block=block, seed=seed)
    eps_l = grey_l - grey_l.mean(axis=0)
    eps_r = grey_r - grey_r.mean(axis=0)
    sigma_l = (eps_l**2).mean(axis=0)
    d_gt = np.asarray(ground_truth_left["disparity"], dtype=np.float64)
    valid = np.asarray(ground_truth_left["valid"], dtype=bool)
    glass = np.asarray(ground_truth_left["glass"], dtype=bool)
    masks = {"non_glass": valid & ~glass, "glass": valid & glass}
    kw = {"max_disparity": max_disparity, "sign": sign}
    rows = []

    def add(cost, metric, condition, per_region):
        for region in REGIONS:
            value, chance, n_pix = per_region[region]
            rows.append(
                {
                    "cost": cost,
                    "metric": metric,
                    "region": region,
                    "condition": condition,
                    "value": value if n_pix else math.nan,
                    "chance": chance,
                    "n_pixels": n_pix,
                    "reason": "" if n_pix else f"no scoreable {region} pixels",
                }
            )

    for condition in CONDITIONS:
        right_eps = eps_r
        if condition == "decorrelated":
            right_eps = np.stack([apply_block_permutation(e, perm, block=block) for e in eps_r])
        sigma_r = (right_eps**2).mean(axis=0)
        margins = {r: [] for r in REGIONS}
        accuracies = {r: [] for r in REGIONS}
        for k in range(n):
            cost, scored = residual_cost_volume(eps_l[k], right_eps[k], window=window, **kw)
            margin = gt_margin(cost, scored, d_gt)
            for region, mask in masks.items():
                margins[region].append(margin[mask & np.isfinite(margin)])
                accuracies[region].append(wta_accuracy(cost, scored, d_gt, mask))
        add(
            "residual_sad",
            "gt_margin",
            condition,
            {r: _margin_entry(margins[r], n) for r in REGIONS},
        )
        add(
            "residual_sad",
            "wta_accuracy",
            condition,
            {r: _accuracy_entry(accuracies[r]) for r in REGIONS},
        )
        cost, scored = variance_cost_volume(sigma_l, sigma_r, window=window, **kw)
        margin = gt_margin(cost, scored, d_gt)
        add(
            "variance_cost",
            "gt_margin",
            condition,
            {r: _margin_entry([margin[m & np.isfinite(margin)]], 1) for r, m in masks.items()},
        )
        add(
            "variance_cost",
            "wta_accuracy",
            condition,
            {r: _accuracy_entry([wta_accuracy(cost, scored, d_gt, m)]) for r, m in masks.items()},
        )
        similarity, scored = pixel_similarity_volume(sigma_l, sigma_r, **kw)
        add(
            "variance_peak",
            "peak_hit_rate",
            condition,
            {
                r: _accuracy_entry([peak_hit_rate(similarity, scored, d_gt, m)])
                for r, m in masks.items()
            },
        )
    return rows
