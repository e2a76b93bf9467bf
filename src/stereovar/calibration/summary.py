"""The calibration table: false-positive rates, power and interval coverage of every rule.

From every scene's replicate rows (:mod:`stereovar.calibration.replicates`), per transform and
statistic:

``false_positive_rate``
    how often a rule fires on a matched null, against its level of 5%;
``power``
    how often it fires on the planted cue at each strength;
``smallest_detectable``
    the smallest planted strength (a multiple of what the renders show) detected with 80%
    power, interpolated on the grid; its mean Monte Carlo-specific :math:`\\rho` is the
    equivalence margin of the ``removed`` verdict;
``coverage``
    how often a 95% interval contains the value it estimates, against 95 +/- 2%.

Rates carry their 95% Wilson interval and the number of replicates. A rate held to the 5%
level ``meets_target`` (:func:`meets_level`) only when its whole interval does: ``yes`` when
the upper bound is at most 5%, ``no`` when the lower bound is above it (refuted), and
``not shown`` when the interval straddles it (too few replicates to show the level: with no
false positive that takes :func:`replicates_to_show`, 73). The rules:

``above_zero``
    the interval lies above 0 (the audit's Monte Carlo rule on ``partial``, the old
    mitigation ``remains``);
``above_null``
    the statistic minus its matched null through the same transform (the mean over the
    ``camera`` null's other replicates, or the encoded null of an 8-bit pipeline) has an
    interval above :data:`MIN_EFFECT` (:func:`difference_interval`): what "Monte
    Carlo-specific" means here;
``removed``
    that difference's interval lies inside the equivalence margin;
``shared``
    the audit's shared-streams check (``shared_streams``: the per-seed residuals'
    cross-view correlation at zero disparity) has an interval above
    :data:`~stereovar.statistics.residuals.SHARED_STREAMS`, on frames whose views are
    independent;
``claim <id> holds``
    a level claim of the claims table on :math:`\\rho` against the ``sensor_sim`` camera
    baseline holds on the replicate's scenes (:mod:`stereovar.calibration.claims`, whose rows
    the calibration table job adds; scenes combined, as the table combines them);
``matching``
    the audit's matching-cue rule (``c_sigma_lift``: the variance-matching cost's
    winner-take-all lift over chance, :mod:`stereovar.intervention.lift`): the lift minus its
    matched null's has an interval above 0, and the same replicate's ``partial`` fires
    ``above_null`` (a matching cue is called only where the cue is Monte Carlo-specific, so
    the rule's false positives are at most the verdict rule's).

Cue-free designs are the matched nulls (``camera``, ``misaligned``) and the camera pipelines
(:mod:`stereovar.calibration.pipelines`, with the 8-bit ones' encoded nulls); each rule's
false-positive rate is given per design and over all of them (:data:`ANY_NULL`).

``scope`` is ``scene`` (one scene's rows) or ``combined`` (the scenes' rows of one replicate
combined as the tables combine them:
:func:`stereovar.statistics.across.combined_correlation_interval` for the statistic and
:func:`stereovar.statistics.across.combined_interval` for its difference).
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
from scipy import stats

from ..intervention.lift import LIFT_METHOD
from ..statistics.across import combined_correlation_interval, combined_interval

LEVEL = 0.05
"""The level every rule is held to: at most 5% false positives."""

COVERAGE_TARGET = (0.93, 0.97)
"""A 95% interval's coverage must lie within 95 +/- 2%."""

POWER = 0.8
"""The power at which a strength counts as detectable."""

MIN_EFFECT = 0.05
"""The smallest Monte Carlo-specific :math:`\\rho` a rule calls a cue: the difference from
the matched null must have its 95% interval above it, not merely above 0. Over 57 600
pixels the interval is about 0.01 wide, so any small misfit of the control is significant;
the camera pipelines outside the null's class (:mod:`stereovar.calibration.pipelines`) leave
0.000-0.032 after the intensity control's colour and position terms (0.018 +/- 0.015 for
8-bit sRGB at 1 DN, 0.032 +/- 0.009 and at most 0.048 for a fixed gain map; the default
scenes, 16 replicates each),
and fired the rule above 0 on 6-50% of their replicates. A cue this weak is below what a
camera pipeline leaves, so it is not called Monte Carlo-specific."""

