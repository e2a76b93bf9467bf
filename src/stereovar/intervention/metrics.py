"""The residual-shuffle intervention of paper Sec. 3.4 (Table 3) for one scene.

For the normal pair and for the decorrelated pair (right residuals block-shuffled by one fixed
permutation :math:`\\Pi`), three costs are scored against the ground-truth disparity: the
per-seed residual SAD :math:`C_\\epsilon` on the grey (RGB-mean) residuals, the variance cost
:math:`C_\\sigma` on the Eq. 1 variance fields and the pixel-level variance similarity. The
seeds are streamed twice (mean, then residuals) and every cost volume is scanned disparity by
disparity (:func:`stereovar.intervention.scan.scan_cost_volume`), so memory is a few images whatever
:math:`N` and :math:`D`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..estimators.seeds import StreamingVariance
from ..statistics.regions import region_masks, valid_set
from .scan import scan_cost_volume, scan_hit_rate
from .shuffle import apply_block_permutation, block_permutation

CONDITIONS = ("normal", "decorrelated")
REGIONS = ("non_glass", "glass")
"""The regions of Table 3 (:func:`stereovar.statistics.regions.region_masks`)."""
COSTS = {
    "residual_sad": ("gt_margin", "wta_accuracy"),
    "variance_cost": ("gt_margin", "wta_accuracy"),
    "variance_peak": ("peak_hit_rate",),
}
"""Table 3's rows: each cost and the metrics reported for it."""


class InterventionResult(NamedTuple):
    """Output of :func:`intervention_metrics`.

    Attributes
    ----------
    rows : list of dict
        One per (cost, metric, region, condition): ``value``, ``chance``, ``n_pixels``,
        ``reason``.
    margins : list of dict
        A uniform random sample of the per-pixel GT margins behind the ``gt_margin`` rows:
        ``cost``, ``region``, ``condition``, ``seed`` (-1 for :math:`C_\\sigma`, which has
        no seed), ``y``, ``x`` and ``margin``, for the margin-distribution figure.
    """

    rows: list
    margins: list


def _with_channels(render) -> np.ndarray:
    """One render, (H, W) or (H, W, C), as an (H, W, C) array of its own dtype."""
    a = np.asarray(render)
    return a[..., None] if a.ndim == 2 else a


def _as_float(render) -> np.ndarray:
    """One render, (H, W) or (H, W, C), as float64 (H, W, C)."""
    return _with_channels(render).astype(np.float64, copy=False)


def _seed_moments(renders: Sequence) -> StreamingVariance:
    """Eq. 1 accumulated over the seeds, reading one render at a time (the mean
    :math:`\\bar I` and :math:`\\sigma^2` of :class:`~stereovar.estimators.seeds.StreamingVariance`,
    with its NaN/Inf handling)."""
    acc = StreamingVariance()
    for render in renders:
        acc.update(_with_channels(render))  # accumulated in float64 there
    return acc


class _RegionAccumulator:
    """Per-region sums of margins, WTA counts and chance levels, pooled over seeds."""

    def __init__(self, masks):
        self.masks = masks
        self.margin_sum = dict.fromkeys(masks, 0.0)
        self.margin_n = dict.fromkeys(masks, 0)
        self.rates = {region: [] for region in masks}

    def add(self, scan, d_gt, *, margin=True):
        for region, mask in self.masks.items():
            if margin:
                values = scan.margin[mask]
                values = values[np.isfinite(values)]
                self.margin_sum[region] += float(values.sum())
                self.margin_n[region] += values.size
            self.rates[region].append(scan_hit_rate(scan, d_gt, mask))

    def margin_entry(self, region, n_runs):
        n = self.margin_n[region]
        return (self.margin_sum[region] / n if n else math.nan), math.nan, n // n_runs

    def rate_entry(self, region):
        results = self.rates[region]
        n = sum(r["n_pixels"] for r in results)
        if not n:
            return math.nan, math.nan, 0
        hits = sum(r["n_hits"] for r in results)
        chance = float(np.mean([r["chance"] for r in results if r["n_pixels"]]))
        return hits / n, chance, n // len(results)


