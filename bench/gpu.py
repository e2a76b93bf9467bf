"""Benchmark: the paper preset's renders and the probe on a GPU against the CPU of the same machine.

1. **Renders.** For each Mitsuba variant (default ``cuda_ad_rgb`` and ``llvm_ad_rgb``, each in
   its own process; ``auto``'s choice is printed too) one scene of the paper preset
   (``workflow/presets/paper.yaml``: 1280x720, SPP 512, the config's integrator, depth, filter
   and sampler) is rendered for ``--seeds`` seed indices of both views, twice over:

   * the named baseline, a bare loop: the scene compiled once, both sensors and the integrator
     loaded once, then ``mi.render`` per seed (the image copied to the host, as every render
     is), run before and after the job;
   * :func:`stereovar.jobs.render.render_job` on the same seeds: its own scene compile, the
     same sampler seeds, both render stores written (no render cache).

   A render at the measured size and SPP comes first and pays the JIT compilation. It prints
   samples per second of each, the ratio of the job to the bare loop, whether the job's
   stored left images equal the bare loop's bit for bit (each loads the scene itself: on a
   GPU or a many-core CPU a second load changes a few pixels of a fixed seed's render, see
   ``docs/performance.md``), and the wall time of the preset's whole render stage (every
   scene, view, seed and SPP of the sweep) projected from each rate; the job's projection
   takes its renders after the first and adds its fixed cost (scene compile, the first
   render's extra time, store writes) once per render job of the preset (one per scene, SPP
   and batch of ``render.seeds_per_job`` seeds). Last, each variant's rate against
   ``llvm_ad_rgb`` (the machine's CPU cores) measured in the same run. ``--cpu-spp`` and
   ``--cpu-seeds`` shorten the CPU variants (a render's rate hardly depends on its SPP; the
   default SPP is the preset's only for GPU variants).

2. **Probe** (PyTorch; ``workflow/presets/probe.yaml``). On synthetic textured pairs with a
   known disparity of 1-13 px at the preset's 320x180 (``bench/probe.py``'s generator), the
   training of one network (:func:`stereovar.probe.training.train_matcher`, the preset's
   training settings, 24 frames: 4 training scenes x N = 6) and one held-out scene's test
   (:func:`stereovar.probe.experiment.test_scene`: the 6 networks of a test job, both test
   frames, every test input, D = 17), plus one 1280x720 pair's
   :func:`~stereovar.probe.network.wta_disparity`, on ``cuda`` against the named baseline,
   the same on that machine's CPU with the job's Torch threads (1), and with every core. GPU
   results are checked against the CPU's (first losses, equal disparities).

``--json PATH`` writes every number. ``--tiny`` runs everything at a small size (a check that
it works on any machine; its rates mean nothing).

Usage::

    python bench/gpu.py --json gpu.json          # on a machine with an NVIDIA GPU
    .venv/bin/python bench/gpu.py --tiny         # quick check, CPU only
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import traceback
from pathlib import Path

BENCH = Path(__file__).resolve().parent
REPO = BENCH.parent
sys.path.insert(0, str(BENCH))

from render_throughput import SCHEMA, paper_samples  # noqa: E402

RENDER_WORKER = r"""
import json, logging, re, sys, tempfile, time
import numpy as np
args = json.loads(sys.argv[1])
from stereovar.renderers.mitsuba.backend import describe_backend, load_mitsuba, select_variant
auto = select_variant("auto")
mi = load_mitsuba(args["variant"])
import drjit as dr
if args["threads"]:
    dr.set_thread_count(args["threads"])
from stereovar.jobs.common import view_stack
from stereovar.jobs.render import render_job
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.renderers.mitsuba.sensor import integrator_dict, sensor_dict
from stereovar.rig import VIEWS, make_rig
from stereovar.scenes.spec import load_scene_spec
from stereovar.seeding import render_seed

opts, spp, seeds = args["options"], args["spp"], list(range(args["seeds"]))
spec = load_scene_spec(args["scene_path"])
t0 = time.perf_counter()
scene, cam = load_scene(mi, spec)
compile_s = time.perf_counter() - t0
rig = make_rig(cam.to_world, cam.fov_deg, width=opts["width"], height=opts["height"],
               baseline_m=opts["baseline_m"], convention=opts["convention"])
