"""The claims table: which of the paper's quantitative claims hold on the scenes run.

The claims are data: ``claims.yaml`` beside this module (schema
``stereovar/schemas/claims.schema.yaml``) gives, per claim, its id, text, section of the paper,
the paper's value, its kind and rule settings, the statistic it is tested on and the bearing
control. :func:`load_claims` reads and validates it; :func:`claims_table` computes each claim's
statistic and control (:data:`~stereovar.statistics.claim_statistics.STATISTICS`) on a run and
gives one row per claim with a verdict of :func:`~stereovar.statistics.claim_rules.verdict`,
whose rules the file states for the table's caption (:meth:`Claims.caption`). Every interval is
95% and, for a level, is for the mean over scenes like those run
(:func:`~stereovar.statistics.across.random_effects_interval`: the variance between scenes is
counted; one scene gives no interval; for a mean :math:`\\rho`, on Fisher's :math:`z`,
:func:`~stereovar.statistics.across.random_effects_correlation_interval`). The rules of each
kind of claim, and of equivalence, are stated in :mod:`stereovar.statistics.claim_rules`.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ..errors import ClaimsError
from ..schema import load_yaml
from .claim_rules import _NAN3, KINDS, NULLS, _ok, verdict
from .claim_statistics import STATISTICS, ClaimInputs, Estimate, estimate

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
        """The rules of each kind of claim and how the intervals are made, from the file's
        ``rules`` and ``intervals``, as the claims table's caption states them."""
        return " ".join(
            ["Verdicts, by kind of claim:", *(self.rules[k] for k in KINDS), self.intervals]
        )


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
    margin = rule.get("equivalence_margin")
    if margin is not None:
        if kind != "level":
            return where + ["rule", "equivalence_margin"], (
                f"a {kind} claim has no equivalence_margin"
                + (" (its margin is its tolerance, paper)" if kind == "tolerance" else "")
                + "; remove it"
            )
        if not (math.isfinite(margin) and margin > 0):
            return where + ["rule", "equivalence_margin"], f"{margin!r} must be finite and > 0"
        if claim["control"] is not None and rule.get("control_explains", True):
            return where + ["rule"], (
                "an equivalence claim's control is shown for context; set control_explains: false"
            )
    elif kind == "ratio" and paper == rule["null_value"]:
        return where + ["paper"], (
            f"the paper's value {paper:g} is the null, which a ratio claim's interval must "
            "exclude, so it could never hold; equivalence margins are for level claims"
        )
    elif kind == "level" and paper == rule["null_value"]:
        return where + ["rule"], (
            f"the paper's value {paper:g} is the null, which an interval that must exclude "
            "the null can never confirm; give equivalence_margin, the largest departure "
            "from it that still counts as the claim"
        )
    share = rule.get("control_share")
    if share is not None:
        if not rule.get("control_explains", True) or claim["control"] is None:
            return where + ["rule", "control_share"], (
                "control_share needs a control that can explain the claim "
                "(control_explains: true); remove it"
            )
        if kind == "tolerance":
            return where + ["rule", "control_share"], (
                "a tolerance claim's control is shown for context; remove it"
            )
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
        ratio claim's null_value, an equivalence_margin where the paper's value is the null
        and only on level claims, control_share only where a control can explain the claim,
        a known statistic with its settings).
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


def _tost_note(claim: dict, tost: Estimate) -> str:
    """The equivalence test's 90% interval and margin, for the row's note."""
    paper = float(claim["paper"])
    if claim["kind"] == "tolerance":
        centre, margin = 0.0, paper
    else:
        centre, margin = paper, float(claim["rule"]["equivalence_margin"])
    if not _ok(tost.low, tost.high):
        return f"equivalence within {centre:g} +- {margin:g} needs an interval"
    return (
        f"equivalence (two one-sided tests at 5%): 90% interval [{tost.low:.3g}, "
        f"{tost.high:.3g}] against {centre:g} +- {margin:g}"
    )


def _claim_row(claim: dict, inputs: ClaimInputs, *, moments: bool) -> dict:
    ours = estimate(claim["statistic"], inputs)
    control = claim["control"]
    theirs = estimate(control["statistic"], inputs) if control else Estimate(*_NAN3)
    label = ""
    if control:
        label = control.get("label_moments", control["label"]) if moments else control["label"]
    rule = claim["rule"]
    notes = [ours.note, f"control: {theirs.note}" if theirs.note else ""]
    tost = None
    if claim["kind"] == "tolerance" or "equivalence_margin" in rule:
        tost = estimate(claim["statistic"], inputs, level=0.90)
        notes.append(_tost_note(claim, tost))
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
            equivalence_margin=rule.get("equivalence_margin"),
            equivalence_interval=None if tost is None else (tost.low, tost.high),
            control_share=rule.get("control_share"),
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
