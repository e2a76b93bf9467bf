"""What people read for the claims: each claim's name, its place in the paper by section
name, and its control, in words instead of the identifiers the tables and scripts key on.

The claims table (``results/tables/claims.csv``) and ``results/summary.json`` keep their
``id``, ``claim``, ``section`` and ``control`` columns as the claims file
(``stereovar/statistics/claims.yaml``) writes them; the pages and the log show
:func:`claim_name`, :func:`section_name` and :func:`control_name` of them. A claims file of a
user's own gets names from the same rules (identifiers spelled out), without a table of its
own.

The sections are those of the paper (``cross_view_variance_correlation.tex``) as numbered in
its compiled form: 1 Introduction; 2 Method (2.1 variance estimation, 2.2 cross-view
alignment, 2.3 correlation measure); 3 Experiments (3.1 setup, 3.2 cross-scene correlation,
3.3 SPP invariance, 3.4 causal evidence: alignment as a matching cue, 3.5 material
breakdown); 4 Discussion; 5 Conclusion.
"""

from __future__ import annotations

import re

__all__ = [
    "CLAIM_NAMES",
    "SECTION_NAMES",
    "claim_name",
    "control_name",
    "readable",
    "section_name",
]

SECTION_NAMES = {
    "sec:intro": "introduction",
    "sec:method": "method",
    "sec:method-var": "variance estimation",
    "sec:method-warp": "cross-view alignment",
    "sec:method-rho": "correlation measure",
    "sec:exp": "experiments",
    "sec:exp-setup": "setup",
    "sec:exp-main": "cross-scene correlation",
    "sec:exp-spp": "SPP invariance",
    "sec:exp-cv": "causal evidence, the residual-shuffle intervention",
    "sec:exp-mat": "material breakdown",
    "sec:discussion": "discussion",
    "sec:conclusion": "conclusion",
}
"""The paper's section labels and their titles, as a reader knows them."""

REGION_NAMES = {"all": "all valid pixels", "non_glass": "non-glass", "glass": "glass"}
"""Regions of the statistics."""

COST_NAMES = {
    "residual_sad": "residual SAD",
    "variance_cost": "variance cost",
    "variance_peak": "variance peak",
}
"""Table 3's cost functions (Sec. 3.4)."""

METRIC_NAMES = {
    "gt_margin": "ground-truth margin",
    "wta_accuracy": "winner-take-all accuracy",
    "peak_hit_rate": "peak hit rate",
}
"""Table 3's matching metrics (Sec. 3.4)."""

METHOD_NAMES = {
    "sensor_sim": "a simulated camera's noise",
    "sensor": "the analytic sensor model",
    "null_flip": "the right field flipped",
    "null_shift": "the disparity shifted",
    "no_warp": "no warp",
    "partial": "intensity controlled",
    "spearman": "Spearman",
}
"""Statistics and controls that a control label names by identifier."""

CLAIM_NAMES = {
    "rho_all": "ρ over all valid pixels is 0.754",
    "rho_non_glass": "ρ on non-glass pixels is 0.779",
    "rho_glass": "ρ on glass pixels is 0.301",
    "rho_glass_below_non_glass": "ρ is lower on glass than on non-glass (0.301 against 0.779)",
    "rho_no_warp": "Without the warp, ρ falls to 0.36",
    "spp_invariance": "ρ does not change with SPP (within 0.2%)",
    "no_finite_sample_artefact": "ρ does not change with the number of seeds N (within 0.2%): "
    "no finite-sample artefact",
    "glass_variance_ratio": "Glass pixels carry 7 times the variance of non-glass pixels",
    "real_sensors_rho_zero": "Real sensors carry ρ = 0",
    "probe": "A trained matcher uses the cue",
}
"""Names of the claims of the shipped claims file, by id; Table 3's claims are named from
their cost, metric and region (:func:`claim_name`)."""

_LABEL = re.compile(r"\s*\(((?:sec|tab|fig|eq):[\w:-]+)\)")
_TABLE3 = re.compile(
    r"^Table 3 (?P<cost>\w+) (?P<metric>\w+) (?P<region>\w+): normal (?P<sign>[<>]) decorr\.?$"
)
_RHO = re.compile(r"\brho\b")


