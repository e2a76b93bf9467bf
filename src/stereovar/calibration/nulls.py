"""Matched nulls and each statistic's difference from its null, per scene and with the scenes
combined.

Per scene, transform, statistic and null kind, the null's replicates give its mean
:math:`\\bar\\rho_0` and that mean's standard error (:func:`matched_nulls`; the ``camera``
null, or the camera law through an 8-bit pipeline's encoding, :func:`is_null_kind`). Every
replicate row gets its difference from its matched null with a 95% interval
(:func:`difference_interval`, :func:`with_differences`), and the scenes of each replicate are
combined as the tables combine them (:func:`combined_rows`).
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from ..intervention.lift import LIFT_METHOD
from ..statistics.across import combined_correlation_interval, combined_interval
from .rates import Z, _f


def difference_interval(
    value, low, high, null, null_se, chance_se=math.nan
) -> tuple[float, float, float]:
    """A statistic minus its matched null, with a 95% interval.

    .. math::

        \\Delta = \\rho - \\bar\\rho_0, \\qquad
        \\Delta \\pm z_{0.975}\\sqrt{\\max\\Bigl(\\Bigl(\\frac{h - \\ell}{2 z_{0.975}}
            \\Bigr)^2,\\ \\mathrm{se}_{\\text{chance}}^2\\Bigr) + \\mathrm{se}_0^2}

    with :math:`[\\ell, h]` the statistic's 95% interval (spatial block bootstrap, which
    sees dependence within its tiles only), :math:`\\mathrm{se}_{\\text{chance}}` the
    standard error of the same :math:`\\rho` were the two fields independent, from their
    own autocovariances over every lag (:func:`stereovar.statistics.chance.chance_se`:
    how far two fields with this structure correlate by chance, which the bootstrap misses
    when the structure is larger than a tile), :math:`\\bar\\rho_0` the camera null's mean
    over its replicates and :math:`\\mathrm{se}_0` that mean's standard error. Under the
    null the two standard errors estimate the same spread, each missing part of it, so the
    larger is used, not their sum: the sum counted it twice and covered 100% on the camera
    null (the bootstrap's 0.004 plus the unaligned renders' 0.02-0.06).

    Examples
    --------
    >>> [round(x, 3) for x in difference_interval(0.30, 0.20, 0.40, 0.10, 0.0)]
    [0.2, 0.1, 0.3]

    A chance term smaller than the bootstrap's changes nothing; a larger one replaces it:

    >>> [round(x, 3) for x in difference_interval(0.30, 0.20, 0.40, 0.10, 0.0, 0.01)]
    [0.2, 0.1, 0.3]
    >>> [round(x, 3) for x in difference_interval(0.30, 0.30, 0.30, 0.10, 0.0, 0.05)]
    [0.2, 0.102, 0.298]
    """
    value, low, high, null, null_se, chance_se = (
        _f(x) for x in (value, low, high, null, null_se, chance_se)
    )
    if not all(math.isfinite(x) for x in (value, low, high, null)):
        return math.nan, math.nan, math.nan
    own = (high - low) / (2 * Z)
    if math.isfinite(chance_se):
        own = max(own, chance_se)
    se = math.sqrt(own**2 + (null_se if math.isfinite(null_se) else 0.0) ** 2)
    diff = value - null
    return diff, diff - Z * se, diff + Z * se


def _group(rows, keys):
    out = defaultdict(list)
    for r in rows:
        out[tuple(r[k] for k in keys)].append(r)
    return out


def _sd(values) -> float:
    v = np.array([x for x in values if math.isfinite(x)])
    return float(v.std(ddof=1)) if v.size > 1 else math.nan


def is_null_kind(kind: str) -> bool:
    """Whether a design's replicates serve as a matched null: ``camera``, or the camera law
    through an encoding (``camera_<pipeline>``)."""
    return kind == "camera" or str(kind).startswith("camera_")


def matched_nulls(rows: list[dict]) -> dict:
    """Per (scene, transform, region, method, null kind): the null's mean :math:`\\rho`
    over its replicates, that mean's standard error and the number of replicates, the
    per-replicate values (for leave-one-out use), and for the ``camera`` null the
    ``misaligned`` null's standard deviation (``chance_sd``, the chance correlation of
    unaligned fields with the renders' structure, a diagnostic)."""
    out: dict = {}
    keys = ("scene", "transform", "region", "method")

    def entry(key):
        return out.setdefault(key, {"mean": math.nan, "se": math.nan, "n": 0,
                                    "values": {}, "chance": {}, "chance_sd": math.nan})

    for key, group in _group([r for r in rows if r["kind"] == "misaligned"], keys).items():
        values = {int(r["replicate"]): _f(r["rho"]) for r in group}
        e = entry((*key, "camera"))
        e["chance"], e["chance_sd"] = values, _sd(values.values())
    chosen = [r for r in rows if is_null_kind(r["kind"])]
    for key, group in _group(chosen, (*keys, "kind")).items():
        e = entry(key)
        values = {int(r["replicate"]): _f(r["rho"]) for r in group}
        finite = np.array([v for v in values.values() if math.isfinite(v)])
        e["values"] = values
        e["n"] = int(finite.size)
        if finite.size:
            e["mean"] = float(finite.mean())
            e["se"] = _sd(finite) / math.sqrt(finite.size)
    return out


