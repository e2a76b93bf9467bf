"""``stereovar init`` (starter configs), ``stereovar run`` (the workflow) and
``stereovar report`` (Snakemake's report), each in the current directory."""

from __future__ import annotations

import argparse
import sys

from ..errors import StereovarError
from ..stages import stage_list
from .snakemake import (
    _VERBOSE,
    _hold_results,
    _passed_configfiles,
    _project_root,
    _run_snakemake,
    _warn_unlocked,
    _workflow,
    _workflow_config,
    say,
)

#: The starter audit config ``stereovar init`` writes; ``{name}``, ``{renders}``, ``{views}``,
#: ``{disparity}`` and ``{convention}`` are filled in (placeholders, or the example's files).
AUDIT_STARTER = """\
# stereovar audit audit.yaml: audit renders made elsewhere for the cross-view variance cue.
# How to describe your files: {audit_docs}
# Keys, types and defaults (the audit: section): {configuration_docs}
audit:
  # results/audit/<name>/verdict.html
  name: {name}
  renders: {renders}
  # the {{view}} values in the paths
  views: {views}
  # the left view's disparity (add {{view}} to give both views')
  disparity: {disparity}
  # conventional: x_R = x_L - d (Middlebury, KITTI, SceneFlow); paper: x_R = x_L + d
  convention: {convention}
  # glass_mask: masks/{{frame}}.png      # or segmentation: seg/{{frame}}.png, glass_ids: [3]
  # depth: depth/{{frame}}.exr           # instead of disparity, with focal_px and baseline_m
  # transfer: srgb                     # PNG renders: srgb (default, with a warning) or linear
  # spp: 128                           # for the tables; null = not given (0)
  # mitigations: [denoise]             # test mitigations on these renders
  # probe: true                        # train and test the learned matcher on these frames
"""


#: The workflow's targets that ``stereovar run`` lists, each with what it makes and about how
#: long it takes on 2 cores with the default config, its renders included (docs: Measured
#: performance); ``calibration``, ``probe`` and ``export`` read the run's renders.
RUN_TARGETS = {
    "all": "the default experiment, claims and results/index.html (~20 min)",
    "mitigations": "the mitigation table and its trade-off figure (~10 min)",
    "calibration": "the verdict rules on matched nulls of the run (~4 min)",
    "probe": "trains stereo matchers: do they learn the cue? (~15 min)",
    "generators": "the cue under Kubric/BlenderProc/Infinigen defaults (~15 min)",
    "estimators": "the moments estimator against the seeds estimator (~25 min)",
    "export": "renders, variance, disparity as files an audit reads (seconds)",
}


def _run_epilog() -> str:
    """The ``run --help`` list of :data:`RUN_TARGETS`, one item each (:class:`_ListFormatter`)."""
    width = max(map(len, RUN_TARGETS))
    lines = [f"  {name:<{width}}  {what}" for name, what in RUN_TARGETS.items()]
    title = "targets (2 cores, default config; or any Snakemake target or path):"
    return "\n".join([title, *lines])


class _ListFormatter(argparse.HelpFormatter):
    """argparse's help, with each line of a text that starts with two spaces kept as a list
    item: ``  name  what``, its text wrapped under itself."""

    def _fill_text(self, text, width, indent):
        import re
        import textwrap

        out = []
        for line in text.splitlines():
            item = re.match(r"(  \S+\s+)(.*)", line)
            if item is None:
                out.append(super()._fill_text(line, width, indent))
                continue
            head = indent + item.group(1)
            out.append(
                textwrap.fill(
                    item.group(2), width, initial_indent=head, subsequent_indent=" " * len(head)
                )
            )
        return "\n".join(out)


def _complete_targets(prefix: str = "", **_) -> list:
    """Tab completion of ``run``'s targets (argcomplete's completer protocol)."""
    return [name for name in RUN_TARGETS if name.startswith(prefix)]


def _write_new(path, text: str) -> bool:
    """Write ``text`` to ``path`` atomically unless it exists; True if written."""
    from ..io.store import atomic_path

    if path.exists():
        say(f"kept {path} (it exists)", sys.stdout)
        return False
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    say(f"wrote {path}", sys.stdout)
    return True


def _cmd_init(args: argparse.Namespace) -> int:
    import os

    root = _project_root()
    fields = {
        "name": "my_renders",
        "renders": "renders/{frame}/{view}/seed_{seed}.exr",
        "views": "{left: L, right: R}",
        "disparity": "disparity/{frame}.pfm",
        "convention": "conventional",
    }
    if args.example:
        from ..audit.synthetic import write_synthetic_audit

        folder = root / "data" / "synthetic"
        present = [path for path in (folder, root / "audit.yaml") if path.exists()]
        if len(present) == 1:  # the example's data without its config, or the reverse
            raise StereovarError(
                f"{present[0]} exists; remove it or run stereovar init --example in another "
                "directory"
            )
        if present:  # an example written before: both kept, as every file init writes
            say(f"kept {folder} (it exists)", sys.stdout)
        else:
            settings, _ = write_synthetic_audit(os.path.relpath(folder, root))
            fields = {**settings, "views": "{left: L, right: R}"}
            say(f"wrote {folder}: 2 synthetic frames with a known cross-view correlation",
                sys.stdout)
    _write_new(root / "config.yaml", (_workflow() / "config.yaml").read_text())
    from ..links import docs_page

    links = {"audit_docs": docs_page("audit"), "configuration_docs": docs_page("configuration")}
    _write_new(root / "audit.yaml", AUDIT_STARTER.format(**fields, **links))
    print("next: stereovar run -j2 (the default experiment) or stereovar audit audit.yaml")
    return 0


