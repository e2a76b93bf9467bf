"""The dose-response table: what a seed-mean mitigation ships, over its budget and the camera,
predicted and measured, with the budget that removes the cue and its cost.

From every scene's dose-response rows (:mod:`stereovar.calibration.dose_response`), one row
per transform, camera, budget multiple and kind (``predicted`` from the
:math:`1/\\mathrm{SPP}` law, ``measured`` on the run's renders at that budget):

- ``mc_specific``: the intensity-controlled :math:`\\rho` of what ships minus the same on its
  matched null at the same budget and camera, per scene
  (:func:`stereovar.calibration.nulls.difference_interval`; a predicted point averages its
  replicates' differences and bounds, the interval one measurement would have), combined over
  scenes (:func:`stereovar.statistics.across.combined_interval`);
- ``mc_cue``: :func:`~stereovar.statistics.mitigations.mc_cue_state` against the transform's
  equivalence margin on what it ships (the calibration's, ``margin``; ``margin_strength``
  the planted strength it certifies);
- ``psnr``: :math:`10\\log_{10}(1/\\overline{V})` with :math:`\\overline V` the shipped image's
  mean variance (its mean squared error: the transforms are unbiased), peak 1 as the
  mitigation table's;
- ``render_cost``: the samples behind one shipped image over the run's SPP (the cost of one
  render as a team makes it now).
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .mitigations import _f, equivalence_margin, mc_cue_state

DOSE_TABLE_COLUMNS = [
    "transform",
    "gain",
    "read_noise",
    "multiple",
    "shipped_spp",
    "render_cost",
    "kind",
    "n_scenes",
    "mc_specific",
    "mc_specific_low",
    "mc_specific_high",
    "null_partial",
    "margin",
    "margin_strength",
    "mc_cue",
    "psnr",
]
"""Columns of ``results/tables/dose_response.csv``."""

COMPACT_COLUMNS = [
    "mitigation",
    "camera gain (e- per unit)",
    "budget per image",
    "render time",
    "Monte Carlo-specific rho, predicted",
    "measured",
    "verdict",
    "PSNR",
]
"""Columns of ``results/tables/dose_response.md``."""


def _scene_difference(rows: list[dict], nulls: list[dict]) -> tuple[float, float, float]:
    """One scene's difference from its null (mean over replicates of each bound)."""
    from ..calibration.nulls import difference_interval

    null = [_f(r["rho"]) for r in nulls if math.isfinite(_f(r["rho"]))]
    if not null:
        return (math.nan,) * 3
    mean = float(np.mean(null))
    se = float(np.std(null, ddof=1) / math.sqrt(len(null))) if len(null) > 1 else 0.0
    bounds = [difference_interval(_f(r["rho"]), _f(r["boot_low"]), _f(r["boot_high"]), mean,
                                  se, _f(r.get("chance_se"))) for r in rows]
    bounds = [b for b in bounds if all(math.isfinite(x) for x in b)]
    if not bounds:
        return (math.nan,) * 3
    return tuple(float(x) for x in np.mean(bounds, axis=0))