integ = mi.load_dict(integrator_dict(opts["integrator"], opts["max_depth"]))
sensors = {v: mi.load_dict(sensor_dict(mi, rig, v, spp=spp, rfilter=opts["rfilter"],
                                       sampler=opts["sampler"])) for v in VIEWS}

def bare(view, index):
    seed = render_seed(spec["name"], view, spp, index, policy=args["seed_policy"])
    image = mi.render(scene, sensor=sensors[view], integrator=integ, seed=seed, spp=spp)
    return np.asarray(image, dtype=np.float32)[..., :3]

def bare_pass():
    images, seconds = {}, []
    for view in VIEWS:
        for index in seeds:
            t0 = time.perf_counter()
            images[view, index] = bare(view, index)
            seconds.append(time.perf_counter() - t0)
    return images, seconds

t0 = time.perf_counter()
warm = bare("left", len(seeds))
warm_s = time.perf_counter() - t0
first, bare1 = bare_pass()

class Times(logging.Handler):
    def __init__(self):
        super().__init__(logging.INFO)
        self.seconds = []
    def emit(self, record):
        found = re.search(r"rendered in ([0-9.]+) s", record.getMessage())
        if found:
            self.seconds.append(float(found.group(1)))
times = Times()
logger = logging.getLogger("stereovar")
logger.addHandler(times)
logger.setLevel(logging.INFO)
job = {"job_error": None}
try:
    with tempfile.TemporaryDirectory() as tmp:
        outputs = {v: f"{tmp}/{v}.zarr" for v in VIEWS}
        t0 = time.perf_counter()
        render_job(args["scene_path"], outputs, seeds=seeds, spp=spp, variant=args["variant"],
                   seed_policy=args["seed_policy"], threads=args["threads"] or None, cache=None,
                   **opts)
        job["job_s"] = time.perf_counter() - t0
        job["job_render_s"] = times.seconds
        stored = view_stack([outputs["left"]])[0]
        bare_left = np.stack([first["left", i] for i in seeds])
        job["job_equals_bare"] = bool(np.array_equal(stored, bare_left))
        diff = np.abs(stored - bare_left).max(axis=-1) / np.nanmean(np.abs(bare_left))
        job["job_max_rel_diff"] = float(np.nanmax(diff))
        job["job_pixels_off"] = float((diff > 1e-3).mean())
except Exception as err:  # the bare loop's numbers still count
    job["job_error"] = f"{type(err).__name__}: {err}"[:300]
_, bare2 = bare_pass()
images = np.stack(list(first.values()))
print(json.dumps({
    "auto": auto, "backend": describe_backend(), "compile_s": compile_s, "warmup_s": warm_s,
    "bare_s": [bare1, bare2], **job, "mean": float(np.nanmean(images)),
    "finite": float(np.isfinite(images).mean()),
}))
"""


def render_settings(config: dict) -> dict:
    """render_job's rig and render options from a merged config."""
    r = config["render"]
    return {
        "width": config["resolution"]["width"],
        "height": config["resolution"]["height"],
        "baseline_m": config["rig"]["baseline_m"],
        "convention": config["rig"]["convention"],
        "integrator": r["integrator"],
        "max_depth": r["max_depth"],
        "rfilter": r["rfilter"],
        "sampler": r["sampler"],
    }


def preset_jobs(config: dict) -> int:
    """Render jobs of a config's render stage: one per (scene, SPP) pair and seed batch."""
    from stereovar.experiment import scene_spp_pairs, seed_batches

    render = config["render"]
    batches = seed_batches(int(render["n_seeds"]), int(render["seeds_per_job"]))
    return len(scene_spp_pairs(config)) * len(batches)


