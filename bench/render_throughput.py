"""Benchmark: path-tracing throughput of one paper-scale view on every available backend.

Renders the left view of one scene (default 1280x720 at SPP 512, the paper preset's main
render) once per available Mitsuba variant, each in its own process, after a 1-SPP warm-up
render that pays the JIT compilation. It prints samples per second, the peak RSS and the
ratio to ``llvm_ad_rgb`` (the named baseline, measured in the same run), and projects the
wall time of the paper preset's whole render stage (every scene, view, seed and SPP of
``workflow/presets/paper.yaml``) from each rate. ``scalar_rgb`` runs at ``--scalar-spp``
(it is about two orders of magnitude slower) unless ``--variants`` names it alone.

Then, when Blender's ``bpy`` is installed (the ``cycles`` extra), the same view with Cycles
(:mod:`stereovar.renderers.cycles`, the CPU device, every thread, the same SPP): samples per
second and the ratio to ``llvm_ad_rgb``, plus what a render job pays once before its first
render (importing ``bpy``, compiling the spec into Blender and Mitsuba, the first 1-SPP
render) and that cost's share of a job that renders ``render.seeds_per_job`` seeds of both
views (the workflow batches seeds per job so that start-up is paid once).

With ``--options`` it instead measures render options on ``llvm_ad_rgb`` as interleaved
ratios of samples per second against the named baseline (``path``: the configured
integrator, bilinear textures, one job with every thread), each option and the baseline
alternating ``--repeats`` times, each render in its own process:

* ``moments``: the moments estimator's integrator (:mod:`stereovar.renderers.mitsuba.moments`);
* ``nearest``: nearest-neighbour texture lookups instead of bilinear;
* ``2 jobs x 2 threads``, ``2 jobs x 1 thread``: two renders at once, each with that many
  threads (the machine's throughput when Snakemake runs two render jobs; the ratio is of
  the two jobs' summed samples per second).

Usage::

    .venv/bin/python bench/render_throughput.py                 # every available variant
    .venv/bin/python bench/render_throughput.py --spp 64        # a quicker CPU check
    .venv/bin/python bench/render_throughput.py --options --width 320 --height 180 --spp 32
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow/schemas/config.schema.yaml"

WORKER = r"""
import json, resource, sys, time
args = json.loads(sys.argv[1])
from stereovar.renderers.mitsuba.backend import load_mitsuba
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.renderers.mitsuba.render import render_view
from stereovar.renderers.mitsuba.sensor import integrator_dict
from stereovar.seeding import derive_seed
from stereovar.rig import make_rig
from stereovar.scenes.spec import load_scene_spec
import drjit as dr

if args.get("texture_filter"):
    import stereovar.renderers.mitsuba.scene as compile_scene
    plain = compile_scene._texture_dict
    def texture_dict(mi, spec, name):
        return {**plain(mi, spec, name), "filter_type": args["texture_filter"]}
    compile_scene._texture_dict = texture_dict
mi = load_mitsuba(args["variant"])
if args["threads"]:
    dr.set_thread_count(args["threads"])
spec = load_scene_spec(args["scene_path"])
scene, cam = load_scene(mi, spec)
rig = make_rig(cam.to_world, cam.fov_deg, width=args["width"], height=args["height"],
               baseline_m=args["baseline_m"], convention="paper")
integ = integrator_dict("path", args["max_depth"])
if args.get("moments"):
    from stereovar.renderers.mitsuba.moments import moment_integrator_dict, register
    register(mi)
    integ = moment_integrator_dict(integ)
def render(spp, index):
    image = render_view(mi, scene, rig, "left", spp=spp, integrator=integ, rfilter="box",
                        sampler="independent", seed=derive_seed("bench", "left", spp, index),
                        channels=None)
    return image[..., :3]
