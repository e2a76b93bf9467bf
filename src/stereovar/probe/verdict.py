"""The probe's verdict, per architecture: does the trained network use the Monte Carlo cue,
what could the probe have detected, and which mitigation removes the reliance.

The network trained on the renders as they are (``none``) **uses the cue** when the
difference in differences of the residual shuffle against its cue-blind twin has a 95 %
interval above 0 (:mod:`stereovar.probe.metrics`):

.. math::

    \\mathrm{DiD} = (A_{\\mathrm{normal}} - A_{\\mathrm{shuffled}})_{\\mathrm{none}}
        - (A_{\\mathrm{normal}} - A_{\\mathrm{shuffled}})_{\\mathrm{twin}} > 0.

**Power.** The smallest DiD the probe detects at this budget (two-sided 95 %, power 80 %) is

.. math::

    \\mathrm{MDE} = \\bigl(t_{0.975,\\nu} + t_{0.80,\\nu}\\bigr)
        \\,\\mathrm{SE}(\\mathrm{DiD}_{\\mathrm{none}}),

and where ``none`` is not detected the verdict says "not detectable below" the MDE. The
planted series ``planted_x{f}`` (a cross-view variance cue planted at f times the renders'
strength) gives the power curve: the DiD of each factor with its interval, detected or not.

**Mitigations**, compared with ``none`` (DESIGN.md, Calibration: "removed" needs an
equivalence margin): a mitigation :math:`m` **removes** the reliance when
:math:`\\mathrm{DiD}_m - \\mathrm{DiD}_{none}` has its 95 % interval below 0 (independent
networks and renders: the variances add, Welch–Satterthwaite degrees of freedom) and
:math:`\\mathrm{DiD}_m` is equivalent to 0 within :math:`\\pm\\mathrm{MDE}` (two one-sided
tests: its 90 % interval inside the margin); it **still uses** the cue when its DiD interval
is above 0 and the reduction is not shown; otherwise the answer is **not determined**. A
mitigation that builds every image of a scene from its one seed mean (``sensor_only``,
``equalise``) is **not testable**: the Monte Carlo noise left in that mean is in every image
and in the counterfactuals' reference mean, so the shuffle reaches only the noise added per
image and the DiD is 0 by construction. The ``sensor_only`` network is a second control
(``did_sensor``).

Importing this module pulls in numpy and scipy (t quantiles).
"""

from __future__ import annotations

import math

from ..layout import NONE
from .conditions import SHIPPED_GROUP, shipped_mitigation, shipped_name, ships_one_seed_mean
from .metrics import CONTROL, INTERVAL_METHOD, PRIMARY_ARCHITECTURE, planted_factor, t_quantile

__all__ = ["mitigation_status", "probe_verdict"]

NOT_TESTABLE = "not testable"
"""The status of a mitigation whose images share one seed mean (:data:`SEED_MEAN_REASON`)."""

SEED_MEAN_REASON = (
    "every image of a scene is built from its one seed mean, whose Monte Carlo noise is also "
    "in the counterfactuals' reference mean: the residual shuffle reaches only the noise "
    "added per image, so its DiD is 0 by construction and says nothing about the cue left "
    "in the seed mean"
)
"""Why such a mitigation's DiD does not test it
(:func:`~stereovar.probe.conditions.ships_one_seed_mean`)."""

SHIPPED_NOTE = (
    f"trained on what it ships, one image per {SHIPPED_GROUP} seeds from each group's own "
    f"seed mean: its seed means keep sigma^2/{SHIPPED_GROUP} of Monte Carlo noise, N/"
    f"{SHIPPED_GROUP} times an image of all N seeds, so 'removes' holds a fortiori at N and "
    "'still uses' is an upper bound"
)
"""How a seed-mean mitigation is judged
(:func:`~stereovar.probe.conditions.shipped_name`), on the page beside its status."""

TWIN_CONTROL = "cue-blind twin"
"""The primary control: the same renders with the right residual drawn again each step."""


def _fmt(value, low, high, digits: int = 3) -> str:
    if value is None or not math.isfinite(float(value)):
        return "n/a"
    return f"{value:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]"


def _finite(*values) -> bool:
    return all(v is not None and math.isfinite(float(v)) for v in values)