def _sample_plan(masks, n_runs, size, rng):
    """For each region: {run: (ys, xs)} of ``size`` pairs drawn uniformly without replacement
    from (run, region pixel)."""
    plan = {}
    for region, mask in masks.items():
        ys, xs = np.nonzero(mask)
        total = n_runs * ys.size
        picks = np.sort(rng.choice(total, size=min(size, total), replace=False)) if total else []
        runs = {}
        for k in np.asarray(picks, dtype=np.int64):
            runs.setdefault(int(k // ys.size), []).append(int(k % ys.size))
        plan[region] = {run: (ys[idx], xs[idx]) for run, idx in runs.items()}
    return plan


def _take_samples(out, plan, run, margin, *, cost, condition, seed):
    for region, runs in plan.items():
        if run not in runs:
            continue
        ys, xs = runs[run]
        for y, x, m in zip(ys, xs, margin[ys, xs], strict=True):
            if math.isfinite(m):
                out.append(
                    {
                        "cost": cost,
                        "region": region,
                        "condition": condition,
                        "seed": seed,
                        "y": int(y),
                        "x": int(x),
                        "margin": float(m),
                    }
                )


def intervention_metrics(
    left: Sequence,
    right: Sequence,
    ground_truth_left,
    *,
    sign: int,
    max_disparity: int,
    window: int = 5,
    block: int = 16,
    seed: int = 0,
    margin_samples: int = 2000,
    workers: int = 1,
    regions: Sequence[str] = REGIONS,
    bootstrap=None,
) -> InterventionResult:
    """Table 3's metrics of one scene, normal against decorrelated (paper Sec. 3.4).

    With :math:`I_V^{(n)} = \\bar I_V + \\epsilon_V^{(n)}` and
    :math:`\\tilde I_R^{(n)} = \\bar I_R + \\Pi(\\epsilon_R^{(n)})`,

    .. math::

        C_\\epsilon^{(n)}(x, d) = \\sum_{u \\in W}
            \\bigl|\\epsilon_L^{(n)}(x+u) - \\epsilon_R^{(n)}(x+s d+u)\\bigr|, \\qquad
        C_\\sigma(x, d) = \\sum_{u \\in W} \\bigl|\\sigma_L^2(x+u) - \\sigma_R^2(x+s d+u)\\bigr|,

    with :math:`\\epsilon` the grey (RGB-mean) residual and :math:`\\sigma_V^2` the Eq. 1
    variance (:math:`1/N`, averaged over RGB). They are scored by the GT margin
    :math:`m(x) = \\min_{d \\ne d_{GT}} C(x, d) - C(x, d_{GT})` (:math:`d_{GT}` the integer
    nearest the subpixel ground truth, halves to even), the winner-take-all accuracy
    :math:`\\Pr[|\\arg\\min_d C - d_{GT}| < 1]` against the subpixel ground truth and, for the
    variance, the peak hit rate of :math:`\\arg\\max_d -|\\sigma_L^2(x) - \\sigma_R^2(x + s d)|`
    (the 1x1-window :math:`C_\\sigma`). Decorrelation permutes every channel's residual
    blocks with the same :math:`\\Pi`, so :math:`\\sigma_R^2` becomes :math:`\\Pi(\\sigma_R^2)`.

    Parameters
    ----------
    left, right : sequence of array_like, each (H, W, C) or (H, W)
        The N seeds' renders of each view (an array (N, H, W[, C]) or any sequence that can
        be iterated twice, e.g. one that reads stores lazily).
    ground_truth_left : mapping
        Left view of the ground truth: ``disparity`` (subpixel), ``valid``, ``glass``.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign``.
    max_disparity : int, keyword-only
        :math:`D`; disparities :math:`0..D` are scored.
    window, block, seed : int, keyword-only
        Patch side, residual block side and the seed of :math:`\\Pi` (also of the margin
        sample).
    margin_samples : int, keyword-only
        Size of the margin sample per (cost, region, condition).
    workers : int, keyword-only
        Threads for the cost-volume scans.
    regions : sequence of str, keyword-only
        Regions scored (:data:`REGIONS` by default; ``("all",)`` without a glass mask).
    bootstrap : stereovar.statistics.bootstrap.BootstrapSettings, keyword-only, optional
        When given, the :math:`C_\\sigma` accuracy of region ``all`` in the normal condition
        gets ``low`` and ``high``: its 95% tile-bootstrap interval
        (:func:`stereovar.intervention.lift.wta_lift`, shifted by the chance level), which
        the audit's matching-cue rule reads. Every other row's are NaN.

    Returns
    -------
    InterventionResult
        ``rows``: ``value`` is the mean margin over the region's scored pixels pooled over
        seeds, or the accuracy pooled over seeds (hits / scoreable pixels); ``low`` and
        ``high`` its interval where computed; ``chance`` the mean chance level of an
        accuracy; ``n_pixels`` the scoreable pixels per seed; ``reason`` why ``value`` is
        NaN. ``margins``: the margin sample.
    """
    n = len(left)
    if n != len(right) or n < 2:
        raise ValueError(
            f"need the same number (>= 2) of left and right seeds, got {n} and {len(right)}"
        )
    moments_l, moments_r = _seed_moments(left), _seed_moments(right)
    if moments_l.shape != moments_r.shape:
        raise ValueError(f"left and right renders differ: {moments_l.shape} vs {moments_r.shape}")
    mean_l, mean_r = moments_l.mean, moments_r.mean
    height, width = mean_l.shape[:2]
    perm = block_permutation(height, width, block=block, seed=seed)
    d_gt = np.asarray(ground_truth_left["disparity"], dtype=np.float64)
    omega = valid_set(d_gt, sign=sign, valid=ground_truth_left["valid"])
    masks = region_masks(ground_truth_left, omega, regions=tuple(regions))
    scan = {
        "max_disparity": max_disparity,
        "sign": sign,
        "d_gt": d_gt,
        "workers": workers,
        "dtype": np.float64,
    }
    rng = np.random.default_rng([seed, 2])
    residual_plan = _sample_plan(masks, n, margin_samples, rng)
    variance_plan = _sample_plan(masks, 1, margin_samples, rng)
    acc = {
        (cost, condition): _RegionAccumulator(masks) for cost in COSTS for condition in CONDITIONS
    }
    samples: list[dict] = []

    def score(cost, condition, a, b, plan, run, seed_label):
        """Scan one cost volume, pool its metrics and keep its share of the margin sample."""
        result = scan_cost_volume(a, b, window=window, **scan)
        acc[(cost, condition)].add(result, d_gt)
        _take_samples(
            samples, plan, run, result.margin, cost=cost, condition=condition, seed=seed_label
        )

    for k, (render_l, render_r) in enumerate(zip(left, right, strict=True)):
        eps_l = (_as_float(render_l) - mean_l).mean(axis=-1)
        eps_r = (_as_float(render_r) - mean_r).mean(axis=-1)
        for condition in CONDITIONS:
            if condition == "decorrelated":
                eps_r = apply_block_permutation(eps_r, perm, block=block)
            score("residual_sad", condition, eps_l, eps_r, residual_plan, k, k)
    sigma_l, sigma_r = moments_l.variance, moments_r.variance
    for condition in CONDITIONS:
        if condition == "decorrelated":
            sigma_r = apply_block_permutation(sigma_r, perm, block=block)
        score("variance_cost", condition, sigma_l, sigma_r, variance_plan, 0, -1)
        peak = scan_cost_volume(sigma_l, sigma_r, window=1, **scan)
        acc[("variance_peak", condition)].add(peak, d_gt, margin=False)

    rows = []
    for cost, metrics in COSTS.items():
        for metric in metrics:
            for condition in CONDITIONS:
                a = acc[(cost, condition)]
                for region in masks:
                    if metric == "gt_margin":
                        runs = n if cost == "residual_sad" else 1
                        value, chance, n_pix = a.margin_entry(region, runs)
                    else:
                        value, chance, n_pix = a.rate_entry(region)
                    rows.append(
                        {
                            "cost": cost,
                            "metric": metric,
                            "region": region,
                            "condition": condition,
                            "value": value if n_pix else math.nan,
                            "low": math.nan,
                            "high": math.nan,
                            "chance": chance,
                            "n_pixels": n_pix,
                            "reason": "" if n_pix else f"no scoreable {region} pixels",
                        }
                    )
    if bootstrap is not None and "all" in masks:
        _lift_interval(rows, moments_l.variance, moments_r.variance, ground_truth_left,
                       sign=sign, max_disparity=max_disparity, window=window,
                       bootstrap=bootstrap)
    return InterventionResult(rows, samples)


def _lift_interval(rows, sigma_l, sigma_r, ground_truth_left, *, bootstrap, **scan) -> None:
    """Set ``low`` and ``high`` of the normal :math:`C_\\sigma` accuracy of region ``all``:
    the lift's tile-bootstrap interval plus its chance level."""
    from .lift import wta_lift

    lift = wta_lift(sigma_l, sigma_r, ground_truth_left, tile=bootstrap.tile,
                    reps=bootstrap.reps, seed=bootstrap.seed, **scan)
    for row in rows:
        if (row["cost"], row["metric"], row["region"], row["condition"]) == (
                "variance_cost", "wta_accuracy", "all", "normal"):
            row["low"] = lift["low"] + lift["chance"]
            row["high"] = lift["high"] + lift["chance"]
