"""The claims table's level rule on the calibration's designs.

The claims table (:mod:`stereovar.statistics.claims`) says a level claim on :math:`\\rho`
*holds* when the paper's value lies in our interval, the interval excludes 0, and the
bearing camera baseline does not account for ours. A claim that holds reads as "these
renders show the paper's cross-view correlation, beyond what a camera gives", so on frames
with no Monte Carlo cue it is a false positive. Here each such claim (kind ``level`` on
``rho`` over region ``all`` against the ``sensor_sim`` baseline, as the paper's ``rho_all``)
is decided on every replicate exactly as the table decides it on a run: over the scenes of
the replicate, the mean :math:`\\rho` with its random-effects interval on Fisher's :math:`z`
(:func:`stereovar.statistics.across.random_effects_correlation_interval`), for the statistic
and for the control, and :func:`stereovar.statistics.claim_rules.verdict`.
"""

from __future__ import annotations

import math
from collections import defaultdict

from .stacks import NONE
from .view_statistics import CLAIM_CONTROL

CUE_FREE_EXCLUDED = ("planted", "renders")
"""Design kinds that are not cue-free."""


def calibrated_claims(claims) -> list[dict]:
    """The claims whose rule the calibration can decide on its replicates: level claims on
    ``rho`` over ``all`` read against the ``sensor_sim`` baseline, not by equivalence."""
    out = []
    for c in claims.claims:
        statistic, control = c["statistic"], c.get("control") or {}
        theirs = control.get("statistic") or {}
        if (c["kind"] == "level" and statistic["name"] == "rho"
                and statistic.get("region") == "all"
                and theirs.get("name") == "rho" and theirs.get("region") == "all"
                and theirs.get("method") == CLAIM_CONTROL
                and "equivalence_margin" not in c["rule"]):
            out.append(c)
    return out


def claim_verdicts(rows: list[dict], claim: dict) -> dict:
    """Per design ``(kind, strength_factor)``, the claim's verdict on each replicate
    (transform ``none``, region ``all``; replicates with fewer than 2 scenes are left out:
    the interval over scenes needs 2).

    Returns
    -------
    dict
        ``(kind, strength_factor)`` to a list of verdict strings.
    """
    from ..statistics.across import random_effects_correlation_interval
    from ..statistics.claim_rules import verdict

    ours_method = claim["statistic"]["method"]
    values: dict = defaultdict(lambda: defaultdict(dict))
    for r in rows:
        if r["transform"] != NONE or r["region"] != "all":
            continue
        if r["method"] not in (ours_method, CLAIM_CONTROL):
            continue
        key = (r["kind"], float(r["strength_factor"]), int(r["replicate"]))
        values[key][r["method"]][r["scene"]] = float(r["rho"])
    rule = claim["rule"]
    out: dict = defaultdict(list)
    for (kind, factor, _), by_method in sorted(values.items()):
        scenes = [s for s in by_method.get(ours_method, {})
                  if s in by_method.get(CLAIM_CONTROL, {})
                  and math.isfinite(by_method[ours_method][s])
                  and math.isfinite(by_method[CLAIM_CONTROL][s])]
        if len(scenes) < 2:
            continue
        ours = random_effects_correlation_interval([by_method[ours_method][s] for s in scenes])
        control = random_effects_correlation_interval(
            [by_method[CLAIM_CONTROL][s] for s in scenes])
        out[(kind, factor)].append(verdict(
            "level", claim["paper"], *ours, control,
            control_explains=rule.get("control_explains", True),
            null_value=rule.get("null_value"), control_share=rule.get("control_share")))
    return out


def claim_checks(rows: list[dict], claims=None) -> list[dict]:
    """Calibration-table rows of every calibrated claim: how often it *holds* on each
    cue-free design and on all of them together (its false-positive rate, held to 5%), and on
    the planted cue at each strength.

    The rows have :data:`~stereovar.calibration.summary.CALIBRATION_TABLE_COLUMNS`, with rule
    ``claim <id> holds``, scope ``combined`` and method the claim's statistic.

    Parameters
    ----------
    rows : list of dict
        Every scene's replicate rows.
    claims : stereovar.statistics.claims.Claims, optional
        The claims file (default: the paper's).
    """
    from ..statistics.claim_rules import HOLDS
    from ..statistics.claims import load_claims
    from .rates import LEVEL, meets_level, rate
    from .summary import ANY_NULL

    claims = claims or load_claims()
    out = []
    for claim in calibrated_claims(claims):
        verdicts = claim_verdicts(rows, claim)
        cue_free = {k: v for k, v in verdicts.items() if k[0] not in CUE_FREE_EXCLUDED}
        pooled = [v for vs in cue_free.values() for v in vs]
        designs = [*((k, vs) for k, vs in sorted(cue_free.items())),
                   *([((ANY_NULL, 0.0), pooled)] if len(cue_free) > 1 else []),
                   *((k, vs) for k, vs in sorted(verdicts.items()) if k[0] == "planted")]
        for (kind, factor), found in designs:
            if not found:
                continue
            held = sum(v == HOLDS for v in found)
            r = rate(held, len(found))
            wrong = kind != "planted"
            out.append({
                "check": "false_positive_rate" if wrong else "power",
                "rule": f"claim {claim['id']} holds",
                "scope": "combined",
                "transform": NONE,
                "method": claim["statistic"]["method"],
                "kind": kind,
                "strength_factor": factor,
                "value": r[0], "low": r[1], "high": r[2], "n": len(found),
                "target": f"<= {LEVEL:g}" if wrong else "",
                "meets_target": meets_level(r[1], r[2]) if wrong else "",
                "note": "; ".join(f"{v} {found.count(v)}" for v in sorted(set(found))),
            })
    return out