def _find(rows, architecture, tested, test_input, region):
    for r in rows:
        if (r["architecture"], r["tested"], r["test_input"], r["region"]) == (
            architecture, tested, test_input, region
        ):
            return r
    return None


def _above(row, key) -> bool:
    return row is not None and _finite(row[f"{key}_low"]) and row[f"{key}_low"] > 0


def mitigation_status(mitigation: dict, none: dict, mde: float) -> dict:
    """A mitigation's DiD compared with ``none``'s (module text).

    Parameters
    ----------
    mitigation, none : dict
        Rows of :func:`stereovar.probe.metrics.probe_rows` (``did``, ``did_low``,
        ``did_high``, ``did_se``, ``did_df``) of the shuffled input.
    mde : float
        The equivalence margin, ``none``'s smallest detectable DiD.

    Returns
    -------
    dict
        ``difference`` [``_low``, ``_high``] (95 %), ``equivalence_low``/``_high`` (the
        mitigation's 90 % interval), ``reduced``, ``equivalent`` and ``status``:
        ``"removes"``, ``"still uses"`` or ``"not determined"``.

    Examples
    --------
    >>> none = {"did": 0.05, "did_low": 0.03, "did_high": 0.07, "did_se": 0.01, "did_df": 1e6}
    >>> m = {"did": 0.0, "did_low": -0.02, "did_high": 0.02, "did_se": 0.01, "did_df": 1e6}
    >>> mitigation_status(m, none, mde=0.028)["status"]
    'removes'
    >>> mitigation_status(m, none, mde=0.01)["status"]  # too noisy to show equivalence
    'not determined'
    """
    a, b = mitigation["did_se"] ** 2, none["did_se"] ** 2
    diff = mitigation["did"] - none["did"]
    out = {"difference": diff, "difference_low": math.nan, "difference_high": math.nan,
           "equivalence_low": math.nan, "equivalence_high": math.nan,
           "reduced": False, "equivalent": False}
    if _finite(a, b, mitigation["did_df"], none["did_df"]) and a + b > 0:
        df = (a + b) ** 2 / (
            (a * a / mitigation["did_df"] if a else 0.0) + (b * b / none["did_df"] if b else 0.0)
        )
        half = float(t_quantile(0.975, df)) * math.sqrt(a + b)
        out.update(difference_low=diff - half, difference_high=diff + half)
        out["reduced"] = bool(diff + half < 0)
        half90 = float(t_quantile(0.95, mitigation["did_df"])) * math.sqrt(a)
        low, high = mitigation["did"] - half90, mitigation["did"] + half90
        out.update(equivalence_low=low, equivalence_high=high)
        out["equivalent"] = bool(_finite(mde) and -mde < low and high < mde)
    if out["reduced"] and out["equivalent"]:
        status = "removes"
    elif _above(mitigation, "did") and not out["reduced"]:
        status = "still uses"
    else:
        status = "not determined"
    out["status"] = status
    return out


def _power_curve(rows, architecture, region) -> list[dict]:
    curve = []
    for r in rows:
        if (r["architecture"], r["test_input"], r["region"]) != (architecture, "shuffled",
                                                                 region):
            continue
        factor = planted_factor(r["tested"])
        if not math.isfinite(factor):
            continue
        curve.append({
            "condition": r["tested"], "factor": factor, "strength": r.get("strength"),
            "did": r["did"], "did_low": r["did_low"], "did_high": r["did_high"],
            "detected": _above(r, "did"),
        })
    return sorted(curve, key=lambda p: p["factor"])


def _detected_from(curve) -> float | None:
    """The smallest positive factor from which every larger factor is detected."""
    found = None
    for point in reversed(curve):
        if point["factor"] <= 0 or not point["detected"]:
            break
        found = point["factor"]
    return found