def _loo_null(null: dict, replicate: int) -> tuple[float, float]:
    """The null's mean and standard error without ``replicate`` (so a null replicate is
    never compared with itself)."""
    others = np.array(
        [v for k, v in null["values"].items() if k != replicate and math.isfinite(v)]
    )
    if others.size == 0:
        return math.nan, math.nan
    se = float(others.std(ddof=1) / math.sqrt(others.size)) if others.size > 1 else math.nan
    return float(others.mean()), se


def with_differences(rows: list[dict], nulls: dict) -> list[dict]:
    """Each replicate row with ``diff``, ``diff_low`` and ``diff_high``: the statistic minus
    its scene's matched null (the row's ``null_kind``, ``camera`` by default) through the
    same transform (:func:`difference_interval`; a null replicate is compared with the other
    replicates only)."""
    out = []
    for r in rows:
        null_kind = r.get("null_kind") or "camera"
        key = (r["scene"], r["transform"], r["region"], r["method"], null_kind)
        null = nulls.get(key)
        if null is None:
            d = (math.nan,) * 3
        else:
            replicate = int(r["replicate"])
            mean, se = (
                _loo_null(null, replicate) if r["kind"] == null_kind
                else (null["mean"], null["se"])
            )
            d = difference_interval(r["rho"], r["boot_low"], r["boot_high"], mean, se,
                                    r.get("chance_se", math.nan))
        out.append({**r, "diff": d[0], "diff_low": d[1], "diff_high": d[2]})
    return out


def combined_rows(rows: list[dict]) -> list[dict]:
    """The scenes of each replicate combined as the tables combine them: the mean of the
    scenes' values, for the statistic with its interval on Fisher's :math:`z`
    (:func:`~stereovar.statistics.across.combined_correlation_interval`, inside
    :math:`[-1, 1]`) and for its difference from the matched null with the normal one
    (:func:`~stereovar.statistics.across.combined_interval`: a difference of two
    correlations lies in :math:`[-2, 2]`)."""
    keys = ("replicate", "kind", "strength_factor", "transform", "region", "method")
    out = []
    for key, group in _group(rows, keys).items():
        row = dict(zip(keys, key, strict=True))
        row["scene"] = "combined"
        combine = combined_interval if row["method"] == LIFT_METHOD else (
            combined_correlation_interval)  # a lift is a difference of rates, not a rho
        row["rho"], row["boot_low"], row["boot_high"] = combine(
            [g["rho"] for g in group], [g["boot_low"] for g in group],
            [g["boot_high"] for g in group],
        )
        row["diff"], row["diff_low"], row["diff_high"] = combined_interval(
            [g["diff"] for g in group], [g["diff_low"] for g in group],
            [g["diff_high"] for g in group],
        )
        out.append(row)
    return out