def dose_table(rows: list[dict], nulls: list[dict] | None = None, *, spp: int) -> list[dict]:
    """The rows of :data:`DOSE_TABLE_COLUMNS` from every scene's dose-response rows.

    Parameters
    ----------
    rows : list of dict
        :data:`stereovar.calibration.dose_response.DOSE_COLUMNS` rows of every scene.
    nulls : list of dict, optional
        The calibration's matched nulls (``calibration_nulls.csv``) for the margin.
    spp : int
        The run's SPP (one render).

    Examples
    --------
    Two scenes whose predicted shipped rho sits 0.2 above a null at 0:

    >>> rows = [{"scene": s, "transform": "sensor_only", "gain": 1000.0, "read_noise": 2.0,
    ...          "multiple": 1, "shipped_spp": 64, "kind": k, "replicate": r,
    ...          "rho": 0.2 if k == "predicted" else 0.01 * (r - 0.5), "boot_low": 0.15,
    ...          "boot_high": 0.25, "chance_se": 0.01, "mse": 0.01}
    ...         for s in "ab" for k in ("predicted", "null") for r in (0, 1)]
    >>> (row,) = dose_table(rows, spp=32)
    >>> row["kind"], round(row["mc_specific"], 3), row["mc_cue"], row["render_cost"], row["psnr"]
    ('predicted', 0.2, 'remains', 2.0, 20.0)
    """
    from ..calibration.dose_response import GROUP
    from ..calibration.stacks import SHIPPED
    from .across import combined_interval

    groups = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))
    for r in rows:
        key = (r["transform"], _f(r["gain"]), _f(r["read_noise"]), int(_f(r["multiple"])))
        groups[key][r["scene"]][r["kind"]].append(r)
    out = []
    for (transform, gain, read_noise, multiple), scenes in sorted(groups.items()):
        margin = equivalence_margin(nulls or [], transform + SHIPPED)
        strength = equivalence_margin(nulls or [], transform + SHIPPED, column="margin_strength")
        shipped = int(_f(next(iter(next(iter(scenes.values())).values()))[0]["shipped_spp"]))
        for kind, label in (("predicted", "predicted"), ("renders", "measured")):
            diffs, nulls_mean, mses = [], [], []
            for by_kind in scenes.values():
                if not by_kind.get(kind) or not by_kind.get("null"):
                    continue
                diffs.append(_scene_difference(by_kind[kind], by_kind["null"]))
                nulls_mean.append(float(np.mean([_f(r["rho"]) for r in by_kind["null"]])))
                mses += [_f(r["mse"]) for r in by_kind[kind]]
            diffs = [d for d in diffs if math.isfinite(d[0])]
            if not diffs:
                continue
            value, low, high = combined_interval(*zip(*diffs, strict=True))
            mse = float(np.nanmean(mses))
            out.append({
                "transform": transform, "gain": gain, "read_noise": read_noise,
                "multiple": multiple, "shipped_spp": shipped,
                "render_cost": float(multiple * GROUP), "kind": label,
                "n_scenes": len(diffs), "mc_specific": value, "mc_specific_low": low,
                "mc_specific_high": high, "null_partial": float(np.mean(nulls_mean)),
                "margin": margin, "margin_strength": strength,
                "mc_cue": mc_cue_state(low, high, margin),
                "psnr": 10 * math.log10(1.0 / mse) if mse > 0 else math.nan,
            })
    return out


def removal_budgets(table: list[dict]) -> list[dict]:
    """Per transform and camera: the smallest budget whose predicted interval reads
    ``removed`` (None when no multiple does), the measured verdict at that budget where the
    run rendered it, the smallest measured budget that reads ``removed``, and the point at
    the largest budget predicted (for the sentence when none removes it)."""
    keyed = defaultdict(list)
    for r in table:
        keyed[(r["transform"], _f(r["gain"]), _f(r["read_noise"]))].append(r)
    out = []
    for (transform, gain, read_noise), rows in keyed.items():
        predicted = sorted((r for r in rows if r["kind"] == "predicted"),
                           key=lambda r: r["multiple"])
        measured = {r["multiple"]: r for r in rows if r["kind"] == "measured"}
        first = next((r for r in predicted if r["mc_cue"] == "removed"), None)
        verified = next((r for m, r in sorted(measured.items()) if r["mc_cue"] == "removed"),
                        None)
        out.append({
            "transform": transform, "gain": gain, "read_noise": read_noise,
            "predicted": first, "largest": predicted[-1] if predicted else None,
            "measured_there": measured.get(first["multiple"]) if first else None,
            "verified": verified,
        })
    return out


def budget_text(row: dict) -> str:
    """The samples behind one shipped image: its SPP, or where the renders' SPP is not
    given (an audit without ``audit.spp``) the number of renders.

    Examples
    --------
    >>> budget_text({"shipped_spp": 256, "render_cost": 8.0})
    '256 SPP per image'
    >>> budget_text({"shipped_spp": 0, "render_cost": 8.0})
    '8 renders per image'
    """
    spp = int(_f(row["shipped_spp"])) if math.isfinite(_f(row["shipped_spp"])) else 0
    if spp > 0:
        return f"{spp} SPP per image"
    return f"{_f(row['render_cost']):g} renders per image"