def _architecture_verdict(rows, architecture, region, control) -> dict:
    shuffle = _find(rows, architecture, NONE, "shuffled", region)
    normal = _find(rows, architecture, NONE, "normal", region)
    conflict = _find(rows, architecture, NONE, "conflict", region)
    out: dict = {"architecture": architecture, "region": region}
    if shuffle is None or normal is None:
        out.update(
            uses_cue=None, mitigations=[], power=[],
            paragraph=f"{architecture}: the probe table has no row of the renders as they are "
            "(training 'none', shuffled input); no verdict.",
        )
        return out
    uses = _above(shuffle, "did")
    accuracy = normal["accuracy"]
    mde = shuffle["did_mde"]
    out.update(
        uses_cue=uses,
        did=shuffle["did"], did_low=shuffle["did_low"], did_high=shuffle["did_high"],
        did_se=shuffle["did_se"], did_df=shuffle["did_df"],
        mde=mde,
        accuracy=accuracy,
        fraction=shuffle["did"] / accuracy if accuracy else math.nan,
        did_sensor=shuffle["did_sensor"], did_sensor_low=shuffle["did_sensor_low"],
        did_sensor_high=shuffle["did_sensor_high"],
        uses_cue_vs_sensor=_above(shuffle, "did_sensor"),
        train_seeds=shuffle["train_seeds"],
    )
    if conflict is not None:
        out.update(
            pulled_vs_twin=conflict["pulled_vs_twin"],
            pulled_vs_twin_low=conflict["pulled_vs_twin_low"],
            pulled_vs_twin_high=conflict["pulled_vs_twin_high"],
        )
    did_text = _fmt(shuffle["did"], shuffle["did_low"], shuffle["did_high"])
    mde_text = f"{mde:.3f}" if _finite(mde) else "n/a"
    name = f"{architecture} ({shuffle['train_seeds']} training seeds, {region} pixels)"
    if uses:
        parts = [
            f"{name}: the network trained on the renders uses the Monte Carlo cue. The "
            f"residual shuffle costs it {did_text} more accuracy than its {TWIN_CONTROL} on "
            f"the same inputs, {100 * out['fraction']:.1f}% of its {100 * accuracy:.1f}% "
            f"accuracy (smallest detectable DiD at this budget {mde_text})."
        ]
    else:
        parts = [
            f"{name}: no reliance on the Monte Carlo cue is detected. The residual shuffle "
            f"costs the network {did_text} accuracy beyond its {TWIN_CONTROL} (interval not "
            f"above 0); at this budget the probe detects a DiD of {mde_text} with 80% power, "
            f"so a reliance is not detectable below {mde_text}."
        ]
        out["not_detectable_below"] = mde
    parts.append(
        f"Against the {control} network as a second control the DiD is "
        + _fmt(shuffle["did_sensor"], shuffle["did_sensor_low"], shuffle["did_sensor_high"])
        + "."
    )
    if conflict is not None and _finite(conflict["pulled_vs_twin"]):
        parts.append(
            "Under the cue conflict it puts "
            + _fmt(conflict["pulled_vs_twin"], conflict["pulled_vs_twin_low"],
                   conflict["pulled_vs_twin_high"])
            + f" of the pixels at d + k beyond its {TWIN_CONTROL}."
        )
    curve = _power_curve(rows, architecture, region)
    out["power"] = curve
    if curve:
        start = _detected_from(curve)
        out["detected_from_factor"] = start
        at_one = next((p for p in curve if p["factor"] == 1), None)
        out["renders_strength_detected"] = at_one["detected"] if at_one else None
        points = "; ".join(
            f"x{p['factor']:g} {_fmt(p['did'], p['did_low'], p['did_high'])}"
            + (" detected" if p["detected"] else "")
            for p in curve
        )
        said = (
            f"detected from x{start:g} of the renders' strength up"
            if start is not None
            else f"not detected up to x{curve[-1]['factor']:g} of the renders' strength"
        )
        parts.append(f"Planted cue (DiD per strength factor): {points}; {said}.")
    mitigations = []
    conditions = list(dict.fromkeys(r["tested"] for r in rows
                                    if r["architecture"] == architecture))
    for tested in conditions:
        if tested == NONE or math.isfinite(planted_factor(tested)):
            continue
        if shipped_name(tested) in conditions:
            continue  # judged on what it ships (its shipped condition's row)
        row = _find(rows, architecture, tested, "shuffled", region)
        if row is None or (tested == control and not _finite(row["did"])):
            continue  # the control without a twin (probe.mitigations does not judge it)
        cmp = mitigation_status(row, shuffle, mde)
        mitigation = shipped_mitigation(tested) or tested
        if shipped_mitigation(tested):
            cmp.update(note=SHIPPED_NOTE)
        elif ships_one_seed_mean(tested):
            cmp.update(status=NOT_TESTABLE, reason=SEED_MEAN_REASON)
        mitigations.append({
            "condition": tested, "mitigation": mitigation, "did": row["did"],
            "did_low": row["did_low"], "did_high": row["did_high"],
            "uses_cue": _above(row, "did"), "removes": cmp["status"] == "removes", **cmp,
        })
    out["mitigations"] = mitigations
    if mitigations:
        parts.append(
            "Mitigations, DiD and its difference from none's (equivalence margin "
            f"+/-{mde_text}): "
            + "; ".join(
                f"{m['condition']} {_fmt(m['did'], m['did_low'], m['did_high'])}, "
                f"{_fmt(m['difference'], m['difference_low'], m['difference_high'])}: "
                f"{m['status']}"
                + (f" ({m['reason'] if m.get('reason') else m['note']})"
                   if m.get("reason") or m.get("note") else "")
                for m in mitigations
            )
            + "."
        )
    out["paragraph"] = " ".join(parts)
    return out