ANY_NULL = "any cue-free design"
"""The ``kind`` of the false-positive rows that pool every cue-free design of a scope."""

MARGIN_REPLICATES = 8
"""Fewest replicates of the scenes combined whose power curve sets a transform's equivalence
margin; with fewer (the denoisers' few replicates), the scenes' pooled curve sets it."""

Z = float(stats.norm.ppf(0.975))

CALIBRATION_TABLE_COLUMNS = [
    "check",
    "rule",
    "scope",
    "transform",
    "method",
    "kind",
    "strength_factor",
    "value",
    "low",
    "high",
    "n",
    "target",
    "meets_target",
    "note",
]
"""Columns of ``results/tables/calibration.*``."""

NULL_COLUMNS = [  # margin: the equivalence margin of the row's transform and statistic
    "scene",
    "transform",
    "region",
    "method",
    "null_rho",
    "null_se",
    "n",
    "chance_sd",
    "margin",
    "margin_strength",
]
"""Columns of ``results/tables/calibration_nulls.csv``: each scene's matched null per
transform and statistic, the equivalence margin and the planted strength (a multiple of the
renders' own) that sets it: a result inside the margin certifies that no cue as strong as
that survives."""

SUMMARY_METHODS = ("warp", "partial", "log", "spearman", "relative", "null_shift",
                   "shared_streams", LIFT_METHOD)
