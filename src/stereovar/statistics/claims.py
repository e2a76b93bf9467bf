"""The claims table: which of the paper's quantitative claims hold on the scenes run.

The claims are data: ``claims.yaml`` beside this module (schema
``stereovar/schemas/claims.schema.yaml``) gives, per claim, its id, text, section of the paper,
the paper's value, its kind and rule settings, the statistic it is tested on and the bearing
control. :func:`load_claims` reads and validates it; :func:`claims_table` computes each claim's
statistic and control (:data:`STATISTICS`) on a run and gives one row per claim with a verdict
of :func:`verdict`, whose rules the file states for the table's caption
(:meth:`Claims.caption`):

* **level** claims (a value, e.g. :math:`\\rho = 0.754`): *not testable at this scale* when
  ours or its interval is undefined; *does not hold* when the paper's value is outside our
  interval; *not testable at this scale* when the interval contains the null too (no effect,
  :math:`\\rho = 0`: the data cannot tell the claim from no effect); *explained by a control*
  when the control's interval reaches ours (its upper end at or above our lower end: a camera
  or an unrelated alignment gives as much); *holds* otherwise;
* **ratio** claims (e.g. glass variance :math:`7\\times` non-glass): the level rule with the
  null 1, on the geometric mean over scenes and the exponentiated Student-t interval of the
  per-scene log ratios (:func:`geometric_t_interval`); a scene with a ratio that is not
  positive has no logarithm, and the claim is *not testable* with that scene named;
* **direction** claims (a sign, e.g. Table 3's normal minus decorrelated): *not testable at
  this scale* when our interval spans 0; *does not hold* when it lies on the other side;
  *explained by a control* when the control's interval lies on the paper's side too;
  *holds* otherwise;
* **tolerance** claims (a relative change within the paper's :math:`\\pm t`): *not testable
  at this scale* when undefined; *holds* when :math:`|\\text{ours}| \\le t`; *does not hold*
  otherwise.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy import stats

from ..errors import ClaimsError
from ..schema import load_yaml
from .across import combined_interval, rows_interval

HOLDS = "holds"
FAILS = "does not hold"
EXPLAINED = "explained by a control"
UNTESTABLE = "not testable at this scale"

KINDS = ("level", "ratio", "direction", "tolerance")
"""The kinds of claim, in the order the caption states their rules."""

NULLS = {"level": 0.0, "ratio": 1.0}
"""The no-effect value of a level claim (:math:`\\rho = 0`) and of a ratio claim (1), used by
:func:`verdict` when the claim does not state its own."""

CLAIMS_PATH = Path(__file__).resolve().with_name("claims.yaml")
"""The paper's claims, shipped with the package."""

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "claims.schema.yaml"

CLAIMS_COLUMNS = [
    "id",
    "claim",
    "section",
    "kind",
    "paper",
    "null",
    "ours",
    "ours_low",
    "ours_high",
    "control",
    "control_value",
    "control_low",
    "control_high",
    "verdict",
    "note",
]

_NAN3 = (math.nan,) * 3


def _ok(*values) -> bool:
    return all(v is not None and math.isfinite(float(v)) for v in values)


def verdict(
    kind: str,
    paper: float,
    ours,
    low,
    high,
    control=_NAN3,
    *,
    control_explains: bool = True,
    null_value: float | None = None,
) -> str:
    """The verdict of one claim (the rules of the module docstring).

    Parameters
    ----------
    kind : {"level", "ratio", "direction", "tolerance"}
    paper : float
        The paper's value: a level, a ratio, the signed effect of a direction claim (only its
        sign counts) or the tolerance of a tolerance claim.
    ours, low, high : float
        Our value and its 95% interval (a ratio's on the ratio scale).
    control : tuple (value, low, high)
        The bearing control.
    control_explains : bool, keyword-only
        Whether the control can explain the claim away (False when it is shown for context).
    null_value : float, keyword-only, optional
        The no-effect value a level or ratio interval must exclude (default :data:`NULLS`).
    """
    _, c_low, c_high = control
    if kind == "tolerance":
        if not _ok(ours, paper):
            return UNTESTABLE
        return HOLDS if abs(float(ours)) <= float(paper) else FAILS
    if kind not in KINDS:
        raise ValueError(f"unknown claim kind {kind!r}")
    if not _ok(ours, low, high):
        return UNTESTABLE
    if kind in NULLS:
        null = NULLS[kind] if null_value is None else float(null_value)
        if not low <= paper <= high:
            return FAILS
        if low <= null <= high:
            return UNTESTABLE
        if control_explains and _ok(c_high) and c_high >= low:
            return EXPLAINED
        return HOLDS
    side = math.copysign(1.0, paper)
    if low <= 0 <= high:
        return UNTESTABLE
    if (low > 0) != (side > 0):
        return FAILS
    if control_explains and _ok(c_low, c_high):
        if (c_low > 0 and side > 0) or (c_high < 0 and side < 0):
            return EXPLAINED
    return HOLDS