def probe_verdict(
    rows: list[dict], *, control: str = CONTROL, primary: str = PRIMARY_ARCHITECTURE
) -> dict:
    """The verdict, a paragraph and a claims-style row from the probe table's rows.

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.probe.metrics.probe_rows`.
    control : str, keyword-only
        The second control condition.
    primary : str, keyword-only
        The architecture the top-level keys and the claim describe (else the first).

    Returns
    -------
    dict
        ``architectures`` (one verdict per architecture: ``uses_cue``, ``did`` [...],
        ``mde``, ``not_detectable_below`` where no reliance is detected, ``did_sensor``
        [...], ``pulled_vs_twin`` [...], ``power`` (the planted series), ``detected_from_factor``,
        ``renders_strength_detected``, ``mitigations`` (``status``: removes, still uses, not
        determined, or not testable with its ``reason``), ``paragraph``); the primary
        architecture's keys at the top level; ``region``, ``control``, ``second_control``,
        ``interval``, ``paragraph`` (every architecture's) and ``claim``.

    Examples
    --------
    >>> def row(tested, t, did, low, high):
    ...     return {"architecture": "mccnn", "tested": tested, "test_input": t,
    ...             "region": "all", "accuracy": 0.8, "did": did, "did_low": low,
    ...             "did_high": high, "did_se": 0.015, "did_df": 20.0, "did_mde": 0.043,
    ...             "did_sensor": did, "did_sensor_low": low, "did_sensor_high": high,
    ...             "train_seeds": 10}
    >>> v = probe_verdict([row("none", "shuffled", 0.08, 0.05, 0.11),
    ...                    row("none", "normal", 0.0, 0.0, 0.0)])
    >>> v["uses_cue"], round(v["fraction"], 2), v["primary"]
    (True, 0.1, 'mccnn')
    """
    regions = {r["region"] for r in rows}
    region = "non_glass" if "non_glass" in regions else "all"
    architectures = list(dict.fromkeys(r["architecture"] for r in rows))
    first = primary if primary in architectures else (architectures[0] if architectures
                                                      else primary)
    verdicts = {a: _architecture_verdict(rows, a, region, control) for a in architectures}
    main = verdicts.get(first) or {"uses_cue": None, "mitigations": [], "power": [],
                                   "paragraph": "The probe table is empty; no verdict."}
    out: dict = {k: v for k, v in main.items() if k not in ("architecture", "paragraph")}
    out.update(
        primary=first,
        region=region,
        control=TWIN_CONTROL,
        second_control=control,
        interval=INTERVAL_METHOD,
        architectures=verdicts,
        paragraph=" ".join(
            [main["paragraph"]]
            + [v["paragraph"] for a, v in verdicts.items() if a != first]
            + [f"Intervals: {INTERVAL_METHOD}."]
        ),
    )
    uses = main["uses_cue"]
    claim = {"claim": "a trained matcher uses the cue",
             "answer": "n/a" if uses is None else ("yes" if uses else "no")}
    if uses is not None:
        claim.update(
            value=main["did"], low=main["did_low"], high=main["did_high"],
            mde=main["mde"],
            control=f"difference in differences of the shuffle against the {TWIN_CONTROL}",
        )
    out["claim"] = claim
    return out
