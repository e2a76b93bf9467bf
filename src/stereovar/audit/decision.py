"""The audit page's opening: a traffic light and what was found, how sure, and what to do.

:func:`decision` reads the verdict (:func:`stereovar.audit.verdict.verdict`), the seeding
check (:func:`stereovar.audit.seeding.seeding_finding`), the flags
(:func:`stereovar.audit.flags.control_flags` and the import's warnings) and, where measured,
the audit's own mitigations and dose-response, and words the advice: which mitigation removes
the cue, which budget and camera do, or the probe of the team's own network
(:data:`PROBE_COMMAND`) as the next step.
"""

from __future__ import annotations

import math

from .verdict import SPECIFIC, _find, _interval, _ok

LIGHTS = {"red": "#c0392b", "amber": "#e6a700", "green": "#2e8b57", "grey": "#808080"}
"""Traffic-light colours of the decision."""

PROBE_COMMAND = (
    "stereovar probe --model yourpkg.nets:build --weights model.pt --config audit.yaml "
    "(your network's factory and weights, this audit's config; docs: Probing your own "
    "network)."
)
"""The command the advice names when no mitigation removes the cue: the probe of the team's
own network on the audit's frames."""


def decision(
    result: dict, seeding: dict, flags: list[dict], mitigations: list[str], rows=(), *,
    dose=(),
) -> dict:
    """The page's opening: a traffic light and two or three sentences (what was found, how
    sure, what to do).

    Red: a moderate or strong Monte Carlo-specific cue, a variance-matching cue beyond a
    camera, or views that share their random streams. Amber: a weak cue, a result that
    cannot be tested, or a verdict with flags. Green: none of these.

    Parameters
    ----------
    result : dict
        :func:`~stereovar.audit.verdict.verdict`.
    seeding : dict
        :func:`~stereovar.audit.seeding.seeding_finding`.
    flags : list of dict
        The import's warnings and :func:`~stereovar.audit.flags.control_flags`.
    mitigations : list of str
        :func:`stereovar.statistics.mitigations.mitigation_findings` of the audit's own
        mitigation table (empty when ``audit.mitigations`` is not set).
    rows : list of dict
        :func:`~stereovar.audit.verdict.verdict_rows`: the numbers the sentences quote, each
        with its interval and its control.
    dose : list of str
        :func:`stereovar.statistics.dose_response.dose_findings` of the audit's
        dose-response (empty without ``sensor_only`` in ``audit.mitigations``): where no
        mitigation removes the cue, the budget and camera that do, or else the probe of the
        team's own network as the next step.

    Returns
    -------
    dict
        ``light`` (a :data:`LIGHTS` key), ``headline`` and ``sentences`` (how sure, what
        to do), the two also as ``sure`` and ``do``.
    """
    mc, word = result["mc_specific"], result["strength"]
    strong = mc is True and word in ("strong", "moderate")
    red = strong or result.get("matching_cue") is True or seeding.get("shared") is True
    if red:
        light = "red"
    elif mc is None or (mc is True) or flags:
        light = "amber"
    else:
        light = "green"
    tested = result.get("matched_null", True)
    if mc is True and not tested:
        found = (
            f"These renders carry a {word} intensity-controlled cross-view variance cue "
            "(no matched null: not tested as Monte Carlo-specific)"
        )
    elif mc is True:
        found = f"These renders carry a {word} Monte Carlo-specific cross-view variance cue"
    elif mc is False:
        found = "No Monte Carlo-specific cross-view variance cue was detected in these renders"
    else:
        found = "Whether these renders carry a Monte Carlo-specific cue cannot be told"
    if seeding.get("shared") is True:
        found += ", and the two views share their random streams"
    headline = found + "."
    def iv(r):
        return _interval(r["value"], r["low"], r["high"])

    partial, pearson = _find(rows, "intensity-controlled"), _find(rows, "Pearson rho after")
    camera = _find(rows, "camera baseline: simulated")
    specific = _find(rows, SPECIFIC)
    zero = seeding.get("zero") or (math.nan, math.nan, math.nan)
    if _ok(specific["value"], specific["low"], specific["high"], specific.get("null")):
        first = (
            f"How sure: the Monte Carlo-specific rho is {iv(specific)} (95% interval): the "
            f"intensity-controlled rho {iv(partial)} minus its matched null "
            f"{specific['null']:.3f} (camera-law noise drawn on these frames)"
        )
    else:
        first = (
            f"How sure: the intensity-controlled rho is {iv(partial)} (95% interval), "
            "where a real camera's noise gives about 0"
        )
    sure = (
        first + "; the raw Pearson rho "
        f"{iv(pearson)} is beside {iv(camera)} for a simulated camera"
        + (
            ", and the residual correlation at zero disparity is "
            + _interval(*zero)
            + ", where independent seeds give 0"
            if seeding.get("shared")
            else ""
        )
        + (
            f"; {len(flags)} flag{'s' * (len(flags) != 1)} below "
            f"qualif{'ies' if len(flags) == 1 else 'y'} it."
            if flags
            else "; no check raised a flag."
        )
    )
    # a budget and camera measured to remove it first, else one predicted (its line says so)
    removing = ([line for line in dose if ": removed from" in line]
                or [line for line in dose if ": predicted removed from" in line
                    and "but measured" not in line])
    if mitigations and not mitigations[-1].startswith("No mitigation"):
        do = "Measured on these renders (audit.mitigations): " + mitigations[-1]
    elif mitigations:
        do = ("None of the mitigations measured on these renders removes the Monte "
              "Carlo-specific part at their own budget; see the Mitigations section. ")
        if removing:
            do += "To remove it: " + removing[0]
        elif dose:
            do += (dose[0] + " No budget or camera measured removes it, so the next step is "
                   "to test whether your own network uses it: " + PROBE_COMMAND)
        else:
            do += ("Next: add sensor_only to audit.mitigations to find the budget and camera "
                   "that remove it (the dose-response), or test whether your own network "
                   "uses it: " + PROBE_COMMAND)
    elif red or mc is True:
        do = (
            "Before training a stereo network on them, measure which mitigation removes the "
            "cue and at what budget, camera and image quality: set audit.mitigations: "
            "[denoise, denoise_sensor, equalise, sensor_only] and run the audit again."
        )
    elif mc is None:
        do = ("Nothing can be concluded yet: give the audit more frames or seeds (stereovar "
              "sample plans how many) or fix what the flags below name, and run it again.")
    elif flags:
        do = ("No cue to mitigate was found; check the flags below before relying on that, "
              "as each can hide one.")
    else:
        do = "Nothing needs mitigating for this cue before training."
    if seeding.get("shared") is True:
        do += " Render each view with its own sampler seed (Cycles: scene.cycles.seed)."
    return {"light": light, "headline": headline, "sentences": [sure, do], "sure": sure,
            "do": do}