"""The statistics the table reports (every calibrated one stays in the replicate rows)."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def rate(k: int, n: int) -> tuple[float, float, float]:
    """A proportion :math:`k/n` with its 95% Wilson interval (NaN for :math:`n = 0`).

    Examples
    --------
    >>> [round(x, 3) for x in rate(5, 100)]
    [0.05, 0.022, 0.112]
    """
    if n <= 0:
        return math.nan, math.nan, math.nan
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=0.95, method="wilson")
    return k / n, float(ci.low), float(ci.high)


NOT_SHOWN = "not shown"
"""``meets_target`` of a rate whose Wilson interval straddles its level: neither shown nor
refuted, too few replicates to tell."""


def meets_level(low, high, level: float = LEVEL) -> str:
    """Whether a rate held to at most ``level`` is shown to meet it, from its 95% Wilson
    interval :math:`[\\ell, h]`: ``yes`` when the whole interval does (:math:`h \\le` level),
    ``no`` when it lies above (:math:`\\ell >` level: refuted), :data:`NOT_SHOWN` when it
    straddles the level, ``""`` when it is not known.

    Examples
    --------
    >>> [meets_level(*rate(k, n)[1:]) for k, n in ((0, 80), (0, 16), (10, 20))]
    ['yes', 'not shown', 'no']
    """
    low, high = _f(low), _f(high)
    if not (math.isfinite(low) and math.isfinite(high)):
        return ""
    if high <= level:
        return "yes"
    if low > level:
        return "no"
    return NOT_SHOWN


def replicates_to_show(level: float = LEVEL) -> int:
    """The fewest replicates that can show a rate of at most ``level``: the smallest
    :math:`n` whose Wilson upper bound with no false positive, :math:`z^2/(n + z^2)`, is at
    most ``level`` (more are needed when any replicate fires).

    Examples
    --------
    >>> replicates_to_show()
    73
    """
    n = max(1, math.floor(Z * Z * (1 - level) / level) - 1)
    while rate(0, n)[2] > level:
        n += 1
    return n


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


def equivalent(low, high, margin) -> bool:
    """Whether an interval lies inside :math:`[-\\delta, \\delta]` (two one-sided tests)."""
    low, high, margin = _f(low), _f(high), _f(margin)
    return bool(math.isfinite(margin) and margin > 0 and -margin < low and high < margin)


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


def _fires(rule: str, r: dict, margin=math.nan) -> bool | None:
    if rule == "shared":
        from ..statistics.residuals import SHARED_STREAMS

        low = _f(r["boot_low"])
        return None if not math.isfinite(low) else low > SHARED_STREAMS
    if rule == "above_zero":
        low = _f(r["boot_low"])
        return None if not math.isfinite(low) else low > 0
    low, high = _f(r["diff_low"]), _f(r["diff_high"])
    if not (math.isfinite(low) and math.isfinite(high)):
        return None
    if rule == "matching":
        specific = r.get("partial_fires")
        return None if specific is None else bool(low > 0 and specific)
    if rule == "above_null":
        return low > MIN_EFFECT
    if rule == "removed":
        return equivalent(low, high, margin)
    raise ValueError(f"unknown rule {rule!r}")


def _count(rule, group, margin=math.nan) -> tuple[int, int]:
    fired = [_fires(rule, r, margin) for r in group]
    fired = [f for f in fired if f is not None]
    return int(sum(fired)), len(fired)


def detectable(power_curve: list[tuple[float, float]], target: float = POWER) -> float:
    """The smallest strength whose power reaches ``target``, linearly interpolated between
    the grid's strengths (NaN when none does).

    Examples
    --------
    >>> detectable([(0.25, 0.1), (0.5, 0.5), (1.0, 0.9)])
    0.875
    """
    prev = None
    for s, p in sorted(power_curve):
        if math.isfinite(p) and p >= target:
            if prev is None or not math.isfinite(prev[1]):
                return float(s)
            s0, p0 = prev
            if p == p0:
                return float(s)
            return float(s0 + (target - p0) * (s - s0) / (p - p0))
        prev = (s, p)
    return math.nan


def _coverage(group, column_value="rho", low="boot_low", high="boot_high") -> tuple[int, int]:
    """Replicates whose interval holds the leave-one-out mean of the same scene's other
    replicates (the estimand: the statistic's expectation under this design and scene)."""
    hits = total = 0
    for scene_group in _group(group, ("scene",)).values():
        k, n = _scene_coverage(scene_group, column_value, low, high)
        hits, total = hits + k, total + n
    return hits, total


def _scene_coverage(group, column_value, low, high) -> tuple[int, int]:
    values = np.array([_f(r[column_value]) for r in group])
    lows = np.array([_f(r[low]) for r in group])
    highs = np.array([_f(r[high]) for r in group])
    ok = np.isfinite(values) & np.isfinite(lows) & np.isfinite(highs)
    values, lows, highs = values[ok], lows[ok], highs[ok]
    n = values.size
    if n < 3:
        return 0, 0
    truth = (values.sum() - values) / (n - 1)
    return int(np.sum((lows <= truth) & (truth <= highs))), int(n)


def calibration_table(rows: list[dict], *, methods=SUMMARY_METHODS, region="all") -> tuple:
    """The calibration table and the matched nulls.

    Parameters
    ----------
    rows : list of dict
        Every scene's replicate rows (:data:`~stereovar.calibration.replicates.
        CALIBRATION_COLUMNS`).
    methods : sequence of str
        The statistics reported.
    region : str
        The region reported.

    Returns
    -------
    table : list of dict
        :data:`CALIBRATION_TABLE_COLUMNS`.
    nulls : list of dict
        :data:`NULL_COLUMNS`.
    """
    rows = [r for r in rows if r["region"] == region and r["method"] in methods]
    for r in rows:
        for k in ("rho", "boot_low", "boot_high", "strength_factor"):
            r[k] = _f(r[k])
        r["replicate"] = int(r["replicate"])
    null_means = matched_nulls(rows)
    per_scene = with_differences(rows, null_means)
    scopes = {"scene": per_scene, "combined": combined_rows(per_scene)}
    for scoped in scopes.values():
        _pair_with_partial(scoped)
    table: list[dict] = []
    margins: dict = {}

    def add(check, rule, scope, transform, method, kind, factor, triple, n, target, meets, note=""):
        table.append(
            {
                "check": check,
                "rule": rule,
                "scope": scope,
                "transform": transform,
                "method": method,
                "kind": kind,
                "strength_factor": factor,
                "value": triple[0],
                "low": triple[1],
                "high": triple[2],
                "n": n,
                "target": target,
                "meets_target": meets,
                "note": note,
            }
        )

    for scope, scoped in scopes.items():
        groups = _group(scoped, ("transform", "method"))
        for (transform, method), group in groups.items():
            by_design = _group(group, ("kind", "strength_factor"))
            # the rules on the nulls: at most 5% false positives, per cue-free design and
            # over all of them (the level a verdict is held to on data of unknown kind)
            cue_free = [k for (k, f) in by_design if k not in ("planted", "renders")]
            pooled = [r for k in cue_free for r in by_design[(k, 0.0)]]
            rules = (RULE_OF[method],) if method in RULE_OF else ("above_zero", "above_null")
            detects = "matching" if method == LIFT_METHOD else "above_null"
            for kind, chosen in [*((k, by_design[(k, 0.0)]) for k in cue_free),
                                 *([(ANY_NULL, pooled)] if len(cue_free) > 1 else [])]:
                for rule in rules:
                    k, n = _count(rule, chosen)
                    if not n:
                        continue
                    r = rate(k, n)
                    note = ""
                    if rule == "above_zero" and method != "partial":
                        note = "a camera's a*mu + b correlates too: not a Monte Carlo test"
                    add("false_positive_rate", rule, scope, transform, method, kind, 0.0, r, n,
                        f"<= {LEVEL:g}", _meets_rate(r), note)
            # power on the planted cue, by strength
            planted = sorted(f for (k, f) in by_design if k == "planted")
            curve = []
            for factor in planted:
                chosen = by_design[("planted", factor)]
                k, n = _count(detects, chosen)
                if not n:
                    continue
                r = rate(k, n)
                curve.append((factor, r[0]))
                add("power", detects, scope, transform, method, "planted", factor, r, n,
                    "", "")
            smallest = detectable(curve)
            margin = math.nan
            if math.isfinite(smallest) and detects == "above_null":
                # the mean Monte Carlo-specific rho at the detectable strength: interpolated
                margin = _interpolated_diff(by_design, smallest)
            replicates = max((len(v) for k, v in by_design.items() if k[0] == "planted"),
                             default=0)
            margins[(scope, transform, method)] = (margin, replicates, smallest)
            if planted:
                add("smallest_detectable", detects, scope, transform, method, "planted",
                    smallest, (smallest, math.nan, math.nan),
                    sum(len(v) for v in by_design.values()), "", "",
                    f"equivalence margin (mean rho minus null there) {margin:.4f}"
                    if math.isfinite(margin) else "" if math.isfinite(smallest)
                    else "no planted strength reaches 80% power")
            # removed: how often the equivalence rule calls a cue removed
            for kind, factor in [("camera", 0.0), *(("planted", f) for f in planted)]:
                chosen = by_design.get((kind, factor), [])
                k, n = _count("removed", chosen, margin)
                if not n or not math.isfinite(margin):
                    continue
                r = rate(k, n)
                wrong = kind == "planted" and factor >= smallest
                add("removed_rate", "removed", scope, transform, method, kind, factor, r, n,
                    f"<= {LEVEL:g}" if wrong else "", _meets_rate(r) if wrong else "",
                    "calls a detectable cue removed" if wrong else "")
            # coverage of the 95% intervals, of the statistic and of its difference, where
            # every replicate of a scene has one estimand (not the misaligned null, whose
            # random offset changes what it estimates)
            for (kind, factor), chosen in sorted(by_design.items()):
                if kind == "misaligned":
                    continue
                for what, cols in (("rho", ("rho", "boot_low", "boot_high")),
                                   ("difference", ("diff", "diff_low", "diff_high"))):
                    k, n = _coverage(chosen, *cols)
                    if not n:
                        continue
                    r = rate(k, n)
                    add("coverage", what, scope, transform, method, kind, factor, r, n,
                        "0.95 +/- 0.02", _meets_coverage(r))
    def margin_of(transform, method):
        """The combined scope's margin when at least :data:`MARGIN_REPLICATES` replicates
        set it, else the pooled scenes' (:func:`margin_scope`)."""
        scope = margin_scope(table, transform, method)
        margin, _, strength = margins.get((scope, transform, method), (math.nan, 0, math.nan))
        return margin, strength if math.isfinite(margin) else math.nan

    nulls = []
    for (scene, transform, region_, method, kind), null in null_means.items():
        if kind != "camera":  # an encoded null of a pipeline, not of the run's frames
            continue
        nulls.append(
            {
                "scene": scene,
                "transform": transform,
                "region": region_,
                "method": method,
                "null_rho": null["mean"],
                "null_se": null["se"],
                "n": null["n"],
                "chance_sd": null["chance_sd"],
                **dict(zip(("margin", "margin_strength"), margin_of(transform, method),
                           strict=True)),
            }
        )
    return table, nulls


def _pair_with_partial(rows: list[dict]) -> None:
    """Give each ``c_sigma_lift`` row ``partial_fires``: whether the verdict rule
    (``partial`` ``above_null``) fires on the same scene (or scenes combined), replicate,
    design and transform, which the ``matching`` rule requires."""
    keys = ("scene", "replicate", "kind", "strength_factor", "transform", "region")
    fired = {tuple(r[k] for k in keys): _fires("above_null", r)
             for r in rows if r["method"] == "partial"}
    for r in rows:
        if r["method"] == LIFT_METHOD:
            r["partial_fires"] = fired.get(tuple(r[k] for k in keys))


def _interpolated_diff(by_design, strength) -> float:
    points = []
    for (kind, factor), group in by_design.items():
        if kind != "planted":
            continue
        d = np.array([_f(r["diff"]) for r in group])
        d = d[np.isfinite(d)]
        if d.size:
            points.append((factor, float(d.mean())))
    if not points:
        return math.nan
    points.sort()
    xs, ys = zip(*points, strict=True)
    return float(np.interp(strength, xs, ys))


def _meets_rate(r) -> str:
    """:func:`meets_level` of a :func:`rate` against :data:`LEVEL`."""
    return meets_level(r[1], r[2])


def _meets_coverage(r) -> str:
    """``yes`` when the coverage's Wilson interval meets 95 +/- 2%, ``no`` when it lies
    outside, ``short`` when it lies below."""
    low, high = COVERAGE_TARGET
    if not math.isfinite(r[1]):
        return ""
    if r[2] < low:
        return "short"
    if r[1] > high:
        return "over"
    return "yes"


def _pick(table, **match) -> list[dict]:
    return [r for r in table if all(r.get(k) == v for k, v in match.items())]


def worst_false_positive(
    table: list[dict], *, scope: str = "scene", transform: str = "none",
    method: str = "partial", rule: str = "above_null", pooled: bool = False,
) -> dict | None:
    """The false-positive row of ``rule`` over the cue-free designs whose Wilson upper bound
    is highest (what "at most" can claim), or ``None``; with ``pooled`` the row of every
    cue-free design together (:data:`ANY_NULL`)."""
    rows = _pick(table, check="false_positive_rate", rule=rule, scope=scope,
                 transform=transform, method=method)
    rows = [r for r in rows if (r["kind"] == ANY_NULL) == pooled]
    rows = [r for r in rows if math.isfinite(_f(r["value"])) and math.isfinite(_f(r["high"]))]
    return max(rows, key=lambda r: (_f(r["high"]), _f(r["value"]))) if rows else None


def _at_most(row) -> str:
    """A rate's Wilson upper bound in percent, rounded up: ``at most 6%``."""
    return f"at most {math.ceil(round(100 * _f(row['high']), 6)):.0f}%"


def _fired(row) -> str:
    """A rate as replicates: ``0 of 64``."""
    n = int(_f(row["n"]))
    return f"{round(_f(row['value']) * n)} of {n}"


def headline(table: list[dict], *, transform: str = "none", method: str = "partial",
             shown=None) -> str:
    """The calibration in a few plain words, for the results and verdict pages: the upper
    end of the 95% Wilson interval of the verdict rule's false-positive rate over every
    cue-free design together (matched nulls and camera pipelines, :data:`ANY_NULL`) with the
    scenes combined, the scope the verdicts use, and per scene; the worst single design; the
    smallest planted strength it detects with 80% power (scenes combined); and, where an
    upper bound is above the 5% level, that the replicates run cannot show it and how many
    would (:func:`replicates_to_show`).

    Examples
    --------
    >>> row = {"check": "false_positive_rate", "rule": "above_null", "transform": "none",
    ...        "method": "partial"}
    >>> table = [
    ...     {**row, "kind": "camera", "scope": "scene", "value": 0.0, "low": 0.0,
    ...      "high": 0.0566, "n": 64},
    ...     {**row, "kind": "camera", "scope": "combined", "value": 0.0, "low": 0.0,
    ...      "high": 0.1936, "n": 16},
    ...     {**row, "kind": ANY_NULL, "scope": "combined", "value": 0.0, "low": 0.0,
    ...      "high": 0.0169, "n": 224},
    ...     {**row, "kind": ANY_NULL, "scope": "scene", "value": 0.0, "low": 0.0,
    ...      "high": 0.0085, "n": 448},
    ...     {"check": "smallest_detectable", "rule": "above_null", "scope": "combined",
    ...      "transform": "none", "method": "partial", "kind": "planted", "value": 0.3,
    ...      "note": "equivalence margin (mean rho minus null there) 0.0200"},
    ... ]
    >>> print(headline(table))  # doctest: +NORMALIZE_WHITESPACE
    On data like yours, this instrument calls a Monte Carlo-specific cue where there is none
    in at most 2% of cue-free frames with the scenes combined (95% confidence; 0 of 224
    replicates of the matched nulls and camera pipelines together; per scene at most 1%, 0
    of 448), and detects one from 0.3x the strength the renders show (80% power;
    intensity-controlled rho 0.0200 above its null). Each design alone: at most 20% (worst,
    camera, 0 of 16 with the scenes combined; 73 replicates with no false positive would
    show 5%).
    """
    pooled = {scope: worst_false_positive(table, scope=scope, transform=transform,
                                          method=method, pooled=True)
              for scope in ("combined", "scene")}
    single = {scope: worst_false_positive(table, scope=scope, transform=transform,
                                          method=method)
              for scope in ("combined", "scene")}
    if single["scene"] is None:
        return "No calibration replicates: the instrument's false-positive rate is not known."
    lead = pooled["combined"] or single["combined"] or single["scene"]
    where = "with the scenes combined" if lead["scope"] == "combined" else "per scene"
    what = ("the matched nulls and camera pipelines together" if lead["kind"] == ANY_NULL
            else f"worst design, {lead['kind']}")
    text = (
        "On data like yours, this instrument calls a Monte Carlo-specific cue where there is "
        f"none in {_at_most(lead)} of cue-free frames {where} (95% confidence; "
        f"{_fired(lead)} replicates of {what}"
    )
    second = pooled["scene"] if lead["kind"] == ANY_NULL else None
    if second is not None:
        text += f"; per scene {_at_most(second)}, {_fired(second)}"
    text += "), and "
    smallest = _pick(table, check="smallest_detectable", scope="combined",
                     transform=transform, method=method)
    value = _f(smallest[0]["value"]) if smallest else math.nan
    if not math.isfinite(value):
        text += "detects no planted cue with 80% power up to the strongest planted."
    else:
        margin = smallest[0].get("note", "").rsplit(" ", 1)[-1]
        text += (
            f"detects one from {value:.2g}x the strength the renders show (80% power; "
            f"intensity-controlled rho {margin} above its null)."
        )
    state = meets_level(lead["low"], lead["high"])
    if state == "no":
        low = math.floor(round(100 * _f(lead["low"]), 6))
        text += f" The rate is above the {100 * LEVEL:g}% level (at least {low:.0f}%)."
    elif state == NOT_SHOWN:
        text += (
            f" {int(_f(lead['n']))} replicates cannot show the {100 * LEVEL:g}% level: "
            f"{replicates_to_show()} with no false positive would."
        )
    worst = single["combined"] or single["scene"]
    if lead["kind"] == ANY_NULL and worst is not None:
        scope = "with the scenes combined" if worst["scope"] == "combined" else "per scene"
        text += (
            f" Each design alone: {_at_most(worst)} (worst, {worst['kind']}, {_fired(worst)} "
            f"{scope}"
        )
        if meets_level(worst["low"], worst["high"]) == NOT_SHOWN:
            text += f"; {replicates_to_show()} replicates with no false positive would show 5%"
        text += ")."
    coverage = coverage_sentence(table, transform=transform, shown=shown)
    return text + (f" {coverage}" if coverage else "")


COVERAGE_SHOWN = (
    ("warp", "rho", "Pearson rho after the warp"),
    ("partial", "rho", "intensity-controlled rho"),
    ("partial", "difference", "Monte Carlo-specific rho"),
    ("spearman", "rho", "Spearman rho"),
)
"""The 95% intervals the results page shows, as (statistic, what, label) of the coverage
checks."""

VERDICT_COVERAGE_SHOWN = (
    *COVERAGE_SHOWN,
    (LIFT_METHOD, "difference", "C_sigma lift beyond its matched null"),
)
"""The 95% intervals an audit's verdict page shows: the results page's and the matching-cue
rule's."""


def coverage_sentence(table: list[dict], *, transform: str = "none", shown=None) -> str:
    """The measured coverage of each 95% interval a page shows (``shown``:
    :data:`COVERAGE_SHOWN`, or :data:`VERDICT_COVERAGE_SHOWN` for a verdict page),
    per scene over the camera null and the planted cue at each strength (designs with one
    estimand and every replicate; the pipeline nulls' few replicates set their false-positive
    rates, not a coverage), as the range of the point estimates; an interval whose range
    leaves 93-97% is so labelled rather than taken at its word.

    Examples
    --------
    Coverage is labelled by its 95% Wilson interval: here the second misses 93-97%.

    >>> row = {"check": "coverage", "scope": "scene", "transform": "none",
    ...        "method": "warp", "rule": "rho"}
    >>> table = [{**row, "kind": "camera", "value": 0.95, "low": 0.87, "high": 0.98},
    ...          {**row, "kind": "planted", "value": 0.66, "low": 0.53, "high": 0.76}]
    >>> print(coverage_sentence(table))  # doctest: +NORMALIZE_WHITESPACE
    Measured coverage of the 95% intervals shown (target 93-97%): Pearson rho after the
    warp 66-95% (too narrow at some designs).
    """
    parts = []
    for method, what, label in shown or COVERAGE_SHOWN:
        rows = [r for r in _pick(table, check="coverage", scope="scene", transform=transform,
                                 method=method, rule=what)
                if r["kind"] in ("camera", "planted") and math.isfinite(_f(r["value"]))]
        if not rows:
            continue
        values = [_f(r["value"]) for r in rows]
        low, high = 100 * min(values), 100 * max(values)
        text = f"{label} {low:.0f}-{high:.0f}%" if round(low) != round(high) else (
            f"{label} {low:.0f}%")
        states = {_meets_coverage((_f(r["value"]), _f(r["low"]), _f(r["high"]))) for r in rows}
        notes = []
        if "short" in states:
            notes.append("too narrow at some designs")
        if "over" in states:
            notes.append("wider than 95% at some designs")
        parts.append(text + (f" ({'; '.join(notes)})" if notes else ""))
    if not parts:
        return ""
    return ("Measured coverage of the 95% intervals shown (target 93-97%): "
            + ", ".join(parts) + ".")


COMPACT_COLUMNS = [
    "transform",
    "method",
    "false positives above its null, every cue-free design, scenes combined",
    "false positives above its null, per scene",
    "false positives above its null, scenes combined",
    "false positives above 0, per scene",
    "smallest detectable (x the renders)",
    "equivalence margin",
    "coverage of rho (lowest)",
    "coverage of the difference (lowest)",
    "replicates per scene",
]
"""Columns of ``results/tables/calibration.md``: one row per transform and statistic (the
CSV beside it has every check, scope and design). The first rate pools every cue-free
design (the matched nulls and the camera pipelines, :data:`ANY_NULL`), the level a verdict
is held to; the others are the worst single design. Each is read by the upper end of its
95% Wilson interval: ``at most 6% (0 of 64; not shown)``, with the replicates that fired
and, unless the interval shows the 5% level, ``not shown`` (it straddles the level) or
``no`` (it lies above); the rule ``above 0`` is the audit's former Monte Carlo rule;
``shared_streams`` and ``c_sigma_lift`` are read by their own rules (:data:`RULE_OF`);
coverage is the lowest over the designs, pooled over scenes."""

RULE_OF = {"shared_streams": "shared", LIFT_METHOD: "matching"}
"""The rule each check of the audit's light is held to; every other statistic's is
``above_null``."""


def false_positive_text(row) -> str:
    """A rate held to :data:`LEVEL` as what it shows: the upper end of its 95% Wilson
    interval, the replicates that fired and, unless it is ``yes``, its :func:`meets_level`
    word.

    Examples
    --------
    >>> value, low, high = rate(0, 64)
    >>> false_positive_text({"value": value, "low": low, "high": high, "n": 64})
    'at most 6% (0 of 64; not shown)'
    """
    meets = row.get("meets_target") or meets_level(row["low"], row["high"])
    return f"{_at_most(row)} ({_fired(row)}" + ("" if meets == "yes" else f"; {meets}") + ")"


def _percent(row) -> str:
    """A rate's cell: a rate held to :data:`LEVEL` by its upper bound
    (:func:`false_positive_text`), a coverage by its value and interval with its
    ``meets_target`` word when it is not ``yes``."""
    if not row or not math.isfinite(_f(row["value"])):
        return "n/a"
    if str(row.get("target", "")).startswith("<=") and math.isfinite(_f(row["high"])):
        return false_positive_text(row)
    value, low, high = (100 * _f(row[k]) for k in ("value", "low", "high"))
    text = f"{value:.0f}% [{low:.0f}, {high:.0f}]"
    return text + ("" if row.get("meets_target") in ("yes", "") else f" ({row['meets_target']})")


def _worst(rows, check, rule, pick_max=True, **match):
    chosen = [
        r for r in _pick(rows, check=check, rule=rule, **match) if math.isfinite(_f(r["value"]))
    ]
    if not chosen:
        return None
    return (max if pick_max else min)(chosen, key=lambda r: _f(r["value"]))


def margin_scope(table: list[dict], transform: str, method: str) -> str:
    """The scope whose power curve sets a transform's equivalence margin, as
    :func:`calibration_table` chooses it for the verdicts: ``combined`` when at least
    :data:`MARGIN_REPLICATES` replicates of the scenes combined reach each planted strength,
    else ``scene`` (the scenes' replicates pooled), so that every page quotes the margin the
    verdict uses."""
    power = _pick(table, check="power", scope="combined", transform=transform, method=method)
    n = max((int(_f(r["n"])) for r in power), default=0)
    return "combined" if n >= MARGIN_REPLICATES else "scene"


def compact_table(table: list[dict]) -> list[dict]:
    """:data:`COMPACT_COLUMNS` rows of the calibration table: per transform and statistic
    the worst false-positive rate of each rule (per scene, and for the verdict rule also with
    the scenes combined), the smallest detectable strength with its margin (scenes
    combined), and the lowest coverage over the designs (per scene): a false-positive rate
    by the upper end of its 95% Wilson interval (the worst over the matched nulls,
    :func:`worst_false_positive`), a coverage with its interval, each with whether it meets
    its target (:func:`meets_level`)."""
    out = []
    keys = list(dict.fromkeys((r["transform"], r["method"]) for r in table))
    for transform, method in keys:
        scene = _pick(table, scope="scene", transform=transform, method=method)
        smallest = _pick(table, check="smallest_detectable", transform=transform,
                         method=method, scope=margin_scope(table, transform, method))
        value = _f(smallest[0]["value"]) if smallest else math.nan
        note = smallest[0].get("note", "") if smallest else ""
        n = max(
            (int(_f(r["n"])) for r in scene
             if r["check"] == "false_positive_rate" and r["kind"] != ANY_NULL), default=0
        )
        rule = RULE_OF.get(method, "above_null")
        out.append(
            {
                "transform": transform,
                "method": method,
                "false positives above its null, every cue-free design, scenes combined":
                _percent(worst_false_positive(table, scope="combined", transform=transform,
                                              method=method, rule=rule, pooled=True)),
                "false positives above its null, per scene": _percent(
                    worst_false_positive(table, scope="scene", transform=transform,
                                         method=method, rule=rule)
                ),
                "false positives above its null, scenes combined": _percent(
                    worst_false_positive(table, scope="combined", transform=transform,
                                         method=method, rule=rule)
                ),
                "false positives above 0, per scene": _percent(
                    worst_false_positive(table, scope="scene", transform=transform,
                                         method=method, rule="above_zero")
                )
                if method == "partial"
                else "n/a" if method in RULE_OF
                else "not a Monte Carlo test (a camera correlates too)",
                "smallest detectable (x the renders)": f"{value:.3g}"
                if math.isfinite(value)
                else "none up to the strongest",
                "equivalence margin": note.rsplit(" ", 1)[-1] if math.isfinite(value) and note
                else "n/a",
                "coverage of rho (lowest)": _percent(
                    _worst(scene, "coverage", "rho", pick_max=False)
                ),
                "coverage of the difference (lowest)": _percent(
                    _worst(scene, "coverage", "difference", pick_max=False)
                ),
                "replicates per scene": n,
            }
        )
    return out