def readable(text: str) -> str:
    """``text`` with identifiers spelled out: ``rho`` as ρ, regions, costs, metrics and
    statistics by name, other underscores as spaces.

    Examples
    --------
    >>> readable("rho (non_glass) = 0.779")
    'ρ (non-glass) = 0.779'
    >>> readable("shuffle drop of the sensor_only network")
    'shuffle drop of the sensor only network'
    >>> readable("90% interval [0.1, 0.2] against 0 +- 0.1")
    '90% interval [0.1, 0.2] against 0 ± 0.1'
    """
    out = _RHO.sub("ρ", str(text))
    for table in (REGION_NAMES, COST_NAMES, METRIC_NAMES, METHOD_NAMES):
        for key, name in table.items():
            if "_" in key:
                out = re.sub(rf"\b{re.escape(key)}\b", name, out)
    return out.replace("_", " ").replace(" +- ", " ± ")


def section_name(section: str) -> str:
    """Where the paper makes a claim, by section number and name: each ``(sec:...)`` label
    becomes the section's name, the labels of tables and figures are dropped.

    Examples
    --------
    >>> section_name("Sec. 3.4 (sec:exp-cv), Table 3 (tab:intervention)")
    'Sec. 3.4, causal evidence, the residual-shuffle intervention; Table 3'
    >>> section_name("Sec. 3.2 (sec:exp-main), Table 1 (tab:cross)")
    'Sec. 3.2, cross-scene correlation; Table 1'
    >>> section_name("Sec. 9 (sec:elsewhere)"), section_name("")
    ('Sec. 9', '')
    """
    parts = []
    for item in (p.strip() for p in str(section or "").split(",")):
        if not item:
            continue
        label = _LABEL.search(item)
        place = _LABEL.sub("", item).strip()
        name = SECTION_NAMES.get(label.group(1)) if label else None
        parts.append(f"{place}, {name}" if name else place)
    return "; ".join(parts)


def claim_name(claim_id: str, text: str) -> str:
    """A claim's name as a sentence a reader follows: the shipped claims by
    :data:`CLAIM_NAMES`, Table 3's from their cost, metric and region, any other with its
    identifiers spelled out (:func:`readable`).

    Examples
    --------
    >>> claim_name("rho_all", "rho (all) = 0.754")
    'ρ over all valid pixels is 0.754'
    >>> print(claim_name("t3", "Table 3 variance_cost gt_margin non_glass: normal > decorr."))
    ... # doctest: +NORMALIZE_WHITESPACE
    Variance cost, ground-truth margin on non-glass pixels: higher with the residuals aligned
    than block-shuffled
    >>> claim_name("mine", "rho (glass) above 0.1")
    'ρ (glass) above 0.1'
    """
    if claim_id in CLAIM_NAMES:
        return CLAIM_NAMES[claim_id]
    match = _TABLE3.match(str(text))
    if match and match["cost"] in COST_NAMES and match["metric"] in METRIC_NAMES:
        region = REGION_NAMES.get(match["region"], readable(match["region"]))
        where = "" if match["region"] == "all" else f" on {region} pixels"
        more = "higher" if match["sign"] == ">" else "lower"
        name = (
            f"{COST_NAMES[match['cost']]}, {METRIC_NAMES[match['metric']]}{where}: {more} "
            "with the residuals aligned than block-shuffled"
        )
        return name[0].upper() + name[1:]
    return readable(text)


def control_name(label: str) -> str:
    """A control's label in words (:func:`readable`, ``X rho`` as "ρ of X").

    Examples
    --------
    >>> control_name("sensor_sim rho"), control_name("null_flip rho")
    ("ρ of a simulated camera's noise", 'ρ of the right field flipped')
    >>> control_name("spearman glass - non-glass")
    'Spearman ρ, glass minus non-glass'
    >>> control_name("same on simulated sensor frames")
    'same on simulated sensor frames'
    """
    label = str(label or "")
    method, _, rest = label.partition(" ")
    if rest == "rho" and method in METHOD_NAMES:
        return f"ρ of {METHOD_NAMES[method]}"
    if method == "spearman" and " - " in rest:
        first, second = rest.split(" - ", 1)
        return f"Spearman ρ, {readable(first)} minus {readable(second)}"
    if label == "analytic sensor rho":
        return "ρ of the analytic sensor model"
    return readable(label)