def _iv(row: dict) -> str:
    return (f"{row['mc_specific']:.3f} [{row['mc_specific_low']:.3f}, "
            f"{row['mc_specific_high']:.3f}]")


def dose_findings(table: list[dict]) -> list[str]:
    """One sentence per transform and camera: the budget that removes the cue, predicted and
    measured, with its cost, or the numbers at the largest budget when none does.

    Examples
    --------
    >>> row = {"transform": "sensor_only", "gain": 30.0, "read_noise": 2.0, "multiple": 4,
    ...        "shipped_spp": 256, "render_cost": 8.0, "mc_specific": 0.03,
    ...        "mc_specific_low": 0.01, "mc_specific_high": 0.05, "mc_cue": "removed",
    ...        "psnr": 18.3, "margin": 0.1, "margin_strength": 0.5}
    >>> print(dose_findings([{**row, "kind": "predicted"}, {**row, "kind": "measured"}])[0])
    sensor_only with a camera of gain 30 e- per unit (read noise 2 e-): removed from 256 SPP per image (8x the render time of one render, PSNR 18.3 dB), predicted 0.030 [0.010, 0.050] and measured 0.030 [0.010, 0.050] there (margin 0.1: no cue as strong as 0.5x the renders' own survives).
    """  # noqa: E501
    out = []
    for b in removal_budgets(table):
        head = (f"{b['transform']} with a camera of gain {b['gain']:g} e- per unit (read noise "
                f"{b['read_noise']:g} e-)")
        first, there, verified = b["predicted"], b["measured_there"], b["verified"]
        if first is None:
            last = b["largest"]
            text = f"{head}: no budget up to {budget_text(last)} removes it"
            text += (f" (predicted {_iv(last)} there, {last['mc_cue']}; "
                     f"{last['render_cost']:g}x the render time)")
            if verified is not None:
                text += f"; measured removed at {budget_text(verified)}: {_iv(verified)}"
            out.append(text + ".")
            continue
        cost = (f"{budget_text(first)} ({first['render_cost']:g}x the render time of one "
                f"render, PSNR {first['psnr']:.1f} dB)")
        if there is not None and there["mc_cue"] == "removed":
            text = (f"{head}: removed from {cost}, predicted {_iv(first)} and measured "
                    f"{_iv(there)} there")
        elif there is not None:
            text = (f"{head}: predicted removed from {cost} ({_iv(first)}), but measured "
                    f"{_iv(there)} there, {there['mc_cue']}: the prediction is optimistic")
        else:
            text = (f"{head}: predicted removed from {cost} ({_iv(first)}), not rendered at "
                    "that budget (render spp_xK to verify)")
        if verified is not None and verified is not there:
            text += f"; measured removed at {budget_text(verified)}: {_iv(verified)}"
        if math.isfinite(_f(first.get("margin"))):
            text += (f" (margin {first['margin']:.2g}: no cue as strong as "
                     f"{_f(first['margin_strength']):.2g}x the renders' own survives)")
        out.append(text + ".")
    return out


def compact_table(table: list[dict]) -> list[dict]:
    """:data:`COMPACT_COLUMNS`: one line per transform, camera and budget, the predicted and
    measured Monte Carlo-specific rho side by side."""
    measured = {(r["transform"], r["gain"], r["multiple"]): r for r in table
                if r["kind"] == "measured"}
    out = []
    for r in table:
        if r["kind"] != "predicted":
            continue
        m = measured.get((r["transform"], r["gain"], r["multiple"]))
        out.append({
            "mitigation": r["transform"],
            "camera gain (e- per unit)": f"{r['gain']:g}",
            "budget per image": budget_text(r).removesuffix(" per image"),
            "render time": f"{r['render_cost']:g}x",
            "Monte Carlo-specific rho, predicted": _iv(r),
            "measured": _iv(m) if m else "not rendered",
            "verdict": (m or r)["mc_cue"] + (" (measured)" if m else " (predicted)"),
            "PSNR": f"{(m or r)['psnr']:.1f} dB",
        })
    return out
