"""The verdict page in plain words: what its numbers mean, for a reader without the paper.

:func:`meaning_items` gives the page's "What these numbers mean" box: :math:`\\rho`, the
Monte Carlo-specific :math:`\\rho`, the matched null, the 95% interval, the light and the
:math:`C_\\sigma` lift, each defined in a sentence a data engineer reads, with this audit's
own numbers where they help; then :func:`readings` explains the readings that look
contradictory on this audit's numbers (and only those that occur):

- a simulated camera's raw :math:`\\rho` above the renders' (raw :math:`\\rho` follows
  brightness, which both views of any camera share, so it cannot tell Monte Carlo noise from
  sensor noise);
- a red light without a matching cue beyond a camera's (the light follows the Monte
  Carlo-specific :math:`\\rho`; the matching test asks a narrower question);
- a Monte Carlo-specific :math:`\\rho` far below the raw :math:`\\rho` (most of the raw
  correlation is brightness).

Each item is ``(term, text)``: the page sets the term in bold.
"""

from __future__ import annotations

import math

from .verdict import MATCHING, SPECIFIC, _find, _interval, _ok


def _value(row: dict) -> float:
    try:
        return float(row.get("value"))
    except (TypeError, ValueError):
        return math.nan


def meaning_items(rows: list[dict], result: dict) -> list[tuple[str, str]]:
    """The "What these numbers mean" box: each term with its definition in plain words.

    Parameters
    ----------
    rows : list of dict
        :func:`stereovar.audit.verdict.verdict_rows` (``null``: the matched null).
    result : dict
        :func:`stereovar.audit.verdict.verdict`.

    Returns
    -------
    list of tuple
        ``(term, text)`` in reading order, then :func:`readings`.

    Examples
    --------
    >>> rows = [{"quantity": "Monte Carlo-specific rho", "region": "all", "value": 0.4,
    ...          "low": 0.3, "high": 0.5, "null": 0.01}]
    >>> [term for term, _ in meaning_items(rows, {"matching_cue": None})][:3]
    ['ρ (rho)', 'Monte Carlo-specific ρ', 'Matched null']
    """
    specific = _find(rows, SPECIFIC)
    null = specific.get("null")
    null_text = f" Here it is {float(null):.3f}." if _ok(null) else (
        " This audit has none, so no number on this page is called Monte Carlo-specific."
    )
    items = [
        ("ρ (rho)",
         "a correlation, from −1 to 1, between the two views' per-pixel noise levels (how much "
         "each pixel varies from one render seed to the next), after the right view is moved "
         "onto the left by the true disparity. 0: unrelated; 1: the same pattern in both "
         "views."),
        ("Monte Carlo-specific ρ",
         "the part of ρ a real camera would not give: ρ after removing what each view's "
         "brightness, colour and position on the sensor explain (the intensity-controlled "
         "ρ), minus the same number on the matched null. When its whole 95% interval is "
         "above 0.05, the renders carry a cue a stereo network can learn from them and will "
         "not find in real photographs."),
        ("Matched null",
         "the same measurement on simulated camera noise (noise that follows brightness, as "
         "a sensor's does) drawn for these same frames, seed counts and disparities, and "
         "stored in the same file encoding: what the number would be without Monte Carlo "
         "noise." + null_text),
        ("95% interval",
         "the numbers in brackets, [low, high]: a range that holds the true value in 95 of "
         "100 repeats of this audit. It is made by resampling each frame's pixels in blocks "
         "(a spatial block bootstrap), because neighbouring pixels are not independent, and "
         "combining the frames."),
        ("The light",
         "RED: a moderate or strong Monte Carlo-specific cue (0.3 or more), a cue a "
         "variance-matching cost can use, or views that share their random numbers: act "
         "before training. AMBER: a weak cue, a result that cannot be tested, or a flag to "
         "check. GREEN: none of these: nothing to do about this cue."),
        ("C_σ lift",
         "how many percentage points (pp) more often than chance a matcher that compares "
         "only the two views' noise levels (the cost C_σ) picks the true disparity; read "
         "beyond the same lift on the matched null."),
    ]
    return items + readings(rows, result)


def readings(rows: list[dict], result: dict) -> list[tuple[str, str]]:
    """The readings of this audit that look contradictory, each explained (see the module
    docstring); none when none occurs.

    Examples
    --------
    >>> rows = [
    ...     {"quantity": "Pearson rho after the warp", "region": "all",
    ...      "value": 0.55, "low": 0.48, "high": 0.61},
    ...     {"quantity": "camera baseline: simulated sensor, same N", "region": "all",
    ...      "value": 0.69, "low": 0.68, "high": 0.70}]
    >>> [term for term, _ in readings(rows, {"mc_specific": True})]
    ["Why a camera's raw ρ can be higher"]
    """
    out = []
    raw, camera = _find(rows, "Pearson rho after"), _find(rows, "camera baseline: simulated")
    if _ok(raw["value"], camera["value"]) and _value(camera) > _value(raw):
        shown = {k: _interval(r["value"], r["low"], r["high"])
                 for k, r in (("camera", camera), ("raw", raw))}
        out.append((
            "Why a camera's raw ρ can be higher",
            f"the simulated camera's raw ρ ({shown['camera']}) is above the renders' "
            f"({shown['raw']}). Raw ρ "
            "mostly follows brightness, which both views of any camera share, so a camera's "
            "noise levels correlate across the views too, here more. The raw ρ alone cannot "
            "tell Monte Carlo noise from sensor noise; that is why the verdict reads the Monte "
            "Carlo-specific ρ, from which brightness is removed.",
        ))
    beyond = _find(rows, MATCHING)
    if result.get("mc_specific") is True and result.get("matching_cue") is False:
        out.append((
            "Why a Monte Carlo-specific cue without a matching cue",
            "the verdict follows the Monte Carlo-specific ρ: the noise ties the two views "
            "together in a way no camera does, and a network can learn that as a shortcut. "
            "The matching test asks something narrower: whether a cost comparing noise "
            "levels alone finds the disparity more often than on a camera's noise"
            + (f" (here {100 * _value(beyond):+.1f} pp)" if _ok(beyond["value"]) else "")
            + ". It does not here, so this simple cost gains nothing a camera would not give; "
            "a trained network can still use the cue in other ways (the learned probe tests "
            "that).",
        ))
    specific = _find(rows, SPECIFIC)
    if _ok(raw["value"], specific["value"]) and _value(specific) < 0.5 * _value(raw):
        out.append((
            "Why the Monte Carlo-specific ρ is below the raw ρ",
            "most of the raw correlation is brightness, which any camera shares between "
            "its views; what is left once brightness and the matched null are removed is "
            "what only Monte Carlo rendering gives.",
        ))
    return out
