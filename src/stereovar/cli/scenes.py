"""``stereovar scenes generate`` and ``stereovar scenes validate``: procedural scene specs
and their check."""

from __future__ import annotations

import argparse

from ..errors import StereovarError


def _cmd_scenes_generate(args: argparse.Namespace) -> int:
    from ..scenes.generate import write_scenes

    if args.count < 1:
        raise StereovarError(f"--count must be >= 1, got {args.count}")
    if args.seed < 0:
        raise StereovarError(f"--seed must be >= 0, got {args.seed}")
    paths = write_scenes(args.out, args.count, args.seed)
    for path in paths:
        print(path)
    return 0


def _cmd_scenes_validate(args: argparse.Namespace) -> int:
    from ..scenes.spec import load_scene_spec, scene_spec_digest

    for file in args.files:
        spec = load_scene_spec(file)
        print(f"{file}: ok ({scene_spec_digest(spec)[:12]})")
    if args.variant != "none":
        from ..renderers import get_renderer

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