def _configfiles(args) -> list:
    """``--preset`` configs (the workflow's) then ``--configfile`` configs, as given."""
    from pathlib import Path

    from ..workflow_home import preset_path

    files = [str(preset_path(name)) for name in args.preset or []]
    for f in args.configfile or []:
        if not Path(f).is_file():
            raise StereovarError(f"{f}: no such config file; give an existing --configfile")
        files.append(f)
    return files


def _targets(targets: list, snakemake_args: list) -> list:
    """The targets ``run`` names to Snakemake: the given ones; else ``all``, unless a word of
    Snakemake's options is not an option (``-n mitigations``, ``-R render``): Snakemake reads
    it as a target or as a value, and without a target it runs ``all``, the workflow's
    default target, as it would have.

    Examples
    --------
    >>> _targets([], ["-n"]), _targets([], ["-n", "mitigations"]), _targets(["probe"], [])
    (['all'], [], ['probe'])
    """
    if targets:
        return list(targets)
    return [] if any(not arg.startswith("-") for arg in snakemake_args) else ["all"]


def _cmd_run(args: argparse.Namespace) -> int:
    files = _configfiles(args)
    root = _project_root()
    # the config as the workflow will read it: refused in one line before Snakemake starts,
    # and the results the run may write, which it holds while it goes
    config = _workflow_config(root, [*files, *_passed_configfiles(args.snakemake_args)])
    options = ["-j", str(args.cores), *_targets(args.targets, args.snakemake_args)]
    if files:
        options += ["--configfile", *files]
    with _hold_results(root, config, args.command_line, args.snakemake_args) as lock:
        _warn_unlocked(lock)
        token = _VERBOSE.set(args.verbose)  # one line per stage, or (-v) Snakemake's output
        try:
            return _run_snakemake([*options, *args.snakemake_args], root)
        finally:
            _VERBOSE.reset(token)


def _cmd_report(args: argparse.Namespace) -> int:
    files = _configfiles(args)
    options = ["--report", args.output]
    if files:
        options += ["--configfile", *files]
    rc = _run_snakemake([*options, *args.snakemake_args], _project_root())
    if rc == 0:
        say(f"report: {args.output}", sys.stdout)
    return rc


def _add_configs(parser) -> None:
    parser.add_argument(
        "--configfile", action="append", metavar="FILE", help="config merged on top (repeatable)"
    )
    parser.add_argument(
        "--preset",
        action="append",
        metavar="NAME",
        help="a preset shipped with the workflow: paper, paper-moments or probe (the "
        "paper's scale, with the moments estimator, the probe's frames), or "
        "generators/kubric, generators/blenderproc, generators/infinigen (a generator's own "
        "Cycles settings), merged before --configfile",
    )


def _register_workflow(subparsers) -> None:
    init = subparsers.add_parser(
        "init",
        help="write a starter config.yaml and audit.yaml here",
        description="Write config.yaml (the workflow's defaults, commented) and audit.yaml (an "
        "audit config to fill in) in the current directory; an existing file is kept.",
    )
    init.add_argument(
        "--example",
        action="store_true",
        help="also write two synthetic frames under data/synthetic and point audit.yaml at them",
    )
    init.set_defaults(func=_cmd_init)
    run = subparsers.add_parser(
        "run",
        help="run the workflow here (results under ./results)",
        description="Run the stereovar workflow with the current directory as its working "
        "directory: config.yaml here if there is one (else the defaults), then --preset and "
        "--configfile configs. Any other option goes to snakemake, as do the words after "
        "its first one and after -- (stereovar run -n: a dry run, the plan by stage). "
        f"Prints one line per stage with jobs, in this order: {stage_list('run')}; inside a "
        "long stage, its jobs done, the run's and an estimate of the time left.",
        epilog=_run_epilog(),
        formatter_class=_ListFormatter,
        allow_abbrev=False,  # --config is Snakemake's, not short for --configfile
    )
    targets = run.add_argument(
        "targets", nargs="*", metavar="TARGET", help="targets, listed below (default: all)"
    )
    targets.completer = _complete_targets
    run.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    run.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="show Snakemake's whole output live (it always goes to "
        "logs/stereovar-run-<time>.log; without -v, one line per stage)",
    )
    _add_configs(run)
    run.set_defaults(func=_cmd_run, passthrough=True)
    report = subparsers.add_parser(
        "report",
        help="write Snakemake's report of the run here",
        description="Write Snakemake's self-contained report of the results here (the "
        "workflow's captions, figures and tables). Any other option goes to snakemake, as "
        "do the words after -- .",
        allow_abbrev=False,
    )
    report.add_argument(
        "-o", "--output", default="results/report.html", help="default results/report.html"
    )
    _add_configs(report)
    report.set_defaults(func=_cmd_report, passthrough=True)
