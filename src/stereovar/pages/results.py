"""The main run's results page, ``results/index.html``: what a person opens after a run.

:func:`page_sections` puts the run's results in reading order, and :func:`to_html_page`
renders them with the template ``results.html.j2`` (:mod:`stereovar.pages.templates`) as one
self-contained page (figures embedded, links relative to ``results/``):

1. a one-line conclusion (:func:`conclusion`): whether the views' Monte Carlo variance fields
   correlate beyond their matched null, with the number that says so, its interval and its
   control;
2. the run's settings (renderer, estimator, scenes, N and SPP, the config digest);
3. the headline (:func:`matched_headline`): the Monte Carlo-specific :math:`\\rho`, the
   intensity-controlled :math:`\\rho` minus its matched null through the same path, with its
   95% interval and the null beside it; then every control by region with its interval
   (:func:`control_rows`), each number the claims call "explained by a control" marked so
   beside it; and the calibration's sentence;
4. the claims table (:func:`claim_cells`), each claim by name and section name
   (:mod:`stereovar.pages.names`), on a band of colour :data:`CLAIMS_BAND`;
5. the figures with their captions (``workflow/report/*.rst``, MathML math);
6. the mitigations (one compact table, :func:`mitigation_rows`), the learned probe and the
   generator profiles, when they have run;
7. links to every table in each format, and to Snakemake's report or the command that makes it.

A number is called Monte Carlo-specific only as a difference from its matched null
(the calibration's camera-law noise through the same statistic): without the calibration's
nulls the page says so, and headlines :math:`\\rho` after the warp with its controls.
"""

from __future__ import annotations

import math

from .names import claim_name, control_name, readable, section_name

__all__ = [
    "CLAIMS_BAND",
    "CONTROL_GROUPS",
    "REGIONS",
    "claim_cells",
    "conclusion",
    "control_rows",
    "headline",
    "interval_keys",
    "interval_text",
    "matched_headline",
    "mitigation_rows",
    "page_sections",
    "significant",
    "to_html_page",
]

CLAIMS_BAND = "#e3eefb"
"""Background of the claims table, a colour used nowhere else on the page (a browser test
finds the table on a screenshot by it)."""

REGIONS = {"all": "all valid pixels", "non_glass": "non-glass", "glass": "glass"}
"""Regions of the headline table, in order, with their labels."""

HEADLINE_METHOD = "warp"
"""The paper's statistic: Pearson's :math:`\\rho` after the warp (Eq. 3)."""

SCENE_METHODS = frozenset({"warp", "sensor_sim", "sensor", "null_shift", "null_flip",
                           "no_warp"})
"""Statistics the page reads against the paper and the camera, as the claims do: each shown
with the interval for the mean over scenes like these (``scenes_low``, ``scenes_high``, a
random-effects interval), the same interval as in the claims table. The others (the
intensity-controlled :math:`\\rho`, read against its matched null as the calibration and the
mitigations read it) keep the scenes' block-bootstrap intervals combined. One quantity, one
interval: no number on the page is shown with both."""

INTERVAL_NOTE = (
    "95% intervals: of ρ after the warp and its camera and null-warp controls, over scenes "
    "like these (as the claims); of the intensity-controlled and Monte Carlo-specific ρ, on "
    "these scenes' pixels (block bootstrap, as the calibration and the mitigations)."
)
"""How the page's intervals are made, under the headline table."""


def interval_keys(method: str) -> tuple[str, str]:
    """The statistics-table columns of ``method``'s interval on the page
    (:data:`SCENE_METHODS`).

    Examples
    --------
    >>> interval_keys("warp"), interval_keys("partial")
    (('scenes_low', 'scenes_high'), ('boot_low', 'boot_high'))
    """
    return ("scenes_low", "scenes_high") if method in SCENE_METHODS else ("boot_low", "boot_high")

MATCHED_METHOD = "partial"
"""The statistic whose difference from its matched null is the Monte Carlo-specific part:
the intensity-controlled :math:`\\rho` (camera noise follows intensity, which both views
share)."""

