"""The mitigation table: each mitigation's cue, controls, Table 3 and image-quality cost.

One row per mitigation (:mod:`stereovar.mitigations`) and region. Intervals are stated per
column family:

- correlations (``rho``, ``partial``, the controls, the residual correlations): the mean over
  scenes with the scenes' block-bootstrap intervals combined
  (:func:`stereovar.statistics.across.combined_interval`; conditional on the scenes run);
- Table 3 (the :math:`C_\\sigma` lift over chance, the :math:`C_\\epsilon` shuffle effect):
  Student t over scenes, or for one scene a Wilson interval over its pixels
  (:func:`stereovar.statistics.lift.wta_lift`;
  :func:`stereovar.statistics.t_intervals.t_interval`);
- image quality: the mean over scenes with a Student t interval.

The Monte Carlo-specific part of the cue (``mc_specific``) is the intensity-controlled
:math:`\\rho` (``partial``: the variance correlation with the part explained by intensity
removed, paper Sec. 2.4's shot-noise control) minus the same statistic on the matched null
passed through the same transform (``null_partial``: camera-law noise drawn from the scene's
own seed means, :mod:`stereovar.calibration`), per scene, then combined over scenes. A
transform can make pure camera noise look like a cue (a denoiser's variance follows local
contrast, which both views share), and only the difference is Monte Carlo's. ``mc_cue``:
``remains`` when the difference's interval lies above 0, ``reversed`` below 0, ``removed``
when it lies inside the equivalence margin (``margin``: the Monte Carlo-specific
:math:`\\rho` that the calibration detects with 80% power through the same transform; none
when no planted strength reaches that power through it), else ``inconclusive`` (an interval
that merely covers 0 is no evidence of removal).

A transform that builds its images from the seed mean (``sensor_only``, ``equalise``) hides
the seed mean's Monte Carlo noise from Eq. 1 over its :math:`N` outputs;
``shipped_mc_specific`` is the same difference measured on what it ships, over disjoint seed
groups (:func:`stereovar.calibration.stacks.shipped_stack`); where it is measured,
``mc_cue`` is its verdict.
"""

from __future__ import annotations

import math

import numpy as np

from .across import rows_interval
from .lift import wta_lift
from .matched_null import matched_difference
from .t_intervals import t_interval

MITIGATION_COLUMNS = [
    "mitigation",
    "kind",
    "region",
    "n_scenes",
    "spp",
    "n_seeds",
    "render_spp",
    "aux_spp",
    "rho",
    "rho_low",
    "rho_high",
    "partial",
    "partial_low",
    "partial_high",
    "null_partial",
    "mc_specific",
    "mc_specific_low",
    "mc_specific_high",
    "margin",
    "margin_strength",
    "mc_cue",
    "shipped_mc_specific",
    "shipped_mc_specific_low",
    "shipped_mc_specific_high",
    "null_shift",
    "null_shift_low",
    "null_shift_high",
    "sensor_sim",
    "sensor_sim_low",
    "sensor_sim_high",
    "cs_lift",
    "cs_lift_low",
    "cs_lift_high",
    "ce_shuffle_effect",
    "ce_shuffle_effect_low",
    "ce_shuffle_effect_high",
    "residual_rho_gt",
    "residual_rho_gt_low",
    "residual_rho_gt_high",
    "residual_rho_zero",
    "residual_rho_zero_low",
    "residual_rho_zero_high",
    "psnr",
    "psnr_low",
    "psnr_high",
    "relative_mse",
    "bias",
    "relative_bias",
    "transform_ms_per_mpix",
    "description",
]
"""Columns of ``results/tables/mitigations.*``."""

INTERVALS = {
    "correlations": "95% spatial block bootstrap per scene, scenes combined (conditional on "
    "the scenes run)",
    "table3": "95% Student t over scenes (Wilson over pixels for one scene)",
    "image_quality": "95% Student t over scenes",
}
"""How each column family's interval is computed (also stated in ``results/summary.json``)."""