def render_variant(variant: str, args, config: dict) -> dict | None:
    """One variant's worker run, its rates and projections; None when it failed."""
    gpu = variant.startswith("cuda")
    spp = args.spp if gpu else args.cpu_spp
    seeds = args.seeds if gpu else args.cpu_seeds
    options = render_settings(config)
    job = {
        "variant": variant,
        "scene_path": str(REPO / "scenes" / f"{args.scene}.yaml"),
        "spp": spp,
        "seeds": seeds,
        "threads": 0,
        "seed_policy": config["render"]["seed_policy"],
        "options": options,
    }
    proc = subprocess.run(
        [sys.executable, "-c", RENDER_WORKER, json.dumps(job)], capture_output=True, text=True
    )
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-3:]
        print(f"{variant:12s}: failed: {' | '.join(tail)}")
        return None
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    per_render = options["width"] * options["height"] * spp
    renders = 2 * seeds
    total, paper = paper_samples()
    bare = [sum(p) for p in out["bare_s"]]
    bare_rate = per_render * renders / statistics.mean(bare)
    out.update(variant=variant, spp=spp, seeds=seeds, renders_per_pass=renders)
    out.update(bare_rate=bare_rate, bare_hours=total / bare_rate / 3600)
    print(
        f"{variant:12s}: {options['width']}x{options['height']} SPP {spp}, {seeds} seed(s) x 2 "
        f"views; auto picks {out['auto']}; scene compile {out['compile_s']:.2f} s, first render "
        f"(JIT) {out['warmup_s']:.2f} s"
    )
    print(
        f"{'':12s}  bare mi.render loop (baseline): {bare[0]:7.2f} s / {bare[1]:7.2f} s per pass "
        f"= {bare_rate / 1e6:8.2f} M samples/s; paper preset render stage ({total:.3e} "
        f"samples) {out['bare_hours']:.2f} h"
    )
    if out["job_error"]:
        print(f"{'':12s}  render_job failed: {out['job_error']}")
        return out
    job_rate = per_render * renders / out["job_s"]
    # a job's first render pays the JIT compilation of its own scene's kernels
    steady = statistics.median(out["job_render_s"][1:] or out["job_render_s"])
    overhead = out["job_s"] - renders * steady
    jobs = preset_jobs(paper)
    # the preset's render jobs: every render at the job's render rate, plus the fixed cost
    # measured here (scene compile, first render, store writes) once per job
    job_hours = (total / (per_render / steady) + jobs * overhead) / 3600
    out.update(
        job_rate=job_rate,
        job_render_rate=per_render / steady,
        job_overhead_s=overhead,
        job_hours=job_hours,
    )
    print(
        f"{'':12s}  render_job                    : {out['job_s']:7.2f} s per pass "
        f"= {job_rate / 1e6:8.2f} M samples/s: ratio {bare_rate / job_rate:.3f} to the bare "
        f"loop in time; stored images equal the bare loop's bit for bit: {out['job_equals_bare']} "
        f"(largest difference {out['job_max_rel_diff']:.1e} of the mean radiance, "
        f"{100 * out['job_pixels_off']:.2f}% of pixels off by more than 1e-3 of it)"
    )
    print(
        f"{'':12s}  render_job's renders {', '.join(f'{t:.2f}' for t in out['job_render_s'])} s: "
        f"{per_render / steady / 1e6:.2f} M samples/s after the first (ratio "
        f"{steady * bare_rate / per_render:.3f} to the bare loop), {overhead:.2f} s per job "
        f"besides (scene compile, the first render's extra time, store writes)"
    )
    print(f"{'':12s}  paper preset render stage as its {jobs} render jobs: {job_hours:.2f} h")
    return out


def render_part(args, report: dict) -> None:
    total, paper = paper_samples()
    config = paper
    if args.tiny:
        config = {**paper, "resolution": {"width": 160, "height": 90}}
    print(
        f"renders: {args.scene}, paper preset {paper['resolution']['width']}x"
        f"{paper['resolution']['height']}, {total:.3e} samples in its render stage "
        f"({len(paper['scenes'])} scenes x 2 views x N = {paper['render']['n_seeds']} at SPP "
        f"{paper['render']['spp']}, plus the SPP sweep)"
    )
    results = {}
    for variant in args.variants:
        out = render_variant(variant, args, config)
        if out is not None:
            results[variant] = out
    base = results.get("llvm_ad_rgb")
    if base:
        for variant, out in results.items():
            if variant != "llvm_ad_rgb":
                ratio = out["bare_rate"] / base["bare_rate"]
                out["ratio_to_llvm"] = ratio
                print(
                    f"{variant:12s}: {ratio:.1f}x llvm_ad_rgb on this machine's "
                    f"{os.cpu_count()} CPU threads (bare loops; image means "
                    f"{out['mean']:.5f} / {base['mean']:.5f})"
                )
    report["render"] = results