Z = 1.959963984540054
"""The standard normal's 0.975 quantile (95% intervals)."""

CONTROL_GROUPS = (
    (
        "intensity-controlled",
        "ρ of ln σ² with ln μ regressed out of each view; the Monte Carlo-specific ρ is it "
        "minus the same on camera-law noise drawn from this run's frames",
        (("partial", "partial ρ"),),
    ),
    (
        "sensor baseline",
        "the same on a simulated camera's noise: what any stereo pair shows",
        (("sensor_sim", "simulated camera"),),
    ),
    (
        "null warps",
        "wrong alignments, which sit well below ρ when the warp matters",
        (
            ("null_shift", "disparity shifted"),
            ("null_flip", "right field flipped"),
            ("no_warp", "no warp"),
        ),
    ),
)
"""The controls shown beside the headline: (group, what it tells, ((method, label), ...));
every other statistic and control is in the statistics table and figure."""

VERDICT_CLASSES = {
    "holds": "holds",
    "does not hold": "fails",
    "explained by a control": "explained",
    "not testable at this scale": "untestable",
    "remains": "remains",
    "removed": "removed",
    "inconclusive": "inconclusive",
    "reversed": "remains",
    "n/a": "na",
}
"""CSS class of each verdict (others, such as the probe's yes/no, are plain)."""

EXPLAINED = "explained by a control"
"""The claims' verdict that the page repeats beside the number it concerns."""

CONCLUSIONS = {
    "remains": ("Cue present", "remains"),
    "reversed": ("Below the null", "inconclusive"),
    "removed": ("No cue", "removed"),
    "inconclusive": ("Undecided", "inconclusive"),
    "n/a": ("Not calibrated", "na"),
}
"""The conclusion's word and colour class for each verdict on the Monte Carlo-specific
:math:`\\rho` (:func:`stereovar.statistics.mitigations.mc_cue_state`)."""

TABLE_LABELS = {
    "claims": "Claims of the paper on this run",
    "scenes": "Scenes",
    "statistics": "Every statistic and control across scenes",
    "seed_curve": "ρ against the number of seeds",
    "cross_scene": "Table 1: per scene",
    "spp_sweep": "Table 2: ρ against SPP",
    "spp_sweep_fit": "Table 2: fit against SPP",
    "intervention": "Table 3: the residual-shuffle intervention",
    "cross_renderer": "The renderers side by side",
    "mitigations": "Mitigations: every region, control and Table 3 column",
    "mitigations_headline": "Mitigations: the table on this page",
    "probe": "Learned probe",
    "probe_training": "Learned probe: training",
    "generators": "Generator profiles",
    "calibration": "Calibration: false positives, power and coverage of every rule",
    "calibration_nulls": "Calibration: each scene's matched null per transform",
}
"""Labels of the tables the page links, by file name."""

MITIGATION_COLUMNS = {
    "mitigation": "mitigation",
    "samples": "samples per image",
    "mc_specific": "Monte Carlo-specific ρ of its renders [95%]",
    "null": "matched null",
    "ships": "Monte Carlo-specific ρ of what it ships [95%] (the verdict reads it)",
    "verdict": "verdict",
    "psnr": "PSNR, dB [95%]",
    "budget": "raw render at equal budget, dB",
}
"""The compact mitigation table's columns and headers (:func:`mitigation_rows`)."""