CORRELATION_METHODS = {
    "rho": "warp",
    "partial": "partial",
    "null_shift": "null_shift",
    "sensor_sim": "sensor_sim",
}
"""Column prefix to the registered statistic (:data:`stereovar.statistics.registry.METHODS`)
it summarises."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def mc_cue_state(low: float, high: float, margin: float = math.nan) -> str:
    """The verdict on a Monte Carlo-specific difference's 95% interval: ``remains`` (above
    :data:`~stereovar.calibration.rules.MIN_EFFECT`, the smallest cue the rules call),
    ``reversed`` (below its negative), ``removed`` (inside :math:`(-\\delta, \\delta)`, the
    equivalence margin: two one-sided tests), ``inconclusive`` (covers 0 but reaches past the
    margin, or no margin), or ``n/a`` (no interval).

    Examples
    --------
    >>> mc_cue_state(0.1, 0.3, 0.02), mc_cue_state(-0.01, 0.01, 0.02)
    ('remains', 'removed')
    >>> mc_cue_state(-0.1, 0.2, 0.02), mc_cue_state(float("nan"), 1.0)
    ('inconclusive', 'n/a')
    >>> mc_cue_state(0.02, 0.08, 0.02)  # above 0, not above the smallest cue called
    'inconclusive'
    """
    from ..calibration.rules import MIN_EFFECT

    if not (math.isfinite(low) and math.isfinite(high)):
        return "n/a"
    if low > MIN_EFFECT:
        return "remains"
    if high < -MIN_EFFECT:
        return "reversed"
    if math.isfinite(margin) and margin > 0 and -margin < low and high < margin:
        return "removed"
    return "inconclusive"


def equivalence_margin(nulls, transform: str = "none", method="partial",
                       column: str = "margin") -> float:
    """The margin of ``removed`` for rows measured through ``transform``: the Monte
    Carlo-specific :math:`\\rho` that the calibration detects with 80% power through that
    transform (the nulls' ``margin``). NaN when no planted strength reaches 80% power
    through it: the instrument cannot then show that the cue is gone. ``column``
    ``margin_strength``: the planted strength (a multiple of the renders' own) that sets it,
    what a result inside the margin certifies is gone."""
    for r in nulls:
        if (r["transform"], r["method"]) == (transform, method) and math.isfinite(
            _f(r.get(column))
        ):
            return _f(r[column])
    return math.nan


def _scene_values(rows, region, quantity) -> list[float]:
    return [_f(r["value"]) for r in rows if r["region"] == region and r["quantity"] == quantity]


def _intervention_effect(rows, region) -> tuple[float, float, float]:
    """:math:`C_\\epsilon` WTA accuracy, normal minus block-shuffled, mean over scenes with a
    t interval (Table 3's residual-shuffle effect)."""
    per_scene = {}
    for r in rows:
        if (r["cost"], r["metric"], r["region"]) != ("residual_sad", "wta_accuracy", region):
            continue
        if str(r.get("source") or "render") != "render":
            continue
        per_scene.setdefault(r["scene"], {})[r["condition"]] = _f(r["value"])
    diffs = [
        c["normal"] - c["decorrelated"]
        for c in per_scene.values()
        if "normal" in c and "decorrelated" in c
    ]
    return t_interval(diffs)


def mitigation_table(
    runs: list[dict], nulls: list[dict] | None = None, *, shipped: list[dict] | None = None
) -> list[dict]:
    """The rows of :data:`MITIGATION_COLUMNS`.

    Parameters
    ----------
    runs : list of dict
        Per mitigation, in table order: ``mitigation``, ``kind``, ``description``, ``spp``,
        optionally ``render_spp`` (samples per pixel behind one image; ``spp`` by default)
        and ``aux_spp`` (the auxiliary pass's; 0 by default),
        ``correlation`` (its scenes' correlation rows), ``intervention`` (its scenes'
        intervention rows; may be empty) and ``scene_rows`` (its scenes' mitigation rows,
        :data:`stereovar.jobs.mitigation_scene.MITIGATION_SCENE_COLUMNS`), and optionally
        ``calibration_transform``: the transform whose matched null applies (``none`` by
        default, for renders as rendered).
    nulls : list of dict, optional
        The calibration's matched nulls (:data:`stereovar.calibration.summary.NULL_COLUMNS`);
        without them ``mc_specific`` and ``mc_cue`` are NaN and ``n/a``.
    shipped : list of dict, optional
        The calibration's ``renders`` rows: each seed-mean transform's statistics on what it
        ships (over disjoint seed groups), whose difference from their own matched null is
        ``shipped_mc_specific`` (NaN for the other rows).

    Returns
    -------
    list of dict
        One row per mitigation and region: ``all``, and each other region that a scene's
        correlation rows define.
    """
    from .regions import REGIONS

    out = []
    for run in runs:
        corr = run["correlation"]
        # "all" always; a region only where some scene defines it (a material mask exists)
        regions = [
            g
            for g in REGIONS
            if g == "all" or any(r["region"] == g and math.isfinite(_f(r["rho"])) for r in corr)
        ]
        scenes = sorted({r["scene"] for r in corr})
        n_seeds = sorted({int(_f(r["n_seeds"])) for r in corr if math.isfinite(_f(r["n_seeds"]))})
        for region in regions:
            row = {
                "mitigation": run["mitigation"],
                "kind": run["kind"],
                "region": region,
                "n_scenes": len(scenes),
                "spp": run["spp"],
                "n_seeds": n_seeds[0] if len(n_seeds) == 1 else ",".join(map(str, n_seeds)),
                "render_spp": run.get("render_spp", run["spp"]),
                "aux_spp": run.get("aux_spp", 0),
                "description": run["description"],
            }
            for column, method in CORRELATION_METHODS.items():
                chosen = [r for r in corr if r["region"] == region and r["method"] == method]
                row[column], row[f"{column}_low"], row[f"{column}_high"] = rows_interval(chosen)
            null, *diff = matched_difference(
                corr,
                nulls or [],
                transform=run.get("calibration_transform", "none"),
                region=region,
            )
            row["null_partial"] = null
            row["mc_specific"], row["mc_specific_low"], row["mc_specific_high"] = diff
            matched = run.get("calibration_transform", "none")
            row["margin"] = equivalence_margin(nulls or [], matched)
            row["margin_strength"] = equivalence_margin(nulls or [], matched,
                                                        column="margin_strength")
            row["mc_cue"] = mc_cue_state(diff[1], diff[2], row["margin"])
            label = matched + "|shipped"
            _, *ships = matched_difference(
                [r for r in shipped or [] if r["transform"] == label],
                nulls or [],
                transform=label,
                region=region,
            )
            (
                row["shipped_mc_specific"],
                row["shipped_mc_specific_low"],
                row["shipped_mc_specific_high"],
            ) = ships
            if all(math.isfinite(x) for x in ships):
                # what a team ships decides: the seed mean's Monte Carlo noise counts
                row["margin"] = equivalence_margin(nulls or [], label)
                row["margin_strength"] = equivalence_margin(nulls or [], label,
                                                            column="margin_strength")
                row["mc_cue"] = mc_cue_state(ships[1], ships[2], row["margin"])
            lift = (
                wta_lift(run["intervention"], "render", region)
                if run["intervention"]
                else (math.nan, math.nan, math.nan)
            )
            row["cs_lift"], row["cs_lift_low"], row["cs_lift_high"] = lift
            effect = _intervention_effect(run["intervention"], region)
            (
                row["ce_shuffle_effect"],
                row["ce_shuffle_effect_low"],
                row["ce_shuffle_effect_high"],
            ) = effect
            scene_rows = run["scene_rows"]
            for quantity in ("residual_rho_gt", "residual_rho_zero"):
                chosen = [
                    {"rho": r["value"], "boot_low": r["low"], "boot_high": r["high"]}
                    for r in scene_rows
                    if r["region"] == region and r["quantity"] == quantity
                ]
                row[quantity], row[f"{quantity}_low"], row[f"{quantity}_high"] = rows_interval(
                    chosen
                )
            row["psnr"], row["psnr_low"], row["psnr_high"] = t_interval(
                _scene_values(scene_rows, region, "psnr")
            )
            for quantity in ("relative_mse", "bias", "relative_bias"):
                values = np.asarray(_scene_values(scene_rows, region, quantity))
                values = values[np.isfinite(values)]
                row[quantity] = float(values.mean()) if values.size else math.nan
            ms = np.asarray(_scene_values(scene_rows, "all", "transform_ms_per_mpix"))
            ms = ms[np.isfinite(ms)]
            row["transform_ms_per_mpix"] = float(ms.mean()) if ms.size else math.nan
            out.append(row)
    return out


def _iv(row, column, unit="", digits=3) -> str:
    value, low, high = (_f(row.get(k)) for k in (column, f"{column}_low", f"{column}_high"))
    if not math.isfinite(value):
        return "n/a"
    text = f"{value:.{digits}f}{unit}"
    if math.isfinite(low) and math.isfinite(high):
        text += f" [{low:.{digits}f}, {high:.{digits}f}]"
    return text


def _certifies(row) -> str:
    """What a ``removed`` row's margin certifies, from the strength that set it."""
    strength = _f(row.get("margin_strength"))
    if not math.isfinite(strength):
        return ""
    return f"; no cue as strong as {strength:.2g}x the renders' own survives it"


def mitigation_findings(rows: list[dict], region: str = "all") -> list[str]:
    """Plain-language lines of the mitigation table over ``region``: per mitigation its
    Monte Carlo-specific :math:`\\rho` (the intensity-controlled :math:`\\rho` minus its
    matched null through the same transform) and verdict, beside the renders as they are,
    and at what PSNR; then which mitigations remove it (inside the equivalence margin) and
    the cheapest in PSNR.

    Examples
    --------
    >>> rows = [
    ...     {"mitigation": "none", "region": "all", "mc_specific": 0.5, "mc_specific_low": 0.4,
    ...      "mc_specific_high": 0.6, "null_partial": 0.0, "margin": 0.02, "mc_cue": "remains",
    ...      "psnr": 30.0, "psnr_low": 29.0, "psnr_high": 31.0},
    ...     {"mitigation": "sensor_only", "region": "all", "mc_specific": 0.001,
    ...      "mc_specific_low": -0.01, "mc_specific_high": 0.012, "null_partial": 0.0,
    ...      "margin": 0.02, "margin_strength": 0.25, "mc_cue": "removed", "psnr": 28.0,
    ...      "psnr_low": 27.0, "psnr_high": 29.0},
    ... ]
    >>> print(mitigation_findings(rows)[-1])  # doctest: +NORMALIZE_WHITESPACE
    Removes the Monte Carlo-specific part (its interval inside the calibration's equivalence
    margin): sensor_only (PSNR 28.00 dB [27.00, 29.00] against 30.00 dB [29.00, 31.00] as
    rendered; no cue as strong as 0.25x the renders' own survives it).
    """
    chosen = [r for r in rows if r["region"] == region]
    base = next((r for r in chosen if r["mitigation"] == "none"), None)
    lines = []
    for r in chosen:
        ships = ""
        if math.isfinite(_f(r.get("shipped_mc_specific"))):
            ships = (f"; in what it ships (one image per view, the seed mean through the "
                     f"mitigation) {_iv(r, 'shipped_mc_specific')}, the number its verdict "
                     "reads")
        lines.append(
            f"{r['mitigation']}: {r['mc_cue']}. Monte Carlo-specific rho "
            f"{_iv(r, 'mc_specific')} (its intensity-controlled rho minus its matched null, "
            f"which is {_f(r.get('null_partial')):.3f}){ships}; residual correlation at zero "
            f"disparity {_iv(r, 'residual_rho_zero')}; PSNR {_iv(r, 'psnr', ' dB', 2)}"
        )
    margins = [_f(r.get("margin")) for r in chosen if math.isfinite(_f(r.get("margin")))]
    within = " (its interval inside the calibration's equivalence margin)" if margins else ""
    removing = [r for r in chosen if r["mitigation"] != "none" and r["mc_cue"] == "removed"]
    unclear = [r["mitigation"] for r in chosen if r["mc_cue"] in ("inconclusive", "n/a")]
    if not removing:
        lines.append(
            "No mitigation measured here is shown to remove the Monte Carlo-specific part"
            + (
                " (that needs its interval inside the calibration's equivalence margin)."
                if within
                else " (no equivalence margin: run the calibration)."
            )
        )
    else:
        removing.sort(key=lambda r: -_f(r.get("psnr")) if math.isfinite(_f(r.get("psnr"))) else 1e9)
        against = f" against {_iv(base, 'psnr', ' dB', 2)} as rendered" if base else ""
        lines.append(
            f"Removes the Monte Carlo-specific part{within}: "
            + ", ".join(
                f"{r['mitigation']} (PSNR {_iv(r, 'psnr', ' dB', 2)}{against}"
                + _certifies(r) + ")" for r in removing
            )
            + "."
        )
    if unclear:
        lines.insert(
            len(lines) - 1,
            "Neither shown to remain nor to be removed (the interval covers 0 but reaches past "
            "the margin): " + ", ".join(unclear) + ".",
        )
    return lines


HEADLINE_COLUMNS = [
    "mitigation",
    "samples per image",
    "Monte Carlo-specific rho",
    "matched null",
    "what ships",
    "C_sigma lift",
    "PSNR against equal budget",
    "verdict",
]
"""Columns of ``results/tables/mitigations_headline.*``: what the results page shows."""


def equal_budget_psnr(rows: list[dict], row: dict) -> tuple[float, str]:
    """The PSNR a raw render reaches at ``row``'s samples per image: the ``spp_xK`` row
    rendered at that SPP when the table has it (``rendered``), else the renders' PSNR moved
    by the Monte Carlo variance's :math:`1/\\mathrm{SPP}` law (``predicted``).

    .. math::

        \\mathrm{PSNR}(B) = \\mathrm{PSNR}_{\\text{none}}
            + 10 \\log_{10} \\frac{B}{\\mathrm{SPP}}

    (an unbiased estimator's error variance falls as :math:`1/B`; the ``spp_xK`` rows test
    the law). NaN and ``""`` when neither is possible.

    Examples
    --------
    >>> rows = [{"mitigation": "none", "kind": "baseline", "region": "all", "spp": 32,
    ...          "render_spp": 32, "psnr": 25.0}]
    >>> psnr, how = equal_budget_psnr(rows, {"region": "all", "render_spp": 256})
    >>> round(psnr, 2), how
    (34.03, 'predicted')
    """
    region, budget = row["region"], _f(row.get("render_spp"))
    for r in rows:
        if r["region"] == region and r.get("kind") == "spp" and _f(r["spp"]) == budget:
            return _f(r["psnr"]), "rendered"
    base = next((r for r in rows if r["region"] == region and r["mitigation"] == "none"), None)
    if base is None or not (math.isfinite(budget) and budget > 0):
        return math.nan, ""
    psnr, spp = _f(base.get("psnr")), _f(base.get("spp"))
    if not (math.isfinite(psnr) and spp > 0):
        return math.nan, ""
    return psnr + 10.0 * math.log10(budget / spp), "predicted"


def headline_table(rows: list[dict], region: str = "all") -> list[dict]:
    """The mitigation table in :data:`HEADLINE_COLUMNS`, one row per mitigation over
    ``region``: each number with its 95% interval, the Monte Carlo-specific part beside its
    matched null through the same transform, what seed-mean transforms ship, and PSNR beside
    a raw render at the same samples per image (:func:`equal_budget_psnr`)."""
    out = []
    chosen = [r for r in rows if r["region"] == region]
    for r in chosen:
        psnr = _iv(r, "psnr", " dB", 1)
        budget, how = equal_budget_psnr(chosen, r)
        if r["mitigation"] != "none" and math.isfinite(budget) and r.get("kind") != "spp":
            psnr += f"; {budget:.1f} dB at equal budget ({how})"
        null = _f(r.get("null_partial"))
        lift = _iv(r, "cs_lift")
        out.append(
            {
                "mitigation": r["mitigation"],
                "samples per image": int(_f(r.get("render_spp")))
                if math.isfinite(_f(r.get("render_spp")))
                else "",
                "Monte Carlo-specific rho": _iv(r, "mc_specific"),
                "matched null": f"{null:.3f}" if math.isfinite(null) else "n/a",
                "what ships": _iv(r, "shipped_mc_specific")
                if math.isfinite(_f(r.get("shipped_mc_specific")))
                else "as measured",
                "C_sigma lift": lift,
                "PSNR against equal budget": psnr,
                "verdict": r["mc_cue"],
            }
        )
    return out
