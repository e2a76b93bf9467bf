"""The results page's one-line conclusion, the box at its top (:func:`conclusion`): a word
for the verdict on the Monte Carlo-specific :math:`\\rho` (:data:`CONCLUSIONS`) and one
sentence with the number, its interval and its control.
"""

from __future__ import annotations

import math

from .headline import HEADLINE_METHOD
from .numbers import _f

__all__ = ["conclusion"]

CONCLUSIONS = {
    "remains": ("Cue present", "remains"),
    "reversed": ("Below the null", "inconclusive"),
    "removed": ("No cue", "removed"),
    "inconclusive": ("Undecided", "inconclusive"),
    "n/a": ("Not calibrated", "na"),
}
"""The conclusion's word and colour class for each verdict on the Monte Carlo-specific
:math:`\\rho` (:func:`stereovar.statistics.mitigations.mc_cue_state`)."""


def conclusion(matched: dict, warp: dict, explained: dict | None = None) -> dict:
    """The page's one-line conclusion: a word for the verdict on the Monte Carlo-specific
    :math:`\\rho` (:data:`CONCLUSIONS`) and one sentence with the number, its interval and
    its control (the matched null); without a matched null, :math:`\\rho` after the warp with
    its interval, not called Monte Carlo-specific, and its control where the claims say
    that the control explains it.

    Parameters
    ----------
    matched : dict
        :func:`~stereovar.pages.headline.matched_headline`.
    warp : dict
        :func:`~stereovar.pages.headline.headline`.
    explained : dict, optional
        :func:`~stereovar.pages.controls.explained_statistics`.

    Examples
    --------
    >>> m = {"value": 0.4, "low": 0.3, "high": 0.5, "null": 0.001, "margin": 0.1,
    ...      "verdict": "remains", "text": "0.400 [0.300, 0.500]", "n_scenes": 4}
    >>> c = conclusion(m, {"text": "0.745 [0.6, 0.9]"})
    >>> c["word"], c["text"]  # doctest: +NORMALIZE_WHITESPACE
    ('Cue present', 'Monte Carlo-specific ρ = 0.400 [0.300, 0.500] beyond its matched null
    0.001 (all valid pixels, 4 scenes).')
    """
    verdict = matched.get("verdict", "n/a")
    word, cls = CONCLUSIONS.get(verdict, CONCLUSIONS["n/a"])
    n = matched.get("n_scenes")
    where = "all valid pixels" + (f", {n} scenes" if n not in (None, "") else "")
    number = f"Monte Carlo-specific ρ = {matched.get('text', 'n/a')}"
    null = f"matched null {_f(matched.get('null')):.3f}"
    margin = _f(matched.get("margin"))
    if verdict == "remains":
        text = f"{number} beyond its {null} ({where})."
    elif verdict == "reversed":
        text = f"{number}: below its {null} ({where})."
    elif verdict == "removed":
        text = f"{number} against its {null}, within the calibration's margin ±{margin:.3f}."
    elif verdict == "inconclusive":
        reach = f"past the margin ±{margin:.3f}" if math.isfinite(margin) else "with no margin"
        text = f"{number} against its {null}: the interval covers 0 but reaches {reach}."
    else:
        control = (explained or {}).get(("all", HEADLINE_METHOD))
        text = (
            f"No matched null in this run, so no ρ here is called Monte Carlo-specific; "
            f"ρ after the warp = {warp.get('text', 'n/a')}"
            + (f", explained by a control ({control})." if control else ".")
        )
    return {"word": word, "cls": cls, "text": text, "verdict": verdict}