def synthetic_scene(height: int, width: int, n: int, seed: int):
    """Renders (N, H, W, 3) of both views with a known disparity field, and the ground truth
    (disparity, valid, glass: the middle third of the columns)."""
    import numpy as np
    from probe import SIGN, smooth_noise

    rng = np.random.default_rng(seed)
    right = 0.15 + 0.7 * smooth_noise(rng, height, width, 1.0)
    disparity = 1.0 + 12.0 * smooth_noise(rng, height, width, 30.0)
    cols = np.arange(width, dtype=np.float64)
    left = np.stack([np.interp(cols + SIGN * disparity[y], cols, right[y]) for y in range(height)])
    noisy = lambda img: img[None, :, :, None] + 0.02 * rng.standard_normal((n, height, width, 3))  # noqa: E731
    glass = np.zeros((height, width), bool)
    glass[:, width // 3 : 2 * width // 3] = True
    truth = {"disparity": disparity, "valid": np.ones((height, width), bool), "glass": glass}
    return noisy(left), noisy(right), truth


def probe_part(args, report: dict) -> None:
    import numpy as np
    import torch
    from probe import SIGN, synthetic_frame

    from stereovar.config import load_config
    from stereovar.probe.experiment import TestSettings, test_scene
    from stereovar.probe.network import MatchingNet, wta_disparity
    from stereovar.probe.training import TrainingFrame, TrainSettings, train_matcher

    config = load_config(
        [str(REPO / "config.yaml"), str(REPO / "workflow/presets/probe.yaml")], SCHEMA
    )
    height, width = config["resolution"]["height"], config["resolution"]["width"]
    settings = TrainSettings(**config["probe"]["training"])
    n_frames, big = 4 * config["render"]["n_seeds"], (720, 1280)
    if args.tiny:
        settings = TrainSettings(**{**config["probe"]["training"], "steps": 4})
        height, width, n_frames, big = 60, 120, 2, (90, 160)
    frames = [
        TrainingFrame(*synthetic_frame(height, width, 1.0, 13.0, seed=k), SIGN)
        for k in range(n_frames)
    ]
    left, right, truth = synthetic_scene(height, width, config["render"]["n_seeds"], seed=99)
    test = TestSettings(test_frames=config["probe"]["test_frames"], max_disparity=17)
    pair = synthetic_frame(*big, 1.0, 13.0, seed=123)
    cpus = os.cpu_count() or 1
    runs = [("cpu", settings.threads)] + ([("cpu", cpus)] if cpus > settings.threads else [])
    if torch.cuda.is_available():
        runs = [("cuda", settings.threads)] + runs
    else:
        print("probe: no CUDA device visible to PyTorch; CPU only")
    print(
        f"probe: {settings.steps} training steps on {n_frames} synthetic {width}x{height} frames "
        f"({settings.crops} crops of {settings.crop_rows}x{settings.crop_cols} features); test "
        f"of one scene by 6 networks ({test.test_frames} frames x {len(test.inputs)} inputs, "
        f"D = {test.max_disparity}); wta_disparity on one {big[1]}x{big[0]} pair"
    )
    results, d_hats = {}, {}
    print(f"  {'':18s} {'training':>20s} {'test of one scene':>18s} {'wta 1 pair':>12s}")
    for device, threads in runs:
        name = f"{device} ({threads} thread{'s' if threads > 1 else ''})"
        torch.set_num_threads(threads)
        step = TrainSettings(**{**vars(settings), "steps": 3, "threads": threads})
        train_matcher(frames, step, seed=0, device=device)  # warm-up: context, kernels
        timed = TrainSettings(**{**vars(settings), "threads": threads})
        net, history = train_matcher(frames, timed, seed=0, device=device)
        nets = {}
        for k in range(6):
            torch.manual_seed(k)
            nets["net", k] = MatchingNet().to(device)
        regions = ("all", "non_glass", "glass")
        kwargs = {"scene": "synthetic", "sign": SIGN, "regions": regions, "settings": test}
        torch.set_num_threads(threads)
        small = {k: v[:48, :96] for k, v in truth.items()}
        test_scene(nets, left[:2, :48, :96], right[:2, :48, :96], small, **kwargs)  # warm-up
        t0 = time.perf_counter()
        test_scene(nets, left, right, truth, **kwargs)
        test_s = time.perf_counter() - t0
        warm = pair[0][:90, :160], pair[1][:90, :160]
        wta_disparity(nets["net", 0], *warm, sign=SIGN, max_disparity=17)  # warm-up
        t0 = time.perf_counter()
        d_hats[name] = wta_disparity(nets["net", 0], pair[0], pair[1], sign=SIGN, max_disparity=17)
        wta_s = time.perf_counter() - t0
        results[name] = {
            "device": device,
            "threads": threads,
            "train_s": history["seconds"],
            "step_ms": 1e3 * history["step_seconds"],
            "first_losses": history["loss"][:3],
            "test_scene_s": test_s,
            "wta_big_s": wta_s,
        }
        print(
            f"  {name:18s} {history['seconds']:8.2f} s {1e3 * history['step_seconds']:7.2f} "
            f"ms/step {test_s:16.2f} s {wta_s:10.3f} s"
        )
    base_name = f"cpu ({settings.threads} thread{'s' if settings.threads > 1 else ''})"
    base = results[base_name]
    for name, r in results.items():
        if r is base:
            continue
        r["speedup_train"] = base["train_s"] / r["train_s"]
        r["speedup_test"] = base["test_scene_s"] / r["test_scene_s"]
        r["speedup_wta_big"] = base["wta_big_s"] / r["wta_big_s"]
        ref = d_hats[base_name]
        ok = np.isfinite(ref)
        r["wta_agreement"] = float((d_hats[name][ok] == ref[ok]).mean())
        print(
            f"  {name} against the baseline cpu ({base['threads']} thread): training "
            f"{r['speedup_train']:.2f}x, test {r['speedup_test']:.2f}x, wta "
            f"{r['speedup_wta_big']:.2f}x faster; first losses {r['first_losses'][0]:.5f} vs "
            f"{base['first_losses'][0]:.5f}; equal disparities {100 * r['wta_agreement']:.2f}%"
        )
    report["probe"] = results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="scene_000")
    parser.add_argument("--variants", nargs="*", default=["cuda_ad_rgb", "llvm_ad_rgb"])
    parser.add_argument("--spp", type=int, default=512, help="SPP of GPU variants")
    parser.add_argument("--seeds", type=int, default=4, help="seed indices of GPU variants")
    parser.add_argument("--cpu-spp", type=int, default=64, help="SPP of CPU variants")
    parser.add_argument("--cpu-seeds", type=int, default=1, help="seed indices of CPU variants")
    parser.add_argument("--tiny", action="store_true", help="small sizes: a check that it runs")
    parser.add_argument("--no-render", action="store_true")
    parser.add_argument("--no-probe", action="store_true")
    parser.add_argument("--json", help="write every number to this file")
    args = parser.parse_args(argv)
    if args.tiny:
        args.spp, args.seeds, args.cpu_spp, args.cpu_seeds = 8, 2, 8, 1
    report = {"argv": sys.argv[1:], "cpus": os.cpu_count()}
    parts = [] if args.no_render else [("render", render_part)]
    if not args.no_probe:
        try:
            import torch  # noqa: F401
        except ImportError:
            print("probe: PyTorch is not installed (the probe extra); skipped")
        else:
            parts.append(("probe", probe_part))
    failed = 0
    for name, part in parts:
        try:
            part(args, report)
        except Exception:  # a failed part is reported and the next one still runs
            traceback.print_exc()
            report[name] = "failed"
            failed += 1
        if args.json:
            Path(args.json).write_text(json.dumps(report, indent=1, default=str))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