t0 = time.perf_counter()
render(1, 0)
warm = time.perf_counter() - t0
t0 = time.perf_counter()
image = render(args["spp"], 1)
seconds = time.perf_counter() - t0
import numpy as np
finite = float(np.isfinite(np.asarray(image)).mean())
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "warmup": warm, "rss_mb": rss, "finite": finite}))
"""


CYCLES_WORKER = r"""
import json, resource, sys, time
t0 = time.perf_counter()
args = json.loads(sys.argv[1])
from stereovar.renderers.cycles.backend import load_bpy
load_bpy()
imported = time.perf_counter() - t0
from stereovar.renderers import get_renderer
from stereovar.renderers.base import RenderSettings
from stereovar.scenes.spec import load_scene_spec
from stereovar.seeding import derive_seed
spec = load_scene_spec(args["scene_path"])
t1 = time.perf_counter()
scene = get_renderer("cycles").prepare(
    spec,
    rig={"width": args["width"], "height": args["height"], "baseline_m": args["baseline_m"],
         "convention": "paper"},
    threads=args["threads"] or None,
)
built = time.perf_counter() - t1
settings = RenderSettings(max_depth=args["max_depth"])
t1 = time.perf_counter()
scene.render("left", spp=1, seed=derive_seed("bench", "left", 1, 0), settings=settings)
warm = time.perf_counter() - t1
t1 = time.perf_counter()
image = scene.render("left", spp=args["spp"], seed=derive_seed("bench", "left", args["spp"], 1),
                     settings=settings)
seconds = time.perf_counter() - t1
import numpy as np
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "import": imported, "build": built, "warmup": warm,
                  "rss_mb": rss, "finite": float(np.isfinite(image).mean())}))
"""


def view_job(args, config, *, spp) -> dict:
    """A worker's settings: the bench view (scene, size, threads) at ``spp``."""
    return {
        "scene_path": str(REPO / "scenes" / f"{args.scene}.yaml"),
        "width": args.width,
        "height": args.height,
        "spp": spp,
        "threads": args.threads,
        "baseline_m": config["rig"]["baseline_m"],
        "max_depth": config["render"]["max_depth"],
    }


def cycles_rate(args, config, base) -> None:
    """Cycles on the same view, in its own process; prints its rate, the ratio to ``base``
    (``llvm_ad_rgb``'s rate) and the per-job start-up cost."""
    job = view_job(args, config, spp=args.spp)
    proc = subprocess.run(
        [sys.executable, "-c", CYCLES_WORKER, json.dumps(job)], capture_output=True, text=True
    )
    if proc.returncode != 0:
        print(f"{'cycles':12s}: not measured: {proc.stderr.strip().splitlines()[-1:]}")
        return
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    samples = args.width * args.height * args.spp
    rate = samples / out["seconds"]
    ratio = f", {rate / base:6.3f}x llvm_ad_rgb" if base else ""
    print(
        f"{'cycles':12s}: {out['seconds']:8.2f} s for {samples / 1e6:8.1f} M samples = "
        f"{rate / 1e6:8.2f} M samples/s{ratio} (peak RSS {out['rss_mb']:.0f} MB, finite "
        f"{out['finite']:.4f})"
    )
    startup = out["import"] + out["build"] + out["warmup"]
    per_job = 2 * config["render"]["seeds_per_job"]
    job_seconds = startup + per_job * out["seconds"]
    print(
        f"{'cycles':12s}: start-up per job {startup:.1f} s (import bpy {out['import']:.1f} s, "
        f"scene build {out['build']:.1f} s, first 1-SPP render {out['warmup']:.1f} s): "
        f"{100 * startup / job_seconds:.1f}% of a job of {per_job} renders "
        f"(render.seeds_per_job {config['render']['seeds_per_job']}, both views)"
    )
    total, _ = paper_samples()
    print(f"{'cycles':12s}: paper preset render stage projected at {total / rate / 3600:10.1f} h")


def paper_samples() -> tuple[int, dict]:
    """Path samples of the paper preset's render stage, and the merged config."""
    from stereovar.config import load_config
    from stereovar.experiment import scene_spp_pairs

    config = load_config(
        [str(REPO / "config.yaml"), str(REPO / "workflow/presets/paper.yaml")], SCHEMA
    )
    pixels = config["resolution"]["width"] * config["resolution"]["height"]
    n = config["render"]["n_seeds"]
    total = sum(pixels * spp * n * 2 for _, spp in scene_spp_pairs(config))
    return total, config


OPTIONS = {
    "moments": ({"moments": True}, 1),
    "nearest": ({"texture_filter": "nearest"}, 1),
    "2 jobs x 2 threads": ({}, 2),
    "2 jobs x 1 thread": ({"threads": 1}, 2),
}
"""Option name to (worker settings, renders at once)."""


