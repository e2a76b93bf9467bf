"""Command-line interface: ``stereovar <group> <command> ...``.

Commands are grouped with argparse subparsers. To add a group (e.g. ``stereovar backend``),
write a ``_register_<group>(subparsers)`` function that adds its parser and sets
``func=<handler>`` on each leaf command, and call it from :func:`build_parser`. Handlers take
the parsed namespace and return an exit status. Heavy modules (numpy, mitsuba, ...) are
imported inside the handlers so that ``stereovar --help`` stays fast.

Every :class:`~stereovar.errors.StereovarError` is printed as one line,
``stereovar: error: <message>``, on stderr and the exit status is 2.
"""

from __future__ import annotations

import argparse
import sys

from .errors import StereovarError

PROG = "stereovar"


# --------------------------------------------------------------------------------------------
# stereovar scenes ...
# --------------------------------------------------------------------------------------------


def _cmd_scenes_generate(args: argparse.Namespace) -> int:
    from .scenes.generate import write_scenes

    if args.count < 1:
        raise StereovarError(f"--count must be >= 1, got {args.count}")
    if args.seed < 0:
        raise StereovarError(f"--seed must be >= 0, got {args.seed}")
    paths = write_scenes(args.out, args.count, args.seed)
    for path in paths:
        print(path)
    return 0


def _cmd_scenes_validate(args: argparse.Namespace) -> int:
    from .scenes.spec import load_scene_spec, scene_spec_digest

    for file in args.files:
        spec = load_scene_spec(file)
        print(f"{file}: ok ({scene_spec_digest(spec)[:12]})")
    if args.variant != "none":
        from .renderers import get_renderer

        backend = get_renderer(args.renderer).backend(args.variant)
        print(
            f"back end: {backend['renderer']} {backend['renderer_version']}, "
            f"variant {backend['variant']} (render.variant: {args.variant})"
        )
    return 0


def _register_scenes(subparsers) -> None:
    scenes = subparsers.add_parser(
        "scenes", help="generate and validate scene specs", description="Scene specs."
    )
    sub = scenes.add_subparsers(dest="scenes_command", metavar="COMMAND", required=True)

    gen = sub.add_parser(
        "generate",
        help="write procedurally generated scenes",
        description="Write scene_000.yaml ... to --out; the same --count/--seed always gives "
        "the same files, and scene i does not depend on --count.",
    )
    gen.add_argument("--count", type=int, default=20, help="number of scenes (default 20)")
    gen.add_argument("--seed", type=int, default=0, help="run seed (default 0)")
    gen.add_argument("--out", default="scenes", help="output directory (default scenes)")
    gen.set_defaults(func=_cmd_scenes_generate)

    val = sub.add_parser(
        "validate",
        help="check scene spec files",
        description="Validate scene specs against the schema and cross references (for an "
        "XML scene, the file and every file it reads), then the render back end on this "
        "machine; prints 'FILE: ok (digest)' per file and the back end, or one error line and "
        "exit status 2.",
    )
    val.add_argument("files", nargs="+", metavar="FILE", help="scene spec YAML files")
    val.add_argument(
        "--renderer", default="mitsuba", help="renderer whose back end to check (default mitsuba)"
    )
    val.add_argument(
        "--variant",
        default="auto",
        help="render.variant to resolve on this machine (default auto; 'none' skips the "
        "back-end check)",
    )
    val.set_defaults(func=_cmd_scenes_validate)


# --------------------------------------------------------------------------------------------
# stereovar audit / export
# --------------------------------------------------------------------------------------------


def _project_root():
    """The checkout whose workflow the command runs: the current directory, which must hold
    the Snakefile (relative paths in configs are relative to it, as for ``snakemake``)."""
    from pathlib import Path

    root = Path.cwd()
    if not (root / "Snakefile").is_file() or not (root / "workflow").is_dir():
        raise StereovarError(
            f"{root} has no stereovar Snakefile; run this command from the stereovar checkout "
            "(the directory with the Snakefile)"
        )
    return root


def _snakemake(args: list, root) -> int:
    import subprocess

    cmd = [sys.executable, "-m", "snakemake", *args]
    print("stereovar: running " + " ".join(cmd[1:]), file=sys.stderr)
    return subprocess.run(cmd, cwd=root, check=False).returncode


