"""A re-render plan for a data set with one render per view: how many of its frames to render
again with two seeds per view for a stated power, which ones, and the commands.

One render per view cannot be audited (:func:`stereovar.estimators.single.refusal`); two seeds
per view can. Rendering a second seed of every frame is rarely needed: the audit combines its
frames, so its interval narrows as :math:`1/\\sqrt F` over :math:`F` frames.

**The power curve at N = 2.** On each of a few of the data set's own frames, the calibration
(:func:`stereovar.calibration.replicates.scene_calibration`, statistic ``partial``) draws
N = 2 frames per view around the render as the clean image, with its right view the left
moved by :data:`PROBE_DISPARITY` pixels, under a camera-law null and a planted cue of each
strength (as multiples of :data:`REFERENCE_STRENGTH`, the strength the default scenes'
renders show). Per strength :math:`s`, the Monte Carlo-specific difference of one frame has
mean :math:`\\delta(s)` and standard error :math:`\\sigma_1` (its interval's half-width over
:math:`z_{0.975}`, :func:`~stereovar.calibration.nulls.difference_interval`).

**Frames for a power.** Over :math:`F` frames the combined difference has standard error
:math:`\\sigma_1/\\sqrt F`, and the verdict's rule calls a cue when its interval lies above
:data:`~stereovar.calibration.rules.MIN_EFFECT` :math:`m`, so

.. math::

    P(F) = \\Phi\\Bigl(\\frac{\\sqrt F\\,(\\delta(s) - m)}{\\sigma_1} - z_{0.975}\\Bigr),
    \\qquad
    F = \\Bigl\\lceil \\Bigl(\\frac{(z_{0.975} + z_P)\\,\\sigma_1}{\\delta(s) - m}\\Bigr)^2
        \\Bigr\\rceil .

The plan takes :math:`F` frames spread evenly over the data set's sorted frame names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.special import ndtr, ndtri

from ..errors import AuditError

REFERENCE_STRENGTH = 1.0
"""The strength the plan's cue is stated in: the standard deviation of the part of
:math:`\\ln\\sigma^2` intensity does not explain, as the default scenes' renders show it
(0.99-1.03, ``docs/single_render.md``)."""

PROBE_DISPARITY = 4
"""Pixels the synthetic right view is moved by (the statistic aligns the views by it)."""

STRENGTHS = (0.125, 0.25, 0.5, 1.0, 2.0)
"""Planted strengths of the power curve, as multiples of :data:`REFERENCE_STRENGTH`."""

SNIPPET = "render_seeds.py"
"""The Blender script that renders two seeds per view (``workflow/snippets``)."""


@dataclass(frozen=True)
class PowerPoint:
    """One strength of the power curve at N = 2: the planted ``strength`` (multiple of
    :data:`REFERENCE_STRENGTH`), the mean Monte Carlo-specific difference ``delta`` of one
    frame and its standard error ``se``, and the share of single frames the rule detects in
    (``power_one``)."""

    strength: float
    delta: float
    se: float
    power_one: float


def single_render_frames(settings: dict) -> dict:
    """Frame name to ``{view: path}``: the data set's one render per view (the first seed
    where the template has a ``{seed}`` field), found by the audit's template matching.

    Raises
    ------
    AuditError
        The template matches nothing, or a frame lacks a view.
    """
    from .layout import NAME, SINGLE_FRAME, VIEWS, _root, match_template

    root = _root(settings)
    views = dict(settings.get("views") or {v: v for v in VIEWS})
    template = settings["renders"]
    matched = match_template(template, views, root)
    if not matched:
        raise AuditError(
            f"audit.renders {template!r} matches no file under {Path(root).resolve()}; fix "
            "the template, audit.views or audit.root"
        )
    frames: dict = {}
    for values, path in sorted(matched, key=lambda m: str(m[1])):
        name = values.get("frame", settings.get("frame") or SINGLE_FRAME)
        if not NAME.fullmatch(name):
            raise AuditError(f"{path}: frame name {name!r} may only contain letters, digits, _ "
                             "and -; rename the frames")
        frames.setdefault(name, {}).setdefault(values["view"], path)
    lacking = sorted(f for f, v in frames.items() if set(v) != set(VIEWS))
    if lacking:
        view = sorted(set(VIEWS) - set(frames[lacking[0]]))[0]
        raise AuditError(f"frame {lacking[0]} has no {view} view; give every frame both views")
    return dict(sorted(frames.items()))


def power_curve(image, *, strengths=STRENGTHS, replicates: int = 8, seed: int = 0,
                settings=None) -> list[PowerPoint]:
    """The power curve at N = 2 on one render used as the clean image (the module's first
    part).

    Parameters
    ----------
    image : numpy.ndarray (H, W, 3)
        One render of the data set, linear.
    """
    from ..calibration.nulls import difference_interval
    from ..calibration.rates import Z
    from ..calibration.replicates import scene_calibration
    from ..calibration.scene_frames import SceneFrames
    from ..calibration.stacks import NONE
    from ..statistics.fields import AnalysisSettings

    left = np.maximum(np.nan_to_num(np.asarray(image, dtype=np.float64)), 0.0)
    h, w = left.shape[:2]
    d = PROBE_DISPARITY
    right = np.empty_like(left)  # x_R = x_L + d: the right view sees the left's column x - d
    right[:, d:] = left[:, :-d]
    right[:, :d] = left[:, :1]
    mu = left.mean(axis=-1)
    level = float(np.median(mu[mu > 0])) if (mu > 0).any() else 1.0
    law = (0.01 * level, 1e-4 * level**2)  # any camera: the strengths are relative
    variance = {v: law[0] * m.mean(axis=-1) + law[1] for v, m in (("left", left),
                                                                   ("right", right))}
    valid = np.ones((h, w), bool)
    valid[:, w - d:] = False
    truth = {v: {"disparity": np.full((h, w), float(d)), "valid": valid} for v in ("left",
                                                                                  "right")}
    scene = SceneFrames({"left": left, "right": right}, variance, truth, np.zeros((h, w), bool),
                        1, 2, f"sample|spp{seed}")
    rows, _ = scene_calibration(
        scene, transforms=[NONE], settings=settings or AnalysisSettings(),
        replicates=int(replicates), strength_factors=list(strengths), expensive_replicates=0,
        seed=int(seed), min_strength=REFERENCE_STRENGTH, methods=("partial",),
    )
    rows = [r for r in rows if r["method"] == "partial" and r["region"] == "all"]
    null = [r["rho"] for r in rows if r["kind"] == "camera" and math.isfinite(r["rho"])]
    null_mean = float(np.mean(null))
    null_se = float(np.std(null, ddof=1) / math.sqrt(len(null)))
    out = []
    for s in strengths:
        diffs = [difference_interval(r["rho"], r["boot_low"], r["boot_high"], null_mean, null_se,
                                     r["chance_se"])
                 for r in rows if r["kind"] == "planted" and r["strength_factor"] == s]
        diffs = [x for x in diffs if all(math.isfinite(v) for v in x)]
        if not diffs:
            continue
        d_, lo, hi = (np.asarray(x) for x in zip(*diffs, strict=True))
        from ..calibration.rules import MIN_EFFECT

        out.append(PowerPoint(float(s), float(d_.mean()), float(np.mean((hi - lo) / (2 * Z))),
                              float(np.mean(lo > MIN_EFFECT))))
    return out


def frames_for_power(curve: list[PowerPoint], strength: float, power: float) -> tuple:
    """Frames :math:`F` for ``power`` at ``strength`` (the module's equation, with
    :math:`\\delta` and :math:`\\sigma_1` interpolated in the strength's logarithm), and the
    power those frames give; ``(None, 0.0)`` when the cue's difference does not exceed the
    rule's minimum at that strength.

    Examples
    --------
    >>> curve = [PowerPoint(0.5, 0.10, 0.05, 0.2), PowerPoint(1.0, 0.30, 0.05, 1.0)]
    >>> frames, achieved = frames_for_power(curve, 1.0, 0.8)
    >>> frames, round(achieved, 3)
    (1, 0.999)
    >>> frames_for_power(curve, 0.5, 0.8)[0]  # (1.96 + 0.84)^2 (0.05 / 0.05)^2 = 7.85
    8
    """
    from ..calibration.rates import Z
    from ..calibration.rules import MIN_EFFECT

    xs = np.log([p.strength for p in curve])
    delta = float(np.interp(math.log(strength), xs, [p.delta for p in curve]))
    se = float(np.interp(math.log(strength), xs, [p.se for p in curve]))
    if delta <= MIN_EFFECT or se <= 0:
        return None, 0.0
    frames = max(1, math.ceil(((Z + float(ndtri(power))) * se / (delta - MIN_EFFECT))
                              ** 2))
    return frames, power_at(curve, strength, frames)


def spread(names: list[str], count: int) -> list[str]:
    """``count`` names spread evenly over ``names`` (all of them when ``count`` is larger).

    Examples
    --------
    >>> spread([f"f{i}" for i in range(10)], 3)
    ['f0', 'f4', 'f9']
    """
    if count >= len(names):
        return list(names)
    index = np.unique(np.round(np.linspace(0, len(names) - 1, count)).astype(int))
    return [names[i] for i in index]


def snippet_path() -> Path:
    """The Blender script of :data:`SNIPPET` in the workflow's folder (the repository's or the
    installed package's, :func:`stereovar.workflow_home.workflow_root`)."""
    from ..workflow_home import workflow_root

    return Path(workflow_root()) / "workflow" / "snippets" / SNIPPET


def plan(settings: dict, *, strength: float = 1.0, power: float = 0.8, probe_frames: int = 2,
         replicates: int = 8, seed: int = 0) -> dict:
    """The re-render plan of a one-render data set (the module's equations): its frames, the
    power curve at N = 2 measured on ``probe_frames`` of them, the frame count for ``power``
    at ``strength`` and the frames chosen.

    Raises
    ------
    AuditError
        The data set's frames cannot be read, or no frame count reaches ``power`` at
        ``strength`` (the cue is then below what N = 2 can show; the message names the
        smallest strength that can).
    """
    from ..io.images import read_image

    if not 0.5 <= power < 1.0:
        raise AuditError(f"--power must be in [0.5, 1), got {power}")
    if strength <= 0:
        raise AuditError(f"--strength must be above 0, got {strength}")
    frames = single_render_frames(settings)
    names = list(frames)
    channel = (settings.get("channels") or {}).get("render")
    curves = []
    for name in spread(names, probe_frames):
        image = read_image(frames[name]["left"], channel=channel,
                           transfer=settings.get("transfer"),
                           scale=float(settings.get("scale") or 1.0))
        curves.append(power_curve(image, replicates=replicates, seed=seed))
    # the frames' curves pooled: each strength's mean difference and standard error
    curve = [PowerPoint(p.strength, float(np.mean([c[i].delta for c in curves])),
                        float(np.sqrt(np.mean([c[i].se ** 2 for c in curves]))),
                        float(np.mean([c[i].power_one for c in curves])))
             for i, p in enumerate(curves[0])]
    count, achieved = frames_for_power(curve, strength, power)
    if count is None:
        weakest = next((p.strength for p in curve
                        if frames_for_power(curve, p.strength, power)[0] is not None), None)
        raise AuditError(
            f"no number of frames detects a cue of {strength:g}x the reference strength with "
            f"N = 2 (its difference does not exceed the rule's minimum); "
            + (f"ask for {weakest:g}x or more" if weakest else "render more seeds per view")
        )
    chosen = spread(names, count)
    return {"frames": names, "chosen": chosen, "needed": count, "strength": float(strength),
            "power": float(power), "achieved": power_at(curve, strength, len(chosen)),
            "probe_frames": spread(names, probe_frames), "curve": curve}


def write_plan(result: dict, settings: dict, out, *, blend: str | None = None,
               seeds: int = 2) -> dict:
    """Write the plan to the folder ``out``: ``plan.yaml`` (every number), ``plan.md`` (the
    same for a reader), ``render.sh`` (per chosen frame, the Blender command that renders
    ``seeds`` seeds per view of its scene with the scene's own settings, keeping the render
    before the denoiser where the denoiser is on), the script it runs and ``audit.yaml``,
    which audits the re-rendered sample. ``blend``: each frame's scene file, with a
    ``{frame}`` field (else the commands name ``SCENE_OF_<frame>.blend`` to replace). Each
    file is written whole or not at all.

    Returns
    -------
    dict
        Name to the path of each file written.
    """
    import shlex
    import shutil

    import yaml

    from ..io.store import write_file

    out = Path(out).resolve()  # the commands and the audit run from anywhere
    out.mkdir(parents=True, exist_ok=True)
    baseline = settings.get("baseline_m")
    if baseline is None:
        raise AuditError("the data set's audit: section has no baseline_m; give the rig's "
                         "baseline (audit.baseline_m, metres) so the plan renders the same rig")
    renders = out / "renders"
    commands = []
    for frame in result["chosen"]:
        scene = (str(Path(blend.format(frame=frame)).resolve()) if blend
                 else f"SCENE_OF_{frame}.blend")
        commands.append({
            "frame": frame, "blend": scene,
            "command": shlex.join(["blender", "-b", scene, "-P", str(out / SNIPPET), "--",
                                   str(renders / frame), str(seeds), repr(float(baseline))]),
        })
    curve = [{"strength": p.strength, "difference": p.delta, "se": p.se,
              "power_one_frame": p.power_one} for p in result["curve"]]
    record = {
        "frames_in_data_set": len(result["frames"]),
        "frames_to_render": len(result["chosen"]),
        "frames_needed": int(result["needed"]),
        "strength": result["strength"],
        "power_asked": result["power"],
        "power": result["achieved"],
        "seeds_per_view": int(seeds),
        "power_curve_n2": {"frames": result["probe_frames"], "points": curve},
        "renders": [dict(c) for c in commands],
    }
    name = str(settings.get("name", "sample"))
    audit = {"audit": {
        "name": f"{name}_sample",
        "renders": str(renders / "{frame}" / "{view}" / "seed_{seed}.exr"),
        "views": {"left": "L", "right": "R"},
        "depth": str(renders / "{frame}" / "{view}" / "seed_000.exr"),
        "baseline_m": float(baseline),
        "convention": "conventional",
        **({"focal_px": float(settings["focal_px"])} if "focal_px" in settings else {}),
        **({"spp": int(settings["spp"])} if settings.get("spp") else {}),
    }}
    paths = {k: out / v for k, v in (("plan", "plan.yaml"), ("page", "plan.md"),
                                      ("script", "render.sh"), ("audit", "audit.yaml"),
                                      ("snippet", SNIPPET))}
    write_file(paths["snippet"], lambda tmp: shutil.copyfile(snippet_path(), tmp))
    write_file(paths["plan"], lambda tmp: tmp.write_text(yaml.safe_dump(record,
                                                                         sort_keys=False)))
    write_file(paths["audit"], lambda tmp: tmp.write_text(yaml.safe_dump(audit,
                                                                          sort_keys=False)))
    lines = ["#!/bin/sh", "# stereovar sample: the frames to render again, 2 seeds per view",
             "set -e", *[c["command"] for c in commands],
             f"stereovar audit {shlex.quote(str(paths['audit']))}"]
    write_file(paths["script"], lambda tmp: tmp.write_text("\n".join(lines) + "\n"))
    paths["script"].chmod(0o755)
    write_file(paths["page"], lambda tmp: tmp.write_text(plan_page(record)))
    return paths


def plan_page(record: dict) -> str:
    """``plan.md``: the plan's numbers in words, then the curve and the commands."""
    rows = "\n".join(
        f"| {p['strength']:g}x | {p['difference']:.3f} | {p['se']:.3f} | "
        f"{100 * p['power_one_frame']:.0f}% |" for p in record["power_curve_n2"]["points"])
    commands = "\n".join(c["command"] for c in record["renders"])
    return (
        "# Re-render plan\n\n"
        f"Render {record['frames_to_render']} of the data set's {record['frames_in_data_set']} "
        f"frames again with {record['seeds_per_view']} seeds per view. Audited together, "
        f"they detect a cue of {record['strength']:g}x the reference strength (the default "
        f"scenes' renders' own) with {100 * record['power']:.0f}% power "
        f"({100 * record['power_asked']:.0f}% asked; {record['frames_needed']} "
        f"frame{'s' * (record['frames_needed'] != 1)} needed).\n\n"
        "The power curve at N = 2, measured by the calibration on the data set's frames "
        f"{', '.join(record['power_curve_n2']['frames'])}: the Monte Carlo-specific "
        "difference of one frame, its standard error and the share of single frames whose "
        "interval lies above the rule's minimum.\n\n"
        "| strength | difference | standard error | power, one frame |\n"
        "|---|---|---|---|\n" + rows + "\n\n"
        "Each command renders one frame's scene with its own settings (only the seed "
        "changes) and, where its denoiser is on, keeps the render before it "
        "(`audit_noisy.yaml` in its folder audits that):\n\n"
        "```sh\n" + commands + "\n```\n\n"
        "Then `stereovar audit audit.yaml` audits the sample (`render.sh` does both).\n"
    )


def power_at(curve: list[PowerPoint], strength: float, frames: int) -> float:
    """The power of ``frames`` frames at ``strength`` (the module's :math:`P(F)`)."""
    from ..calibration.rates import Z
    from ..calibration.rules import MIN_EFFECT

    xs = np.log([p.strength for p in curve])
    delta = float(np.interp(math.log(strength), xs, [p.delta for p in curve]))
    se = float(np.interp(math.log(strength), xs, [p.se for p in curve]))
    if se <= 0:
        return float(delta > MIN_EFFECT)
    return float(ndtr(math.sqrt(frames) * (delta - MIN_EFFECT) / se - Z))


__all__ = [
    "PROBE_DISPARITY",
    "REFERENCE_STRENGTH",
    "SNIPPET",
    "STRENGTHS",
    "PowerPoint",
    "frames_for_power",
    "plan",
    "power_at",
    "plan_page",
    "power_curve",
    "snippet_path",
    "write_plan",
    "single_render_frames",
    "spread",
]