def _run_workers(job: dict, copies: int) -> tuple[float, list]:
    """Samples per second summed over ``copies`` concurrent worker processes of ``job``."""
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", WORKER, json.dumps(job)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(copies)
    ]
    outs = []
    for proc in procs:
        stdout, stderr = proc.communicate()
        if proc.returncode != 0:
            raise RuntimeError(stderr.strip().splitlines()[-1:])
        outs.append(json.loads(stdout.strip().splitlines()[-1]))
    samples = job["width"] * job["height"] * job["spp"]
    return sum(samples / o["seconds"] for o in outs), outs


def compare_options(args, config) -> int:
    """Interleaved ratios of each option in :data:`OPTIONS` against the ``path`` baseline."""
    import statistics

    base_job = {"variant": "llvm_ad_rgb", **view_job(args, config, spp=args.spp)}
    print(
        f"options on llvm_ad_rgb: {args.scene}, {args.width}x{args.height}, SPP {args.spp}, "
        f"{args.repeats} interleaved repeats; baseline: path, bilinear textures, one job"
    )
    ratios = {name: [] for name in OPTIONS}
    base_rates = []
    for _ in range(args.repeats):
        for name, (extra, copies) in OPTIONS.items():
            base, _ = _run_workers(base_job, 1)
            rate, _ = _run_workers({**base_job, **extra}, copies)
            base_rates.append(base)
            ratios[name].append(rate / base)
    print(
        f"{'path (baseline)':22s}: {statistics.median(base_rates) / 1e6:6.2f} M samples/s "
        f"(median of {len(base_rates)}; range {min(base_rates) / 1e6:.2f}-"
        f"{max(base_rates) / 1e6:.2f})"
    )
    for name, values in ratios.items():
        print(
            f"{name:22s}: ratio {statistics.median(values):5.2f} to path (median; range "
            f"{min(values):.2f}-{max(values):.2f})"
        )
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--spp", type=int, default=512)
    parser.add_argument("--scalar-spp", type=int, default=4)
    parser.add_argument("--scene", default="scene_000")
    parser.add_argument("--threads", type=int, default=0, help="Dr.Jit CPU threads (0: all)")
    parser.add_argument("--variants", nargs="*", help="default: every available variant")
    parser.add_argument("--options", action="store_true", help="compare render options")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-cycles", action="store_true", help="skip the Cycles measurement")
    args = parser.parse_args(argv)
    if args.options:
        return compare_options(args, paper_samples()[1])

    from stereovar.renderers.mitsuba.backend import available_variants

    variants = args.variants or available_variants()
    total, config = paper_samples()
    print(
        f"one view: {args.scene}, {args.width}x{args.height}, SPP {args.spp} "
        f"(scalar_rgb at SPP {args.scalar_spp}); variants: {', '.join(variants)}"
    )
    print(
        f"paper preset render stage: {total:.3e} path samples "
        f"({len(config['scenes'])} scenes, N = {config['render']['n_seeds']}, both views)"
    )
    rates = {}
    for variant in variants:
        slow = variant.startswith("scalar") and args.variants is None
        spp = args.scalar_spp if slow else args.spp
        job = {"variant": variant, **view_job(args, config, spp=spp)}
        proc = subprocess.run(
            [sys.executable, "-c", WORKER, json.dumps(job)], capture_output=True, text=True
        )
        if proc.returncode != 0:
            print(f"{variant:12s}: failed: {proc.stderr.strip().splitlines()[-1:]}")
            continue
        out = json.loads(proc.stdout.strip().splitlines()[-1])
        samples = args.width * args.height * spp
        rates[variant] = samples / out["seconds"]
        print(
            f"{variant:12s}: {out['seconds']:8.2f} s for {samples / 1e6:8.1f} M samples = "
            f"{rates[variant] / 1e6:8.2f} M samples/s (warm-up {out['warmup']:.1f} s, peak RSS "
            f"{out['rss_mb']:.0f} MB, finite {out['finite']:.4f})"
        )
    base = rates.get("llvm_ad_rgb")
    for variant, rate in rates.items():
        hours = total / rate / 3600
        ratio = f", {rate / base:6.2f}x llvm_ad_rgb" if base else ""
        print(f"{variant:12s}: paper preset render stage projected at {hours:10.1f} h{ratio}")
    if not args.no_cycles:
        cycles_rate(args, config, base)
    return 0 if rates else 1


if __name__ == "__main__":
    sys.exit(main())
