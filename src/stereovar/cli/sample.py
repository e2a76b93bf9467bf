"""``stereovar sample``: a re-render plan for a data set with one render per view."""

from __future__ import annotations

import argparse

from .snakemake import say


def _cmd_sample(args: argparse.Namespace) -> int:
    """Read the data set's frames (the audit: section of CONFIG), measure the power curve at
    N = 2 on a few of them, and write the plan (:mod:`stereovar.audit.sample`)."""
    from pathlib import Path

    import yaml

    from ..audit.sample import plan, write_plan
    from ..errors import StereovarError

    path = Path(args.config)
    if not path.is_file():
        raise StereovarError(f"{path}: no such config file; give the data set's audit.yaml")
    settings = (yaml.safe_load(path.read_text()) or {}).get("audit")
    if not isinstance(settings, dict) or "renders" not in settings:
        raise StereovarError(f"{path} has no audit: section with renders; see stereovar "
                             "init --example for one")
    if settings.get("baseline_m") is None:  # before any work: the commands need the rig
        raise StereovarError(f"{path}: the audit: section has no baseline_m; give the rig's "
                             "baseline (metres) so the plan renders the same rig")
    if "root" not in settings:
        settings = {**settings, "root": str(path.resolve().parent)}
    result = plan(settings, strength=args.strength, power=args.power,
                  probe_frames=args.probe_frames, replicates=args.replicates)
    paths = write_plan(result, settings, args.out, blend=args.blend)
    say(f"{PROG_NAME}: render {len(result['chosen'])} of {len(result['frames'])} frames again "
        f"with 2 seeds per view: a cue of {result['strength']:g}x the reference strength is "
        f"then detected with {100 * result['achieved']:.0f}% power; the plan: {paths['page']}, "
        f"the commands: {paths['script']}")
    return 0


PROG_NAME = "stereovar sample"


def _register_sample(subparsers) -> None:
    sample = subparsers.add_parser(
        "sample",
        help="plan which frames of a one-render data set to render again with 2 seeds",
        description="For a data set with one render per view (the audit: section of CONFIG, "
        "its renders template without a {seed} field), measure the audit's power at N = 2 "
        "on a few of its frames, choose how many frames to render again with 2 seeds per "
        "view for the power asked, and write the plan: plan.md, plan.yaml, render.sh (one "
        "Blender command per frame, the scene's own settings, the render before the "
        "denoiser kept) and the audit.yaml of the sample.",
    )
    sample.add_argument("config", metavar="CONFIG", help="YAML config with an audit: section")
    sample.add_argument("--out", default="sample_plan", help="plan folder (default "
                        "sample_plan)")
    sample.add_argument("--strength", type=float, default=1.0,
                        help="the weakest cue to detect, as a multiple of the default "
                        "scenes' renders' own (default 1)")
    sample.add_argument("--power", type=float, default=0.8, help="power asked (default 0.8)")
    sample.add_argument("--blend", help="each frame's Blender scene, with a {frame} field "
                        "(e.g. scenes/{frame}.blend)")
    sample.add_argument("--probe-frames", type=int, default=2,
                        help="frames the power curve is measured on (default 2)")
    sample.add_argument("--replicates", type=int, default=8,
                        help="replicates per strength of the power curve (default 8)")
    sample.set_defaults(func=_cmd_sample)
