"""The probe's verdict: does the trained matcher use the Monte Carlo cue, how strongly, and
which mitigation removes that reliance.

The matcher trained on the renders as they are (``none``) **uses the cue** when the
difference in differences of the residual shuffle against the control network has a 95 %
interval above 0 (:mod:`stereovar.probe.metrics`):

.. math::

    \\mathrm{DiD} = (A_{\\mathrm{normal}} - A_{\\mathrm{shuffled}})_{\\mathrm{none}}
        - (A_{\\mathrm{normal}} - A_{\\mathrm{shuffled}})_{\\mathrm{sensor\\_only}} > 0,

and its strength is :math:`\\mathrm{DiD} / A_{\\mathrm{normal}}`, the share of its accuracy
that the cue carries. A mitigation **removes** the reliance when its own DiD interval is not
above 0. The cue conflict is reported beside it: the share of pixels the network puts at
:math:`d + k`, above the control's.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import math

from ..layout import NONE
from .metrics import CONTROL, INTERVAL_METHOD

__all__ = ["probe_verdict"]


def _fmt(value, low, high, digits: int = 3) -> str:
    if value is None or not math.isfinite(float(value)):
        return "n/a"
    return f"{value:+.{digits}f} [{low:+.{digits}f}, {high:+.{digits}f}]"


def _find(rows, training, test_input, region):
    for r in rows:
        if (r["training"], r["test_input"], r["region"]) == (training, test_input, region):
            return r
    return None


def _above(row, key) -> bool:
    return row is not None and math.isfinite(row[f"{key}_low"]) and row[f"{key}_low"] > 0


def probe_verdict(rows: list[dict], *, control: str = CONTROL) -> dict:
    """The verdict, a paragraph and a claims-style row from the probe table's rows.

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.probe.metrics.probe_rows`.
    control : str, keyword-only

    Returns
    -------
    dict
        ``uses_cue`` (bool, or None without a ``none`` shuffle row), ``region``, ``did``,
        ``did_low``, ``did_high``, ``fraction`` (DiD over the normal accuracy), ``accuracy``,
        ``pulled_vs_control`` [...], ``mitigations`` (one entry per other training condition:
        ``condition``, ``did`` [...], ``uses_cue``, ``removes``), ``paragraph``, ``claim``
        and ``interval``.

    Examples
    --------
    >>> row = lambda t, i, v, lo, hi: {"training": t, "test_input": i, "region": "all",
    ...     "accuracy": 0.8, "did": v, "did_low": lo, "did_high": hi,
    ...     "pulled_vs_control": 0.0, "pulled_vs_control_low": 0.0, "pulled_vs_control_high": 0.0}
    >>> v = probe_verdict([row("none", "shuffled", 0.08, 0.05, 0.11),
    ...                    row("none", "normal", 0.0, 0.0, 0.0)])
    >>> v["uses_cue"], round(v["fraction"], 2)
    (True, 0.1)
    """
    regions = {r["region"] for r in rows}
    region = "non_glass" if "non_glass" in regions else "all"
    shuffle = _find(rows, NONE, "shuffled", region)
    normal = _find(rows, NONE, "normal", region)
    conflict = _find(rows, NONE, "conflict", region)
    out: dict = {"region": region, "interval": INTERVAL_METHOD, "control": control}
    if shuffle is None or normal is None:
        out.update(uses_cue=None, paragraph="The probe table has no row of the renders as they "
                   "are (training 'none', shuffled input); no verdict.", mitigations=[])
        out["claim"] = {"claim": "a trained matcher uses the cue", "answer": "n/a"}
        return out
    uses = _above(shuffle, "did")
    fraction = shuffle["did"] / normal["accuracy"] if normal["accuracy"] else math.nan
    out.update(
        uses_cue=uses,
        did=shuffle["did"],
        did_low=shuffle["did_low"],
        did_high=shuffle["did_high"],
        accuracy=normal["accuracy"],
        fraction=fraction,
    )
    if conflict is not None:
        out.update(
            pulled_vs_control=conflict["pulled_vs_control"],
            pulled_vs_control_low=conflict["pulled_vs_control_low"],
            pulled_vs_control_high=conflict["pulled_vs_control_high"],
        )
    did_text = _fmt(shuffle["did"], shuffle["did_low"], shuffle["did_high"])
    if uses:
        head = (
            f"The trained matcher uses the Monte Carlo cue: on the {region} pixels the residual "
            f"shuffle costs it {did_text} more accuracy than it costs the {control} control "
            f"network on the same inputs, {100 * fraction:.1f}% of its "
            f"{100 * normal['accuracy']:.1f}% accuracy."
        )
    else:
        head = (
            f"The trained matcher does not measurably use the Monte Carlo cue: on the {region} "
            f"pixels the residual shuffle costs it {did_text} accuracy beyond what it costs the "
            f"{control} control network on the same inputs (difference in differences; the "
            "interval is not above 0)."
        )
    parts = [head]
    if conflict is not None:
        parts.append(
            "Under the cue conflict it puts "
            + _fmt(
                conflict["pulled_vs_control"],
                conflict["pulled_vs_control_low"],
                conflict["pulled_vs_control_high"],
            )
            + " of the pixels at d + k beyond the control network."
        )
    mitigations = []
    for training in dict.fromkeys(r["training"] for r in rows):
        if training in (NONE, control):
            continue
        row = _find(rows, training, "shuffled", region)
        if row is None:
            continue
        m_uses = _above(row, "did")
        mitigations.append(
            {
                "condition": training,
                "did": row["did"],
                "did_low": row["did_low"],
                "did_high": row["did_high"],
                "uses_cue": m_uses,
                "removes": uses and not m_uses,
            }
        )
    if mitigations:
        said = "; ".join(
            f"{m['condition']} {_fmt(m['did'], m['did_low'], m['did_high'])} "
            + ("(still uses it)" if m["uses_cue"] else "(no reliance)")
            for m in mitigations
        )
        if uses:
            removing = [m["condition"] for m in mitigations if m["removes"]]
            verdict = (
                "Training on " + ", ".join(removing) + " removes the reliance."
                if removing
                else "No mitigation removes the reliance."
            )
        else:
            verdict = "With no reliance on the renders as they are, there is none to remove."
        parts.append(f"Networks trained on each mitigation, same test: {said}. {verdict}")
    parts.append(f"Intervals: {INTERVAL_METHOD}.")
    out["mitigations"] = mitigations
    out["paragraph"] = " ".join(parts)
    out["claim"] = {
        "claim": "a trained matcher uses the cue",
        "answer": "yes" if uses else "no",
        "value": shuffle["did"],
        "low": shuffle["did_low"],
        "high": shuffle["did_high"],
        "control": f"difference in differences of the shuffle against the {control} network",
    }
    return out
