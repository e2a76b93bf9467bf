"""``stereovar probe``: the user's own stereo network on the counterfactual inputs of an
audit's frames or of the run's scenes."""

from __future__ import annotations

import argparse
import sys

from ..errors import StereovarError
from .monitor import INTERRUPTED_STATUS
from .snakemake import (
    _hold_results,
    _project_root,
    _run_snakemake,
    _warn_unlocked,
    _workflow_config,
    say,
)


def _cmd_probe(args: argparse.Namespace) -> int:
    """The user's own network on the counterfactual inputs of the audit's frames (a config
    with an audit: section) or of the run's scenes; their stores are made first if missing
    (workflow rule ``probe_model_frames``)."""
    from pathlib import Path

    for option, value in (("--test-frames", args.test_frames), ("--batch", args.batch)):
        if value < 1:
            raise StereovarError(f"{option} must be >= 1, got {value}")
    from ..probe.user_loading import check_weights_file, load_user_model

    weights = check_weights_file(args.weights)  # missing, a folder, a named pipe: one line
    files = []
    if args.config:
        if not Path(args.config).is_file():
            raise StereovarError(f"{args.config}: no such config file; give an existing --config")
        files.append(args.config)
    from ..jobs.probe_model import frames_manifest, probe_model_job, read_manifest
    from ..layout import audit_source, probe_model_tables

    model = load_user_model(args.model, weights, device=args.device)  # its errors first
    root = _project_root()
    config = _workflow_config(root, files)
    audit = config.get("audit")
    source = audit_source(audit["name"]) if audit else config["render"]["renderer"]
    manifest = frames_manifest(source)
    options = ["-j", str(args.cores), manifest, "--forcerun", "probe_model_frames"]
    if files:
        options += ["--configfile", *[str(Path(f).resolve()) for f in files]]
    with _hold_results(root, config, args.command_line) as lock:  # the frames and the table
        _warn_unlocked(lock)
        rc = _run_snakemake(options, root)
        if rc == INTERRUPTED_STATUS:  # said by the run
            return rc
        if rc != 0:
            raise StereovarError(
                f"the frames' stores could not be made (snakemake exit status {rc}); see its "
                "output above"
            )
        scenes, stores = read_manifest(root / manifest)
        paths = probe_model_tables(source)
        outputs = dict(zip(("csv", "md", "tex", "html"), paths, strict=True))
        settings = {"test_frames": args.test_frames, "batch": args.batch, "seed": args.seed}
        record = probe_model_job(
            stores, outputs, scenes=scenes, factory=args.model, weights=weights,
            device=args.device, settings=settings, source=source, model=model,
        )
    say("\n".join([*record["lines"], record["reading"], f"table: {paths[1]}"]), sys.stdout)
    return 0


def _register_probe(subparsers) -> None:
    probe = subparsers.add_parser(
        "probe",
        help="does your own stereo network use the Monte Carlo cue?",
        description="Run your PyTorch stereo network on the counterfactual inputs of the "
        "audit's frames (CONFIG with an audit: section) or of the run's scenes (their renders "
        "are made if missing): its accuracy and EPE drop when the right view's Monte Carlo "
        "residual is shuffled, against the drop under the same shuffle of camera-law noise, "
        "with intervals, beside the best constant disparity's accuracy and EPE, and a one-line "
        "reading (not testable where the network's output does not follow a 2-px move of its "
        "right view or is no better than the constant). The model maps (left, right) sRGB images "
        "(B, 3, H, W) in [0, 1] to disparity (B, 1, H, W) or (B, H, W), right pixel at x - d "
        "(docs: Probing your own network).",
    )
    probe.add_argument(
        "--model", required=True, metavar="MODULE:FACTORY",
        help="package.module:factory (or path/to/file.py:factory) building the model; the "
        "current folder is searched first (nets:build finds ./nets.py)",
    )
    probe.add_argument(
        "--weights", required=True, metavar="FILE",
        help="its state_dict (or a dict with state_dict), read with torch.load(weights_only=True)",
    )
    probe.add_argument(
        "--config", metavar="CONFIG",
        help="workflow config; with an audit: section, the audit's frames (default: "
        "config.yaml here, the run's scenes)",
    )
    probe.add_argument("--device", default="cpu", help="torch device (default cpu)")
    probe.add_argument(
        "--test-frames", type=int, default=4, help="renders per frame tested (default 4)"
    )
    probe.add_argument("--batch", type=int, default=4, help="pairs per forward pass (default 4)")
    probe.add_argument("--seed", type=int, default=0, help="shuffles' and bootstrap's seed")
    probe.add_argument("-j", "--cores", type=int, default=2, help="cores (default 2)")
    probe.set_defaults(func=_cmd_probe)