def t_interval(values) -> tuple[float, float, float]:
    """Mean of the finite values and its 95% Student-t interval (NaN below 2 values)."""
    v = np.asarray([float(x) for x in values], dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, math.nan
    mean = float(v.mean())
    if v.size < 2:
        return mean, math.nan, math.nan
    half = float(stats.t.ppf(0.975, v.size - 1) * v.std(ddof=1) / math.sqrt(v.size))
    return mean, mean - half, mean + half


def geometric_t_interval(ratios) -> tuple[float, float, float]:
    """Geometric mean of positive ratios and its 95% interval from their logarithms.

    .. math::

        \\bar\\ell = \\frac1S \\sum_s \\log r_s, \\qquad
        \\exp\\bar\\ell, \\quad
        \\exp\\!\\left(\\bar\\ell \\pm t_{0.975,\\,S-1}\\,\\frac{s_\\ell}{\\sqrt S}\\right)

    (:func:`t_interval` of the logs, exponentiated): never below 0, and symmetric in a ratio
    and its inverse. Equal ratios give that ratio with a zero-width interval, exactly (no
    log and exp round trip to move it by an ulp). NaN when there are none; a NaN interval
    below 2 ratios.

    Parameters
    ----------
    ratios : sequence of float
        Per-scene ratios, each finite and > 0.

    Raises
    ------
    ValueError
        If a ratio is not finite or not positive (it has no logarithm).
    """
    r = np.asarray([float(x) for x in ratios], dtype=np.float64)
    bad = r[~(np.isfinite(r) & (r > 0))]
    if bad.size:
        raise ValueError(f"ratio {bad[0]!r} has no logarithm; every ratio must be finite and > 0")
    if r.size >= 2 and np.all(r == r[0]):
        return float(r[0]), float(r[0]), float(r[0])
    mean, low, high = t_interval(np.log(r))
    return math.exp(mean), math.exp(low), math.exp(high)


# ------------------------------------------------------------------------------ statistics


class ClaimInputs(NamedTuple):
    """What a claim's statistic is computed from: every scene's correlation rows at the main
    SPP, Table 2's rows, the seed-subset curve rows and the intervention rows."""

    rows: list
    sweep: list
    curve: list
    intervention: list


class Estimate(NamedTuple):
    """A statistic's value with its 95% interval, and why it is undefined or what it left
    out (empty when nothing)."""

    value: float
    low: float
    high: float
    note: str = ""


def _per_scene(rows, key: str, value=lambda r: r) -> dict:
    """Scene to ``{row[key]: value(row)}``, scenes in first-seen order."""
    out: dict = {}
    for r in rows:
        out.setdefault(r.get("scene"), {})[r[key]] = value(r)
    return out


def _select(rows, region, method):
    return [r for r in rows if r["region"] == region and r["method"] == method]


def _rho(inputs: ClaimInputs, *, region, method) -> Estimate:
    """Mean :math:`\\rho` over scenes with the scenes' bootstrap intervals combined."""
    return Estimate(*rows_interval(_select(inputs.rows, region, method)))


def _rho_difference(inputs: ClaimInputs, *, region, minus, method) -> Estimate:
    """Mean over scenes of :math:`\\rho_{region} - \\rho_{minus}`, each scene's half-width
    the root sum of squares of the two bootstrap intervals' half-widths, combined."""
    selected = [r for r in inputs.rows if r["method"] == method and r["region"] in (region, minus)]
    diffs, lows, highs = [], [], []
    for pair in _per_scene(selected, "region").values():
        a, b = pair.get(region), pair.get(minus)
        if not a or not b or not _ok(a["rho"], b["rho"]):
            continue
        diffs.append(float(a["rho"]) - float(b["rho"]))
        half = (
            math.hypot(
                float(a["boot_high"]) - float(a["boot_low"]),
                float(b["boot_high"]) - float(b["boot_low"]),
            )
            / 2
        )
        lows.append(diffs[-1] - half)
        highs.append(diffs[-1] + half)
    return Estimate(*combined_interval(diffs, lows, highs))


def _sweep_spread(inputs: ClaimInputs, *, column) -> Estimate:
    """Relative spread of Table 2's ``column`` over the SPP sweep, (max - min) / |mean|; no
    interval."""
    rho = np.array([float(r.get(column, math.nan)) for r in inputs.sweep], dtype=np.float64)
    rho = rho[np.isfinite(rho)]
    if rho.size < 2:
        return Estimate(*_NAN3)
    return Estimate(float((rho.max() - rho.min()) / abs(rho.mean())), math.nan, math.nan)


def _seed_change(inputs: ClaimInputs, *, region, method) -> Estimate:
    """Mean over scenes of the relative change of :math:`\\rho` from the second-largest
    seed subset to all seeds of the seed curve, (full - half) / |full|, with a t interval."""
    selected = [r for r in inputs.curve if (r["region"], r["method"]) == (region, method)]
    changes = []
    for pts in _per_scene(selected, "n_prime", lambda r: float(r["mean_rho"])).values():
        if len(pts) < 2:
            continue
        ordered = sorted(pts, key=int)
        full, half = pts[ordered[-1]], pts[ordered[-2]]
        if _ok(full, half) and full != 0:
            changes.append((full - half) / abs(full))
    return Estimate(*t_interval(changes))


def _corrected_rho(inputs: ClaimInputs, *, region, method) -> Estimate:
    """Mean over scenes of the attenuation-corrected :math:`\\rho` with a t interval."""
    rows = _select(inputs.rows, region, method)
    return Estimate(*t_interval(float(r.get("rho_corrected", math.nan)) for r in rows))


def _region_ratio(inputs: ClaimInputs, *, column, method, numerator, denominator) -> Estimate:
    """Geometric mean over scenes of ``column`` in region ``numerator`` over region
    ``denominator`` (:func:`geometric_t_interval`).

    A scene without a finite value in either region (e.g. no glass) is left out and named in
    the note. A scene whose ratio is not positive and finite has no logarithm: the estimate
    is then NaN with those scenes and their values in the note, rather than a geometric mean
    of the other scenes only, which would leave out the scenes that contradict the claim.
    """
    selected = [
        r for r in inputs.rows if r["method"] == method and r["region"] in (numerator, denominator)
    ]
    ratios, refused, missing = [], [], []
    values = _per_scene(selected, "region", lambda r: float(r.get(column, math.nan)))
    for scene, means in values.items():
        a, b = means.get(numerator, math.nan), means.get(denominator, math.nan)
        if not _ok(a, b):
            missing.append(str(scene))
            continue
        ratio = a / b if b != 0 else math.inf
        if a > 0 and b > 0 and math.isfinite(ratio) and ratio > 0:
            ratios.append(ratio)
        else:
            refused.append(f"{scene} ({numerator} {a:g}, {denominator} {b:g})")
    if refused:
        return Estimate(
            *_NAN3,
            f"{column} ratio not positive in {', '.join(refused)}: it has no logarithm, so no "
            "geometric mean",
        )
    note = f"left out, no finite {column}: {', '.join(missing)}" if missing else ""
    if not ratios:
        return Estimate(*_NAN3, note)
    return Estimate(*geometric_t_interval(ratios), note)


def _intervention_effect(inputs: ClaimInputs, *, cost, metric, region, source) -> Estimate:
    """Mean over scenes of normal minus decorrelated for one Table 3 cell, with a t
    interval (rows of ``source``: ``render`` or ``sensor``; no ``source`` is ``render``)."""
    selected = [
        r
        for r in inputs.intervention
        if (r["cost"], r["metric"], r["region"]) == (cost, metric, region)
        and str(r.get("source") or "render") == source
    ]
    diffs = [
        float(c["normal"]) - float(c["decorrelated"])
        for c in _per_scene(selected, "condition", lambda r: r["value"]).values()
        if "normal" in c and "decorrelated" in c and _ok(c["normal"], c["decorrelated"])
    ]
    return Estimate(*t_interval(diffs))


def _regions():
    from .regions import REGIONS

    return REGIONS


def _methods():
    from .registry import METHODS

    return METHODS.names()


def _sweep_columns():
    return tuple(f"rho_{r}" for r in _regions())


def _row_columns():
    from .correlation import RESULT_KEYS

    return tuple(k for k in RESULT_KEYS if k != "reason")


def _costs():
    from ..intervention.metrics import COSTS

    return tuple(COSTS)


def _metrics():
    from ..intervention.metrics import COSTS

    return tuple(dict.fromkeys(m for ms in COSTS.values() for m in ms))


def _intervention_regions():
    from ..intervention.metrics import REGIONS

    return REGIONS


def _two_regions(settings, first="region", second="minus") -> str | None:
    if settings[first] == settings[second]:
        return f"{first} and {second} are both {settings[first]!r}; give two different regions"
    return None


def _metric_of_cost(settings) -> str | None:
    from ..intervention.metrics import COSTS

    metrics = COSTS[settings["cost"]]
    if settings["metric"] not in metrics:
        return (
            f"metric {settings['metric']!r} is not reported for cost {settings['cost']!r}; "
            f"use one of {', '.join(metrics)}"
        )
    return None


@dataclass(frozen=True)
class Statistic:
    """A statistic a claim can be tested on.

    Attributes
    ----------
    compute : callable
        ``compute(inputs, **settings) -> Estimate``.
    settings : dict
        Each setting's name to a function giving its allowed values.
    check : callable, optional
        ``check(settings) -> message or None``: a rule across settings.
    """

    compute: Callable[..., Estimate]
    settings: dict = field(default_factory=dict)
    check: Callable[[dict], str | None] | None = None


STATISTICS = {
    "rho": Statistic(_rho, {"region": _regions, "method": _methods}),
    "rho_difference": Statistic(
        _rho_difference,
        {"region": _regions, "minus": _regions, "method": _methods},
        _two_regions,
    ),
    "sweep_spread": Statistic(_sweep_spread, {"column": _sweep_columns}),
    "seed_change": Statistic(_seed_change, {"region": _regions, "method": _methods}),
    "corrected_rho": Statistic(_corrected_rho, {"region": _regions, "method": _methods}),
    "region_ratio": Statistic(
        _region_ratio,
        {
            "column": _row_columns,
            "method": _methods,
            "numerator": _regions,
            "denominator": _regions,
        },
        lambda s: _two_regions(s, "numerator", "denominator"),
    ),
    "intervention_effect": Statistic(
        _intervention_effect,
        {
            "cost": _costs,
            "metric": _metrics,
            "region": _intervention_regions,
            "source": lambda: ("render", "sensor"),
        },
        _metric_of_cost,
    ),
}
"""What a claim in ``claims.yaml`` can be tested on (its ``statistic: {name: ...}``)."""


def _estimate(statistic: dict, inputs: ClaimInputs) -> Estimate:
    settings = {k: v for k, v in statistic.items() if k != "name"}
    return STATISTICS[statistic["name"]].compute(inputs, **settings)


# ------------------------------------------------------------------------------ the file


@dataclass(frozen=True)
class Claims:
    """A validated claims file.

    Attributes
    ----------
    claims : tuple of dict
        One per claim, in the table's order (the keys of ``claims.schema.yaml``).
    rules : dict
        Each kind's verdict rule, in words.
    intervals : str
        How the intervals are made, in words.
    path : str
        The file read.
    sha256 : str
        The SHA-256 of the bytes the claims were read from.
    """

    claims: tuple
    rules: dict
    intervals: str
    path: str
    sha256: str

    def caption(self) -> str:
        """The rules and intervals, as the claims table's caption states them."""
        return " ".join(["Verdicts.", *(self.rules[k] for k in KINDS), self.intervals])


@lru_cache(maxsize=1)
def _validator():
    import jsonschema
    import yaml

    schema = yaml.safe_load(SCHEMA_PATH.read_text(encoding="utf-8"))
    return jsonschema.validators.validator_for(schema)(schema)


def _key(path, data) -> str:
    """A dotted key, claims named by index and id: ``claims[7] (glass_ratio).paper``."""
    parts, node = [], data
    for p in path:
        if isinstance(p, int):
            name = node[p].get("id") if isinstance(node[p], dict) else None
            index = f"[{p}]" + (f" ({name})" if isinstance(name, str) else "")
            if parts:
                parts[-1] += index
            else:
                parts.append(index)
        else:
            parts.append(str(p))
        node = node[p]
    return ".".join(parts) if parts else "(top level)"


def _one_line(text: str, limit: int = 200) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _check_claim(index: int, claim: dict, seen: dict) -> tuple[list, str] | None:
    """The first rule across keys ``claim`` breaks: ``(key path, problem)``, or None."""
    kind, paper, rule = claim["kind"], claim["paper"], claim["rule"]
    where = ["claims", index]
    if claim["id"] in seen:
        return where + ["id"], f"{claim['id']!r} is also the id of claims[{seen[claim['id']]}]"
    seen[claim["id"]] = index
    if not math.isfinite(paper):
        return where + ["paper"], f"{paper!r} is not a finite number"
    if kind in NULLS:
        if "null_value" not in rule:
            return where + ["rule"], (
                f"a {kind} claim needs null_value, the no-effect value its interval must "
                f"exclude ({NULLS[kind]:g} for a {kind})"
            )
        if not math.isfinite(rule["null_value"]):
            return where + ["rule", "null_value"], f"{rule['null_value']!r} is not finite"
    elif "null_value" in rule:
        return where + ["rule", "null_value"], (
            f"a {kind} claim has no null_value (its rule is fixed); remove it"
        )
    if kind == "ratio" and not (paper > 0 and rule["null_value"] > 0):
        return where + ["paper"], "a ratio claim's paper value and null_value must be > 0"
    if kind == "direction" and paper == 0:
        return where + ["paper"], "a direction claim's paper value must be non-zero (its sign)"
    if kind == "tolerance" and paper <= 0:
        return where + ["paper"], "a tolerance claim's paper value (the tolerance) must be > 0"
    parts = [("statistic", claim["statistic"])]
    if claim["control"] is not None:
        parts.append(("control", claim["control"]["statistic"]))
        if claim["control"]["statistic"] == claim["statistic"]:
            return where + ["control", "statistic"], "the control is the claim's own statistic"
    for part, statistic in parts:
        at = where + ([part] if part == "statistic" else [part, "statistic"])
        name = statistic["name"]
        if name not in STATISTICS:
            return at + ["name"], (
                f"unknown statistic {name!r}; use one of {', '.join(STATISTICS)}"
            )
        spec = STATISTICS[name]
        settings = {k: v for k, v in statistic.items() if k != "name"}
        for key in spec.settings:
            if key not in settings:
                return at, f"statistic {name!r} needs the setting {key!r}"
        for key, value in settings.items():
            if key not in spec.settings:
                return at + [key], (
                    f"statistic {name!r} has no setting {key!r}; its settings: "
                    f"{', '.join(spec.settings)}"
                )
            allowed = spec.settings[key]()
            if value not in allowed:
                return at + [key], f"{value!r} is not allowed; use one of {', '.join(allowed)}"
        problem = spec.check(settings) if spec.check else None
        if problem:
            return at, problem
    return None


def load_claims(path=None) -> Claims:
    """Read and validate a claims file.

    Parameters
    ----------
    path : str or path-like, optional
        The file (default :data:`CLAIMS_PATH`, the paper's claims).

    Raises
    ------
    ClaimsError
        One line naming the file, the key and the problem, when the file is missing, not
        YAML, or breaks ``claims.schema.yaml`` or a rule across keys (unique ids, a level or
        ratio claim's null_value, a known statistic with its settings).
    """
    path = Path(CLAIMS_PATH if path is None else path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise ClaimsError(
            f"claims file '{path}' cannot be read: {err.strerror}; restore it "
            "(git checkout the package's statistics/claims.yaml) or pass an existing file"
        ) from None
    data = load_yaml(path, "claims file", error=ClaimsError)
    if raw != path.read_bytes():
        raise ClaimsError(f"claims file '{path}' changed while it was read; run again")

    def fail(key_path, problem):
        raise ClaimsError(f"{path}: {_key(key_path, data)}: {_one_line(problem)}; fix that key")

    import jsonschema

    error = jsonschema.exceptions.best_match(_validator().iter_errors(data))
    if error is not None:
        fail(list(error.absolute_path), error.message)
    seen: dict = {}
    for index, claim in enumerate(data["claims"]):
        problem = _check_claim(index, claim, seen)
        if problem:
            fail(*problem)
    return Claims(
        claims=tuple(data["claims"]),
        rules=dict(data["rules"]),
        intervals=data["intervals"],
        path=str(path),
        sha256=hashlib.sha256(raw).hexdigest(),
    )


def claims_digest(path=None) -> str:
    """SHA-256 of a claims file's bytes (default :data:`CLAIMS_PATH`), without validating
    it: the claims job's rerun trigger."""
    return hashlib.sha256(Path(CLAIMS_PATH if path is None else path).read_bytes()).hexdigest()


# ------------------------------------------------------------------------------ the table


def _claim_row(claim: dict, inputs: ClaimInputs, *, moments: bool) -> dict:
    ours = _estimate(claim["statistic"], inputs)
    control = claim["control"]
    theirs = _estimate(control["statistic"], inputs) if control else Estimate(*_NAN3)
    label = ""
    if control:
        label = control.get("label_moments", control["label"]) if moments else control["label"]
    rule = claim["rule"]
    notes = [ours.note, f"control: {theirs.note}" if theirs.note else ""]
    return {
        "id": claim["id"],
        "claim": claim["text"],
        "section": claim["section"],
        "kind": claim["kind"],
        "paper": claim["paper"],
        "null": rule.get("null_value", math.nan),
        "ours": ours.value,
        "ours_low": ours.low,
        "ours_high": ours.high,
        "control": label,
        "control_value": theirs.value,
        "control_low": theirs.low,
        "control_high": theirs.high,
        "verdict": verdict(
            claim["kind"],
            claim["paper"],
            ours.value,
            ours.low,
            ours.high,
            theirs[:3],
            control_explains=rule.get("control_explains", True),
            null_value=rule.get("null_value"),
        ),
        "note": "; ".join(n for n in notes if n),
    }


def claims_table(
    rows: list[dict],
    *,
    sweep: list[dict] | None = None,
    curve: list[dict] | None = None,
    intervention: list[dict] | None = None,
    claims: Claims | None = None,
) -> list[dict]:
    """The claims of the paper against this run (columns :data:`CLAIMS_COLUMNS`), one row
    per claim of ``claims`` in its order.

    Parameters
    ----------
    rows : list of dict
        Every scene's correlation rows at the main SPP.
    sweep : list of dict, optional
        Table 2 rows (``spp``, ``rho_all``).
    curve : list of dict, optional
        Every scene's seed-subset curve rows (:func:`stereovar.statistics.rows.seed_curve_rows`).
    intervention : list of dict, optional
        Every scene's intervention rows (``cost``, ``metric``, ``region``, ``condition``,
        ``value`` and optionally ``source``: ``render`` or ``sensor``).
    claims : Claims, keyword-only, optional
        The claims (default :func:`load_claims` of the paper's).
    """
    claims = load_claims() if claims is None else claims
    inputs = ClaimInputs(list(rows), list(sweep or []), list(curve or []), list(intervention or []))
    from ..estimators import reads_moments

    moments = any(reads_moments(r.get("estimator")) for r in rows)
    return [_claim_row(c, inputs, moments=moments) for c in claims.claims]