def _workflow_config(root, files) -> dict:
    """The config the workflow would run with: ``config.yaml`` of ``root``, then ``files``
    (as ``--configfile``), validated against the workflow's schema with its defaults filled
    in (:func:`stereovar.config.load_config`); one line for anything it refuses."""
    from .config import load_config

    return load_config(
        [root / "config.yaml", *files], root / "workflow" / "schemas" / "config.schema.yaml"
    )


def _cmd_audit(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from .audit.run import audit_paths
    from .schema import load_yaml

    root = _project_root()
    config = Path(args.config)
    if not config.is_file():
        raise StereovarError(f"{config}: no such config file; give the audit's YAML config")
    data = load_yaml(config, "audit config", error=StereovarError) or {}
    settings = data.get("audit") if isinstance(data, dict) else None
    if not isinstance(settings, dict):
        raise StereovarError(
            f"{config}: no audit: section; add one (keys: name, renders, views, disparity, "
            "convention; see the README's 'Audit your own renders')"
        )
    # The whole config, as the workflow will see it, before any file is read; the import is
    # the workflow's (one audit_import job per frame).
    settings = _workflow_config(root, [config])["audit"]
    command = ["-j", str(args.cores), "all", "--configfile", str(config.resolve())]
    if args.import_only:
        command += ["--until", "audit_import"]
    rc = _snakemake(command, root)
    if rc != 0:
        return rc
    paths = audit_paths(settings["name"])
    if args.import_only:
        records = root / Path(paths["summary"]).parent / "import"
        print(f"imported {settings['name']}: one record per frame in {records}")
        return 0
    summary = root / paths["summary"]
    print("\n".join(json.loads(summary.read_text())["summary"]))
    print(f"verdict page: {summary.parent / 'verdict.html'}")
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .audit.export import check_export_targets, export_targets

    root = _project_root()
    files = [Path(f) for f in args.configfile or []]
    config = _workflow_config(root, files)
    targets = export_targets(config, args.format)
    check_export_targets(targets)  # a link or a stray folder would pass for an export
    options = ["-j", str(args.cores), "export", "--config", f"export={{formats: [{args.format}]}}"]
    for f in args.configfile or []:
        options[3:3] = ["--configfile", f]
    rc = _snakemake(options, root)
    if rc != 0:
        return rc
    check_export_targets(targets)
    folder = Path(targets[0]).parent
    scenes = ", ".join(Path(t).name for t in targets)
    print(
        f"exported {len(targets)} scene{'s' * (len(targets) != 1)} to {folder}/ ({scenes}); "
        "each scene directory has an audit.yaml that audits it"
    )
    return 0


def _register_audit(subparsers) -> None:
    audit = subparsers.add_parser(
        "audit",
        help="audit renders made elsewhere for the cross-view variance cue",
        description="Import N >= 2 renders per view of stereo frames and their ground truth "
        "(the audit: section of CONFIG), run every statistic, control and the intervention on "
        "them, and print the verdict's summary; the page is results/audit/<name>/verdict.html.",
    )
    audit.add_argument("config", metavar="CONFIG", help="YAML config with an audit: section")
    audit.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    audit.add_argument(
        "--import-only",
        action="store_true",
        help="run only the import jobs (one per frame: decode, check, sign-check, store)",
    )
    audit.set_defaults(func=_cmd_audit)
    export = subparsers.add_parser(
        "export",
        help="export renders, variance fields and disparity as EXR, PFM, NPY or PNG files",
        description="Write every scene's renders, variance fields, disparity and glass mask "
        "to results/export/<renderer>/<estimator>/<format>/<scene>/ (the workflow's export "
        "target), with an audit.yaml that audits the export.",
    )
    export.add_argument("--format", required=True, choices=["exr", "pfm", "npy", "png"])
    export.add_argument("--configfile", action="append", help="workflow config(s) to export")
    export.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    export.set_defaults(func=_cmd_export)


# --------------------------------------------------------------------------------------------
# entry point
# --------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per command group."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Cross-view Monte Carlo variance correlation in path-traced stereo.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="GROUP", required=True)
    _register_scenes(subparsers)
    _register_audit(subparsers)
    return parser


def main(argv=None) -> int:
    """Run the command line; returns (and, as a script, exits with) the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success, 2 on a usage error or a :class:`~stereovar.errors.StereovarError`.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except StereovarError as err:
        message = " ".join(str(err).split())
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