def _f(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def significant(value: float, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits (at least), with no exponent from 0.0001 up
    to a million: a value of ``digits`` or more integer digits is shown whole.

    Examples
    --------
    >>> significant(0.75412), significant(3594.2), significant(-10613.0), significant(7.0)
    ('0.754', '3594', '-10613', '7')
    >>> significant(0.000123), significant(2.5e7)
    ('0.000123', '2.5e+07')
    """
    if 10 ** (digits - 1) <= abs(value) < 1e6:
        return f"{value:.0f}"
    return f"{value:.{digits}g}"


def interval_text(value, low, high, *, fmt: str = ".3f") -> str:
    """``value [low, high]``, ``value (no interval)`` or ``n/a``; ``fmt`` is a format
    specification, or ``sig`` for :func:`significant`.

    Examples
    --------
    >>> interval_text(0.75412, 0.7311, 0.7766)
    '0.754 [0.731, 0.777]'
    >>> interval_text(7.04, None, "", fmt="sig"), interval_text(float("nan"), 0, 1)
    ('7.04 (no interval)', 'n/a')
    """
    v, lo, hi = _f(value), _f(low), _f(high)

    def show(x):
        return significant(x) if fmt == "sig" else format(x, fmt)

    if not math.isfinite(v):
        return "n/a"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{show(v)} (no interval)"
    return f"{show(v)} [{show(lo)}, {show(hi)}]"


def _statistic(statistics: list[dict], region: str, method: str) -> dict | None:
    return next(
        (r for r in statistics if r.get("region") == region and r.get("method") == method), None
    )


def headline(statistics: list[dict]) -> dict:
    """:math:`\\rho` after the warp over all valid pixels (Eq. 3) from ``summary.json``'s
    ``statistics``: the mean over scenes with its interval for scenes like these
    (:func:`interval_keys`; the claims table's).

    Returns
    -------
    dict
        ``rho``, ``low``, ``high`` (NaN when missing), ``n_scenes`` and ``text``
        (:func:`interval_text`).

    Examples
    --------
    >>> h = headline([{"region": "all", "method": "warp", "mean_rho": 0.7, "boot_low": 0.65,
    ...                "boot_high": 0.75, "scenes_low": 0.6, "scenes_high": 0.8, "n_scenes": 3}])
    >>> h["text"], h["n_scenes"]
    ('0.700 [0.600, 0.800]', 3)
    """
    row = _statistic(statistics, "all", HEADLINE_METHOD) or {}
    rho, low, high = (_f(row.get(k)) for k in ("mean_rho", *interval_keys(HEADLINE_METHOD)))
    return {
        "rho": rho,
        "low": low,
        "high": high,
        "n_scenes": row.get("n_scenes"),
        "text": interval_text(rho, low, high),
    }


def matched_headline(
    statistics: list[dict],
    nulls: list[dict],
    *,
    region: str = "all",
    method: str = MATCHED_METHOD,
    transform: str = "none",
    scenes=None,
) -> dict:
    """The Monte Carlo-specific :math:`\\rho`: the statistic ``method`` over ``region``
    (``summary.json``'s mean over scenes) minus its matched null through the same path (the
    calibration's ``calibration_nulls.csv``, ``transform`` ``none``: the renders as
    rendered), with its 95% interval.

    .. math::

        \\Delta = \\bar\\rho - \\frac1S\\sum_s \\bar\\rho_{0,s}, \\qquad
        \\Delta \\pm z_{0.975}\\sqrt{\\Bigl(\\frac{h - \\ell}{2 z_{0.975}}\\Bigr)^2
            + \\frac{1}{S^2}\\sum_s \\bigl(\\mathrm{se}_{0,s}^2 + s_{\\text{chance},s}^2\\bigr)}

    with :math:`[\\ell, h]` the statistic's interval from the scenes' block bootstraps
    combined (:func:`stereovar.statistics.across.combined_correlation_interval`: placed on
    Fisher's :math:`z` but as long as :func:`stereovar.statistics.across.combined_interval`'s,
    so :math:`(h - \\ell)/(2 z_{0.975})` is still the mean's standard error; the difference
    keeps the normal interval, being no correlation). This is
    :func:`stereovar.statistics.mitigations.matched_difference` (each scene's difference
    with :func:`stereovar.calibration.summary.difference_interval`, combined over scenes)
    written with the scenes' mean: the same number and interval as the mitigation table's
    ``none`` row. The verdict is :func:`stereovar.statistics.mitigations.mc_cue_state`'s
    against the calibration's equivalence margin.

    Parameters
    ----------
    statistics : list of dict
        ``summary.json``'s ``statistics`` (``region``, ``method``, ``mean_rho``,
        ``boot_low``, ``boot_high``, ``n_scenes``).
    nulls : list of dict
        :data:`stereovar.calibration.summary.NULL_COLUMNS` rows.
    scenes : iterable of str, optional
        The run's scenes: only their nulls count.

    Returns
    -------
    dict
        ``value``, ``low``, ``high``, ``null`` (the scenes' mean null), ``margin``,
        ``statistic`` (the statistic's own value, low, high), ``n_scenes``, ``verdict`` and
        ``text``; ``value`` NaN and ``verdict`` ``n/a`` when the run has no such null.

    Examples
    --------
    >>> stats = [{"region": "all", "method": "partial", "mean_rho": 0.5, "boot_low": 0.4,
    ...           "boot_high": 0.6, "n_scenes": 1}]
    >>> nulls = [{"scene": "a", "transform": "none", "region": "all", "method": "partial",
    ...           "null_rho": 0.1, "null_se": 0.0, "chance_sd": 0.0, "margin": 0.05}]
    >>> h = matched_headline(stats, nulls)
    >>> h["text"], h["null"], h["verdict"]
    ('0.400 [0.300, 0.500]', 0.1, 'remains')
    """
    from ..statistics.mitigations import mc_cue_state

    row = _statistic(statistics, region, method) or {}
    value, low, high = (_f(row.get(k)) for k in ("mean_rho", "boot_low", "boot_high"))
    wanted = set(scenes) if scenes else None
    chosen = [
        r for r in nulls
        if (r.get("transform"), r.get("region"), r.get("method")) == (transform, region, method)
        and (wanted is None or r.get("scene") in wanted)
        and math.isfinite(_f(r.get("null_rho")))
    ]
    margins = [_f(r.get("margin")) for r in chosen if math.isfinite(_f(r.get("margin")))]
    out = {
        "value": math.nan, "low": math.nan, "high": math.nan, "null": math.nan,
        "margin": margins[0] if margins else math.nan,
        "statistic": (value, low, high), "n_scenes": row.get("n_scenes"),
        "verdict": "n/a", "text": "n/a",
    }
    if not chosen or not math.isfinite(value):
        return out
    s = len(chosen)
    null = sum(_f(r["null_rho"]) for r in chosen) / s

    def sq(key):
        return sum(_f(r.get(key)) ** 2 for r in chosen if math.isfinite(_f(r.get(key))))

    diff = value - null
    out |= {"value": diff, "null": null, "text": interval_text(diff, math.nan, math.nan)}
    if math.isfinite(low) and math.isfinite(high):
        own = (high - low) / (2 * Z)
        chance = _f(row.get("chance_se"))
        own = max(own, chance) if math.isfinite(chance) else own
        se = math.sqrt(own**2 + sq("null_se") / s**2)
        out |= {"low": diff - Z * se, "high": diff + Z * se}
        out["text"] = interval_text(diff, out["low"], out["high"])
        out["verdict"] = mc_cue_state(out["low"], out["high"], out["margin"])
    return out


def explained_statistics(claims: list[dict], claim_statistics: dict) -> dict:
    """The statistics the claims call "explained by a control", by (region, method): the
    claim's name and its control, so the page says so beside the number.

    Parameters
    ----------
    claims : list of dict
        The claims table's rows (``id``, ``verdict``, ``control``).
    claim_statistics : dict
        Claim id to the (region, method) of the :math:`\\rho` it tests.

    Examples
    --------
    >>> explained_statistics([{"id": "rho_all", "verdict": "explained by a control",
    ...                        "control": "sensor_sim rho"}], {"rho_all": ("all", "warp")})
    {('all', 'warp'): "ρ of a simulated camera's noise"}
    """
    return {
        tuple(claim_statistics[c["id"]]): control_name(c.get("control") or "") or "its control"
        for c in claims
        if c.get("verdict") == EXPLAINED and c.get("id") in claim_statistics
    }


def control_rows(
    statistics: list[dict], matched: dict | None = None, explained: dict | None = None
) -> list[dict]:
    """The headline table by region: the Monte Carlo-specific :math:`\\rho` and its matched
    null (over all valid pixels, where the calibration has them), :math:`\\rho` after the warp,
    then each control of :data:`CONTROL_GROUPS` that ``statistics`` holds, each with its
    interval in every region (:func:`interval_keys`).

    Parameters
    ----------
    statistics : list of dict
        ``summary.json``'s ``statistics``.
    matched : dict, optional
        :func:`matched_headline` over all valid pixels.
    explained : dict, optional
        :func:`explained_statistics`: a cell it names says "explained by a control".

    Returns
    -------
    list of dict
        ``method``, ``group`` (``headline``, ``matched``, ``paper`` or a control group),
        ``label``, ``cells`` (region to text) and ``explained`` (region to the control that
        explains the cell's number).

    Examples
    --------
    >>> stats = [{"region": g, "method": m, "mean_rho": 0.5, "boot_low": 0.4, "boot_high": 0.6}
    ...          for g in ("all", "glass") for m in ("warp", "partial")]
    >>> [(r["method"], r["label"]) for r in control_rows(stats)]
    [('warp', 'ρ after the warp'), ('partial', 'intensity-controlled: partial ρ')]
    >>> control_rows(stats)[1]["cells"]
    {'all': '0.500 [0.400, 0.600]', 'non_glass': 'n/a', 'glass': '0.500 [0.400, 0.600]'}
    """
    explained = explained or {}

    def cells(method):
        return {
            region: interval_text(
                *(_f((_statistic(statistics, region, method) or {}).get(k))
                  for k in ("mean_rho", *interval_keys(method)))
            )
            for region in REGIONS
        }

    def marks(method):
        return {g: explained[(g, method)] for g in REGIONS if (g, method) in explained}

    rows = []
    if matched and math.isfinite(matched["value"]):
        none = {g: "no null" for g in REGIONS if g != "all"}
        rows += [
            {"method": "mc_specific", "group": "headline", "label": "Monte Carlo-specific ρ",
             "cells": {"all": matched["text"], **none}, "explained": {}},
            {"method": "matched_null", "group": "matched",
             "label": "its matched null (camera-law noise)",
             "cells": {"all": f"{matched['null']:.3f}", **none}, "explained": {}},
        ]
    rows.append({"method": HEADLINE_METHOD, "group": "paper", "label": "ρ after the warp",
                 "cells": cells(HEADLINE_METHOD), "explained": marks(HEADLINE_METHOD)})
    present = {r.get("method") for r in statistics}
    for group, _, methods in CONTROL_GROUPS:
        rows += [
            {"method": m, "group": group, "label": f"{group}: {label}", "cells": cells(m),
             "explained": marks(m)}
            for m, label in methods
            if m in present
        ]
    return rows


def conclusion(matched: dict, warp: dict, explained: dict | None = None) -> dict:
    """The page's one-line conclusion: a word for the verdict on the Monte Carlo-specific
    :math:`\\rho` (:data:`CONCLUSIONS`) and one sentence with the number, its interval and
    its control (the matched null); without a matched null, :math:`\\rho` after the warp with
    its interval, not called Monte Carlo-specific, and its control where the claims say
    that the control explains it.

    Parameters
    ----------
    matched : dict
        :func:`matched_headline`.
    warp : dict
        :func:`headline`.
    explained : dict, optional
        :func:`explained_statistics`.

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


def claim_cells(row: dict, *, rho: bool = False, own_scale: bool = False) -> dict:
    """One claims-table row (:data:`stereovar.statistics.claims.CLAIMS_COLUMNS`) as the
    page shows it: the claim by name (:func:`stereovar.pages.names.claim_name`), where the
    paper makes it by section name, numbers to 3 significant digits with their 95%
    intervals (``rho``: a correlation claim, to 3 decimals as the headline table shows the
    same numbers), the control in words. ``own_scale``: the paper's value is in the paper's
    own units (``paper_scale: own`` in the claims file), so the paper column gives its sign,
    the only part that compares, with the value named as the paper's own.

    Examples
    --------
    >>> c = claim_cells({"id": "rho_all", "claim": "rho (all) = 0.754",
    ...     "section": "Sec. 3.2 (sec:exp-main)", "paper": 0.754,
    ...     "ours": 0.7012, "ours_low": 0.65, "ours_high": 0.75, "control": "sensor_sim rho",
    ...     "control_value": 0.01, "control_low": -0.02, "control_high": 0.04,
    ...     "verdict": "does not hold", "note": ""})
    >>> c["claim"], c["section"]
    ('ρ over all valid pixels is 0.754', 'Sec. 3.2, cross-scene correlation')
    >>> c["ours"], c["verdict_class"]
    ('0.701 [0.65, 0.75]', 'fails')
    >>> c["control"], c["control_value"]
    ("ρ of a simulated camera's noise", '0.01 [-0.02, 0.04]')
    """
    paper = row.get("paper")
    fmt = ".3f" if rho else "sig"
    control_value = interval_text(
        row.get("control_value"), row.get("control_low"), row.get("control_high"), fmt=fmt
    )
    paper_note = ""
    if math.isfinite(_f(paper)) and own_scale:
        paper_text = "> 0" if _f(paper) > 0 else "< 0" if _f(paper) < 0 else "0"
        paper_note = f"sign only: the paper's {significant(_f(paper))} is in its own units"
    elif math.isfinite(_f(paper)):
        paper_text = significant(_f(paper))
    else:
        paper_text = str(paper or "")
    verdict = str(row.get("verdict", ""))
    return {
        "id": str(row.get("id", "")),
        "claim": claim_name(str(row.get("id", "")), str(row.get("claim", ""))),
        "section": section_name(str(row.get("section", ""))),
        "note": readable(str(row.get("note") or "")),
        "paper": paper_text,
        "paper_note": paper_note,
        "ours": interval_text(row.get("ours"), row.get("ours_low"), row.get("ours_high"),
                              fmt=fmt),
        "control": control_name(str(row.get("control") or "")) or "none",
        "control_value": control_value if row.get("control") else "",
        "verdict": verdict,
        "verdict_class": VERDICT_CLASSES.get(verdict, ""),
    }


def _iv(row: dict, column: str, digits: int = 3) -> str:
    value, low, high = (_f(row.get(k)) for k in (column, f"{column}_low", f"{column}_high"))
    return interval_text(value, low, high, fmt=f".{digits}f")


def mitigation_rows(rows: list[dict], region: str = "all") -> list[dict]:
    """The compact mitigation table (:data:`MITIGATION_COLUMNS`) over ``region``: per
    mitigation its samples per image, the Monte Carlo-specific :math:`\\rho` with its 95%
    interval beside its matched null, what a seed-mean transform ships, the verdict, and the
    PSNR cost beside a raw render at the same samples per image
    (:func:`stereovar.statistics.mitigations.equal_budget_psnr`). The full table is
    ``results/tables/mitigations.csv``.

    Examples
    --------
    >>> rows = [{"mitigation": "none", "region": "all", "render_spp": 32, "spp": 32,
    ...          "kind": "baseline", "mc_specific": 0.5, "mc_specific_low": 0.4,
    ...          "mc_specific_high": 0.6, "null_partial": 0.001, "mc_cue": "remains",
    ...          "psnr": 19.5, "psnr_low": 16.1, "psnr_high": 22.9}]
    >>> r = mitigation_rows(rows)[0]
    >>> r["mc_specific"], r["null"], r["verdict"], r["psnr"], r["budget"]
    ('0.500 [0.400, 0.600]', '0.001', 'remains', '19.5 [16.1, 22.9]', '')
    """
    from ..statistics.mitigations import equal_budget_psnr

    chosen = [r for r in rows if r.get("region") == region]
    out = []
    for r in chosen:
        budget, how = equal_budget_psnr(chosen, r)
        same = r.get("mitigation") == "none" or r.get("kind") == "spp"
        null = _f(r.get("null_partial"))
        samples = _f(r.get("render_spp"))
        out.append({
            "mitigation": readable(str(r.get("mitigation", ""))),
            "samples": f"{samples:.0f}" if math.isfinite(samples) else "",
            "mc_specific": _iv(r, "mc_specific"),
            "null": f"{null:.3f}" if math.isfinite(null) else "n/a",
            "ships": _iv(r, "shipped_mc_specific")
            if math.isfinite(_f(r.get("shipped_mc_specific"))) else "as measured",
            "verdict": str(r.get("mc_cue", "")),
            "verdict_class": VERDICT_CLASSES.get(str(r.get("mc_cue", "")), ""),
            "psnr": _iv(r, "psnr", 1),
            "budget": f"{budget:.1f} ({how})" if math.isfinite(budget) and not same else "",
        })
    return out


def page_sections(
    *,
    summary: dict,
    claims: list[dict],
    claims_text: str,
    rules: list[str],
    figures: list[dict],
    tables: list[dict],
    intro: str = "",
    mitigations: dict | None = None,
    probe: dict | None = None,
    generators: dict | None = None,
    report: str | None = None,
    report_command: str = "stereovar report",
    calibration: str = "",
    nulls: list[dict] | None = None,
    claim_statistics: dict | None = None,
    docs: dict | None = None,
    own_scale=(),
    provenance: dict | None = None,
) -> dict:
    """Everything the page shows, in reading order (see the module docstring).

    Parameters
    ----------
    summary : dict
        ``results/summary.json`` (:func:`stereovar.jobs.claims.claims_job`).
    claims : list of dict
        The claims table's rows (``results/tables/claims.csv``).
    claims_text, intro : str
        The claims table's caption and a paragraph on the run (reStructuredText).
    rules : list of str
        The verdicts' rules and the intervals, as the claims table's caption states them.
    figures : list of dict
        ``name``, ``src`` (a data URI or a path relative to the page), ``caption``
        (reStructuredText) and ``group`` (the run it belongs to) of each figure.
    tables : list of dict
        ``name``, ``group`` and ``links`` (format to a path relative to the page).
    mitigations, probe : dict, optional
        When they have run: ``rows`` (the mitigation table's rows) and ``lines``
        (:func:`stereovar.statistics.mitigations.mitigation_findings`), or ``paragraph``
        (probe); ``figure`` (as in ``figures``, or None) and ``tables`` (as in ``tables``).
    generators : dict, optional
        When the ``generators`` target has run: ``rows``
        (:func:`stereovar.statistics.generators.compact_table`), ``figure`` and ``tables``.
    report : str, optional
        Snakemake's report relative to the page, when it exists.
    report_command : str, optional
        The command that makes the report.
    calibration : str, optional
        The calibration's sentence (:func:`stereovar.calibration.summary.headline`).
    nulls : list of dict, optional
        The calibration's matched nulls (``calibration_nulls.csv``): with them the headline
        is the Monte Carlo-specific :math:`\\rho` (:func:`matched_headline`).
    claim_statistics : dict, optional
        Claim id to the (region, method) of the :math:`\\rho` it tests
        (:func:`explained_statistics`).
    docs : dict, optional
        Documentation addresses by topic (``page``, ``calibration``, ``mitigations``,
        ``probe``, ``generators``; :func:`stereovar.links.docs_page`).
    own_scale : iterable of str, optional
        Ids of the claims whose paper value is in the paper's own units (:func:`claim_cells`).
    provenance : dict, optional
        :func:`stereovar.provenance.provenance` of the page.
    """
    statistics = list(summary.get("statistics") or [])
    tally: dict[str, int] = {}
    for row in claims:
        tally[str(row.get("verdict", ""))] = tally.get(str(row.get("verdict", "")), 0) + 1
    scenes = list(summary.get("scenes") or [])
    explained = explained_statistics(claims, claim_statistics or {})
    matched = matched_headline(statistics, nulls or [], scenes=scenes or None)
    warp = headline(statistics)
    mitigation_section = None
    if mitigations:
        from ..statistics.mitigations import mitigation_findings

        rows = list(mitigations.get("rows") or [])
        table = mitigation_rows(rows)
        columns = [c for c in MITIGATION_COLUMNS
                   if c != "ships" or any(r["ships"] != "as measured" for r in table)]
        findings = mitigation_findings(rows) if rows else list(mitigations.get("lines") or [])
        n_rows = len([r for r in rows if r.get("region") == "all"])
        mitigation_section = {
            "rows": table,
            "columns": columns,
            "labels": MITIGATION_COLUMNS,
            "summary": (findings[n_rows:] if rows else findings) + [
                f"What removes it (dose-response, dose_response.md): {line}"
                for line in mitigations.get("dose") or []],
            "figure": mitigations.get("figure"),
            "tables": _labelled(mitigations.get("tables") or []),
        }
    if probe:
        probe = {**probe, "tables": _labelled(probe.get("tables") or [])}
    if generators:
        generators = {**generators, **_generator_table(generators.get("rows") or []),
                      "tables": _labelled(generators.get("tables") or [])}
    return {
        "title": "stereovar: results of this run",
        "conclusion": conclusion(matched, warp, explained),
        "run": {
            "renderer": summary.get("renderer", ""),
            "estimator": summary.get("estimator", ""),
            "scenes": scenes,
            "spp": summary.get("spp"),
            "n_seeds": summary.get("n_seeds"),
            "config_digest": str(summary.get("config_digest") or ""),
        },
        "intro": intro,
        "headline": warp,
        "matched": matched,
        "explained": explained,
        "interval": INTERVAL_NOTE,
        "provenance": dict(provenance or {}),
        "controls": control_rows(statistics, matched, explained),
        "control_notes": [(group, note) for group, note, _ in CONTROL_GROUPS],
        "tally": tally,
        "claims": [claim_cells(r, rho=r.get("id") in (claim_statistics or {}),
                               own_scale=r.get("id") in set(own_scale)) for r in claims],
        "claims_text": claims_text,
        "rules": list(rules),
        "figures": list(figures),
        "mitigations": mitigation_section,
        "probe": probe,
        "generators": generators,
        "tables": _labelled(tables),
        "report": report,
        "report_command": report_command,
        "calibration": calibration,
        "calibration_links": next(
            (t["links"] for t in tables if t["name"] == "calibration" and t.get("links")), {}
        ),
        "docs": dict(docs or {}),
    }


def _labelled(tables: list[dict]) -> list[dict]:
    """``tables`` with each one's label (:data:`TABLE_LABELS`)."""
    return [{**t, "label": TABLE_LABELS.get(t["name"], readable(t["name"]))} for t in tables]


def _generator_table(rows: list[dict]) -> dict:
    """The generator table's columns, without a probe column that says only "not run"."""
    from ..statistics.generators import PROBE_NOT_RUN

    columns = list(rows[0]) if rows else []
    probe_not_run = bool(rows) and all(r.get("probe") == PROBE_NOT_RUN for r in rows)
    if probe_not_run:
        columns.remove("probe")
    labels = {c: c.replace("rho", "ρ") for c in columns}
    return {"columns": columns, "labels": labels, "probe_not_run": probe_not_run}


def to_html_page(s: dict) -> str:
    """The page as one self-contained HTML document (``results.html.j2``, no script)."""
    from ..provenance import provenance_line
    from .templates import render

    return render("results.html.j2", s=s, title=s["title"], band=CLAIMS_BAND,
                  regions=REGIONS, provenance=provenance_line(s.get("provenance") or {}))
