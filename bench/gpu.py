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

2. **Probe** (PyTorch; the full-power ``workflow/presets/probe.yaml``). On synthetic textured
   scenes with a known disparity of 1-13 px at the preset's 320x180 (``bench/probe.py``'s
   generator; N renders per view with 2 % noise), shaped as one fold of the preset (its
   training scenes x N, the last seed index of each held out; the validation bands of
   ``probe.validation_rows`` rows), for each architecture
   (:func:`stereovar.probe.architectures.architecture`, its settings the schema's defaults):

   * one network trained to its plateau of validation accuracy (steps taken, best step,
     seconds, seconds per check) and its cue-blind twin
     (:func:`~stereovar.probe.experiment.training_frames` with ``twin=True``) trained for the
     network's best step, as :func:`stereovar.jobs.probe.train_job` trains them;
   * ``--fixed-steps`` steps (200) without checks, so the per-step ratio is clean;
   * one test job (:func:`stereovar.probe.experiment.test_scene`: the tested condition's
     networks, their twins and the control's, ``--test-seeds`` each, on ``--test-scenes``
     held-out scenes, ``probe.test_frames`` frames, every test input, D = 20), the test inputs
     alone, and one network's prediction of one scene;

   each on ``cuda`` against the named baseline, the CPU with a job's Torch threads (1). Where a
   GPU runs, the CPU takes the GPU's steps and checks at its own rates (``--twin-steps`` of
   a twin, a check timed alone; ``--cpu-plateau`` trains to the plateau there too) and
   tests ``--cpu-test-seeds`` networks per group with the GPU's weights (tiles with equal
   hits show that both devices predict alike). Last, the probe stage of the preset and of
   the default ``config.yaml`` (networks and test jobs counted from the configs: conditions,
   variants, planted factors, architectures, seeds and folds) projected from these rates, on
   each device with the jobs one after another and on 2 CPU cores (the baseline's jobs two
   at a time), with their ratios.

``--json PATH`` writes every number. ``--tiny`` runs everything at a small size (a check that
it works on any machine; its rates mean nothing).

Usage::

    python bench/gpu.py --json gpu.json          # on a machine with an NVIDIA GPU
    python bench/gpu.py --no-render --json gpu.json   # the probe alone (about 4 min)
    .venv/bin/python bench/gpu.py --tiny --no-render  # quick check of the probe, CPU only
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


PROBE_CONFIGS = {
    "preset": ("config.yaml", "workflow/presets/probe.yaml"),
    "default": ("config.yaml",),
}
"""The configs whose probe stage is projected: the full-power preset and the default."""

TEST_GROUPS = (("none", "main"), ("none", "twin"), ("sensor_only", "main"))
"""The networks of one test job: the tested condition's, its twins and the control's."""


def probe_config(name: str) -> dict:
    """A merged config of :data:`PROBE_CONFIGS` with the schema's defaults."""
    from stereovar.config import load_config

    return load_config([str(REPO / p) for p in PROBE_CONFIGS[name]], SCHEMA)


def probe_workload(config: dict) -> dict:
    """What a config's probe stage trains and tests, per architecture.

    ``mains``: networks trained to a plateau, each with the validation frames of its fold
    (one per training scene); ``twins``: cue-blind twins (every condition but
    ``sensor_only``), each trained for its network's best step; ``tests``: one
    ``(held-out scenes, networks)`` per test job (condition x fold), the networks being the
    condition's and its twins' plus the control's, ``train_seeds`` each."""
    from stereovar.probe.conditions import CONTROL, probe_conditions
    from stereovar.probe.experiment import fold_scenes

    probe = config["probe"]
    seeds = int(probe["train_seeds"])
    folds = fold_scenes(config["scenes"], int(probe["folds"]))
    conditions = probe_conditions(config)
    validating = int(config["render"]["n_seeds"]) >= 2
    work = {}
    for arch in dict.fromkeys(probe["architectures"]):
        mains, twins, tests = [], 0, []
        for c in conditions:
            for train, held in folds:
                mains += [len(train) if validating else 0] * seeds
                twins += seeds if c.twin else 0
                nets = seeds * len(c.variants) + (seeds if c.name != CONTROL else 0)
                tests.append((len(held), nets))
        work[arch] = {"mains": mains, "twins": twins, "tests": tests}
    return {
        "conditions": [c.name for c in conditions],
        "architectures": list(work),
        "folds": len(folds),
        "train_seeds": seeds,
        "per_architecture": work,
    }


def workload_seconds(work: dict, cost: dict) -> dict:
    """Seconds of one architecture's training and test jobs at ``cost``: ``main`` (a network
    to its plateau, checks excluded), ``check_frame`` (one validation frame of one check),
    ``checks`` (checks per network), ``twin``, ``pairs`` (a held-out scene's test inputs)
    and ``net_scene`` (one network's prediction and scoring of one held-out scene)."""
    train = sum(cost["main"] + cost["checks"] * cost["check_frame"] * v for v in work["mains"])
    train += work["twins"] * cost["twin"]
    test = sum(h * (cost["pairs"] + n * cost["net_scene"]) for h, n in work["tests"])
    return {"train_s": train, "test_s": test, "total_s": train + test}


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def probe_data(args, config: dict) -> dict:
    """Synthetic scenes in the preset's shape: training frames of one fold (its training
    scenes x N, the last seed index of each held out for validation), the twin's frames,
    the validation bands, and held-out test scenes."""
    from probe import SIGN

    from stereovar.probe.experiment import (
        fold_scenes,
        split_validation,
        training_frames,
        validation_band,
    )

    probe = config["probe"]
    height, width = config["resolution"]["height"], config["resolution"]["width"]
    n = int(config["render"]["n_seeds"])
    train_scenes = len(fold_scenes(config["scenes"], int(probe["folds"]))[0][0])
    test_scenes = args.test_scenes
    if args.tiny:
        height, width, n, train_scenes = 64, 160, 3, 2
    scenes = [synthetic_scene(height, width, n, seed=s) for s in range(train_scenes)]
    variants = {}
    for twin in (False, True):
        variants[twin] = split_validation(
            [
                training_frames(left, right, truth, sign=SIGN, twin=twin, strata=probe["strata"])
                for left, right, truth in scenes
            ]
        )
    frames, validation = variants[False]
    return {
        "height": height,
        "width": width,
        "n": n,
        "train_scenes": train_scenes,
        "frames": frames,
        "twin_frames": variants[True][0],
        "band": validation_band(validation, rows=probe["validation_rows"]),
        "validation_rows": probe["validation_rows"],
        "test": [synthetic_scene(height, width, n, seed=100 + s) for s in range(test_scenes)],
    }


def train_measure(entry, settings, data, device: str, args, *, plateau: bool) -> dict:
    """One architecture's training on ``device``: a network to its plateau on the validation
    bands and its twin for the network's best step (``plateau``), ``--fixed-steps`` steps
    without checks, a twin's steps without checks (``--twin-steps``, where no plateau runs),
    and the seconds of one validation check."""
    from dataclasses import replace

    frames, twins, band = data["frames"], data["twin_frames"], data["band"]
    out = {}
    entry.train(frames, replace(settings, steps=3), seed=0, device=device)  # warm-up
    if plateau:
        net, h = entry.train(frames, settings, seed=0, device=device, validation=band)
        checks = max(len(h["validation"]), 1)
        out["plateau"] = {
            "steps": h["steps"],
            "best_step": h["best_step"],
            "seconds": h["seconds"],
            "step_s": h["step_seconds"],
            "checks": len(h["validation"]),
            "check_s": h["validation_seconds"] / checks,
            "best_accuracy": max((a for _, a in h["validation"]), default=float("nan")),
        }
        out["net"] = net
        _, t = entry.train(
            twins, replace(settings, steps=max(int(h["best_step"]), 1)), seed=0, device=device
        )
        out["twin"] = {"steps": t["steps"], "seconds": t["seconds"], "step_s": t["step_seconds"]}
    else:
        _, t = entry.train(twins, replace(settings, steps=args.twin_steps), seed=0, device=device)
        out["twin_fixed"] = {
            "steps": t["steps"],
            "seconds": t["seconds"],
            "step_s": t["step_seconds"],
        }
        two = replace(settings, steps=2, check_every=1, min_steps=0)
        _, c = entry.train(frames, two, seed=0, device=device, validation=band)
        out["check_s"] = c["validation_seconds"] / max(len(c["validation"]), 1)
    _, f = entry.train(frames, replace(settings, steps=args.fixed_steps), seed=0, device=device)
    out["fixed"] = {
        "steps": f["steps"],
        "seconds": f["seconds"],
        "step_s": f["step_seconds"],
        "first_losses": f["loss"][:3],
    }
    return out


def test_measure(entry, net, data, device: str, per_group: int, test) -> dict:
    """One test job on ``device``: ``per_group`` copies of ``net`` for each of
    :data:`TEST_GROUPS` on every held-out scene (:func:`~stereovar.probe.experiment.test_scene`),
    the seconds of the test inputs alone per scene, and of one network's prediction of one
    scene's inputs."""
    import copy

    import numpy as np
    from probe import SIGN

    from stereovar.probe.experiment import scene_law, test_pairs, test_scene

    nets = {
        (c, v, j): copy.deepcopy(net).to(device) for c, v in TEST_GROUPS for j in range(per_group)
    }
    scenes = [
        (left, right, truth, scene_law(left, truth["valid"])) for left, right, truth in data["test"]
    ]
    regions = ("all", "non_glass", "glass")
    left, right, truth, law = scenes[0]
    small = {k: v[:40, :120] for k, v in truth.items()}
    one = dict(list(nets.items())[:1])
    test_scene(
        one,
        entry.predict,
        left[:2, :40, :120],
        right[:2, :40, :120],
        small,
        scene="warm",
        sign=SIGN,
        regions=regions,
        law=law,
        settings=test,
    )  # warm-up
    t0 = time.perf_counter()
    pairs = [
        test_pairs(lf, rt, scene=f"s{i}", sign=SIGN, law=lw, settings=test)
        for i, (lf, rt, _, lw) in enumerate(scenes)
    ]
    pairs_s = (time.perf_counter() - t0) / len(scenes)
    t0 = time.perf_counter()
    entry.predict(
        next(iter(nets.values())),
        list(pairs[0].values()),
        sign=SIGN,
        max_disparity=test.max_disparity,
    )
    predict_s = time.perf_counter() - t0
    rows = []
    t0 = time.perf_counter()
    for i, (lf, rt, tr, lw) in enumerate(scenes):
        rows += test_scene(
            nets,
            entry.predict,
            lf,
            rt,
            tr,
            scene=f"s{i}",
            sign=SIGN,
            regions=regions,
            law=lw,
            settings=test,
        )
    seconds = time.perf_counter() - t0
    hits = {}
    for r in rows:
        key = (
            r["network"],
            r["variant"],
            r["train_seed"],
            r["test_input"],
            r["region"],
            r["scene"],
            r["tile"],
        )
        hits[key] = r["hits"]
    net_scene = max(seconds - pairs_s * len(scenes), 0.0) / (len(nets) * len(scenes))
    return {
        "networks": len(nets),
        "scenes": len(scenes),
        "pairs_per_scene": len(pairs[0]),
        "seconds": seconds,
        "pairs_s": pairs_s,
        "predict_s": predict_s,
        "net_scene_s": net_scene,
        "scoring_share": float(np.clip(1 - predict_s / net_scene, 0, 1)) if net_scene else None,
        "hits": hits,
    }


def _cost(run: dict, plateau_of: dict, validation_frames: int) -> dict:
    """The per-unit seconds of :func:`workload_seconds` from one device's measurements;
    ``plateau_of`` gives the steps, checks and best step (this device's plateau where it ran
    one, else the GPU's)."""
    p = plateau_of
    if "plateau" in run:
        main = run["plateau"]["seconds"] - run["plateau"]["checks"] * run["plateau"]["check_s"]
        check = run["plateau"]["check_s"]
        twin = run["twin"]["seconds"]
    else:  # steps and checks of the GPU's plateau at this device's rates
        main = p["steps"] * run["fixed"]["step_s"]
        check = run["check_s"]
        twin = p["best_step"] * run["twin_fixed"]["step_s"]
    test = run["test"]
    return {
        "main": main,
        "checks": run["plateau"]["checks"] if "plateau" in run else p["checks"],
        "check_frame": check / max(validation_frames, 1),
        "twin": twin,
        "pairs": test["pairs_s"],
        "net_scene": test["net_scene_s"],
    }


def _agreement(a: dict, b: dict) -> float | None:
    common = set(a) & set(b)
    return sum(a[k] == b[k] for k in common) / len(common) if common else None


def probe_part(args, report: dict) -> None:
    """Section 2 of the module docstring."""
    from dataclasses import replace

    import torch

    from stereovar.probe.architectures import architecture
    from stereovar.probe.experiment import TestSettings

    config = probe_config("preset")
    probe = config["probe"]
    data = probe_data(args, config)
    test = TestSettings(
        test_frames=probe["test_frames"],
        max_disparity=args.max_disparity,
        strata=probe["strata"],
        conflict_shift=probe["conflict_shift"],
        tile=config["analysis"]["bootstrap"]["tile"],
    )
    cuda = torch.cuda.is_available()
    base = "cpu (1 thread)"
    devices = (["cuda"] if cuda else []) + [base]
    if not cuda:
        print("probe: no CUDA device visible to PyTorch; the CPU only (networks to a plateau)")
    else:
        print(f"probe: {torch.cuda.get_device_name(0)}, torch {torch.__version__}")
    print(
        f"probe: synthetic {data['width']}x{data['height']} scenes (disparity 1-13 px), "
        f"{data['train_scenes']} training scenes x N = {data['n']}: {len(data['frames'])} "
        f"training frames, {len(data['band'])} validation bands of {data['validation_rows']} "
        f"rows; test job: {len(data['test'])} held-out scenes x {test.test_frames} frames x "
        f"{len(test.inputs)} inputs, D = {test.max_disparity}; the named baseline: {base} "
        f"(a job's Torch threads)"
    )
    results = {}
    for arch in dict.fromkeys(probe["architectures"]):
        entry = architecture(arch)
        settings = entry.settings(probe[entry.config_key])
        if args.tiny:
            settings = replace(settings, steps=12, check_every=4, patience=1, min_steps=4)
        runs = {}
        for device in devices:
            name = "cuda" if device == "cuda" else base
            dev = "cuda" if device == "cuda" else "cpu"
            torch.set_num_threads(1)
            plateau = dev == "cuda" or not cuda or args.cpu_plateau
            run = train_measure(entry, settings, data, dev, args, plateau=plateau)
            net = run.pop("net", None)
            if "cuda" in runs:  # the GPU's network: both devices test the same weights
                net = runs["cuda"]["_net"]
            per_group = args.test_seeds if dev == "cuda" or not cuda else args.cpu_test_seeds
            torch.set_num_threads(1)
            run["test"] = test_measure(entry, net, data, dev, per_group, test)
            run["_net"] = net
            runs[name] = run
        ref = runs[devices[0] if devices[0] == "cuda" else base]["plateau"]
        for run in runs.values():
            run["cost"] = _cost(run, ref, len(data["band"]))
            run.pop("_net")
        results[arch] = {"label": entry.label, "settings": vars(settings), "runs": runs}
        print_arch(arch, entry.label, settings, runs, base, len(data["band"]))
    print(
        "  projections: every network and test job of a config at the rates above, jobs one "
        "after another on one device (their CPU parts included); 2 CPU cores: the baseline's "
        "1-thread jobs two at a time; store reads, planting and job starts not included"
    )
    projections = {}
    for key in PROBE_CONFIGS:
        projections[key] = project(key, results, base, args)
    for arch in results:
        for run in results[arch]["runs"].values():
            run["test"].pop("hits")
    report["probe"] = {
        "data": {k: data[k] for k in ("height", "width", "n", "train_scenes", "validation_rows")},
        "test_settings": {k: v for k, v in vars(test).items()},
        "baseline": base,
        "architectures": results,
        "projection": projections,
    }


def print_arch(arch, label, settings, runs, base, bands: int) -> None:
    """One architecture's measurements on each device and the ratios to the baseline."""
    print(
        f"  {arch} ({label}): steps cap {settings.steps}, a check every {settings.check_every}, "
        f"patience {settings.patience}, min_delta {settings.min_delta}, min_steps "
        f"{settings.min_steps}, {settings.crops} crops of {settings.crop_rows}x"
        f"{settings.crop_cols}"
    )
    for name, r in runs.items():
        p, f, t = r.get("plateau"), r["fixed"], r["test"]
        if p:
            line = (
                f"plateau {p['steps']} steps (best {p['best_step']}, accuracy "
                f"{p['best_accuracy']:.3f}) {p['seconds']:.1f} s ({1e3 * p['step_s']:.1f} ms/step, "
                f"{p['checks']} checks x {p['check_s']:.2f} s); twin {r['twin']['steps']} steps "
                f"{r['twin']['seconds']:.1f} s ({1e3 * r['twin']['step_s']:.1f} ms/step)"
            )
        else:
            c = r["cost"]
            own = c["main"] + c["checks"] * r["check_s"]
            line = (
                f"no plateau run (--cpu-plateau runs one): the GPU's steps and {c['checks']} "
                f"checks x {r['check_s']:.2f} s at this device's rates give {own:.1f} s; "
                f"twin {r['twin_fixed']['steps']} steps {1e3 * r['twin_fixed']['step_s']:.1f} "
                f"ms/step -> {c['twin']:.1f} s for the best step"
            )
        print(f"    {name:15s} {line}")
        print(
            f"    {'':15s} {f['steps']} fixed steps {f['seconds']:.1f} s = "
            f"{1e3 * f['step_s']:.2f} ms/step (first loss {f['first_losses'][0]:.5f}); test of "
            f"{t['networks']} networks x {t['scenes']} scenes {t['seconds']:.1f} s "
            f"({t['pairs_s']:.2f} s inputs per scene, {t['net_scene_s']:.2f} s per "
            f"network-scene, of which {t['predict_s']:.2f} s prediction)"
        )
    b = runs.get(base)
    for name, r in runs.items():
        if r is b or b is None:
            continue
        ratios = {
            "fixed_step": b["fixed"]["step_s"] / r["fixed"]["step_s"],
            "plateau_network": _network_s(b, bands) / _network_s(r, bands),
            "twin": b["cost"]["twin"] / r["cost"]["twin"],
            "test_job": _test_job_s(b) / _test_job_s(r),
            "hits_agree": _agreement(r["test"]["hits"], b["test"]["hits"]),
        }
        r["ratios_to_baseline"] = ratios
        agree = ratios["hits_agree"]
        print(
            f"    {name} against {base}: {ratios['fixed_step']:.1f}x per fixed step, "
            f"{ratios['plateau_network']:.1f}x a network to its plateau, {ratios['twin']:.1f}x "
            f"a twin, {ratios['test_job']:.1f}x a test job of 9 networks x 2 scenes; tiles "
            f"with equal hits (same weights) "
            f"{'n/a' if agree is None else f'{100 * agree:.2f}%'}"
        )


def _network_s(run: dict, bands: int) -> float:
    """Seconds of one network to its plateau with ``bands`` validation frames."""
    c = run["cost"]
    return c["main"] + c["checks"] * c["check_frame"] * bands


def _test_job_s(run: dict, scenes: int = 2, networks: int = 9) -> float:
    """Seconds of a test job of ``networks`` networks on ``scenes`` held-out scenes."""
    c = run["cost"]
    return scenes * (c["pairs"] + networks * c["net_scene"])


def project(key: str, results: dict, base: str, args) -> dict:
    """The probe stage's training and test seconds of config ``key`` on each device measured
    (jobs one after another) and on 2 CPU cores (1-thread jobs two at a time)."""
    config = probe_config(key)
    work = probe_workload(config)
    paths = " + ".join(PROBE_CONFIGS[key])
    per = work["per_architecture"]
    print(
        f"  projection, {paths}: {len(work['conditions'])} conditions "
        f"({', '.join(work['conditions'])}) x {len(work['architectures'])} architectures x "
        f"{work['folds']} folds x {work['train_seeds']} seeds; "
        + "; ".join(
            f"{arch}: {len(w['mains'])} networks to a plateau + {w['twins']} twins, "
            f"{len(w['tests'])} test jobs ({sum(h for h, _ in w['tests'])} scene tests, "
            f"{sum(h * n for h, n in w['tests'])} network-scenes)"
            for arch, w in per.items()
        )
    )
    out = {"configs": list(PROBE_CONFIGS[key]), "workload": work, "devices": {}}
    devices = {}
    for arch, w in per.items():
        if arch not in results:
            continue
        for name, run in results[arch]["runs"].items():
            seconds = workload_seconds(w, run["cost"])
            d = devices.setdefault(name, {"train_s": 0.0, "test_s": 0.0, "total_s": 0.0})
            for k in ("train_s", "test_s", "total_s"):
                d[k] += seconds[k]
            d.setdefault("per_architecture", {})[arch] = seconds
    if base in devices:
        cpu = devices[base]
        devices["2 CPU cores"] = {k: cpu[k] / 2 for k in ("train_s", "test_s", "total_s")}
    for name, d in devices.items():
        extra = ""
        if name not in ("2 CPU cores", base) and "2 CPU cores" in devices:
            two = devices["2 CPU cores"]["total_s"]
            d["speedup_vs_2_cores"] = two / d["total_s"]
            extra = f"; {d['speedup_vs_2_cores']:.1f}x the speed of 2 CPU cores"
        print(
            f"    {name:15s} training {d['train_s'] / 60:8.1f} min + test "
            f"{d['test_s'] / 60:8.1f} min = {d['total_s'] / 3600:6.2f} h{extra}"
        )
    out["devices"] = devices
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="scene_000")
    parser.add_argument("--variants", nargs="*", default=["cuda_ad_rgb", "llvm_ad_rgb"])
    parser.add_argument("--spp", type=int, default=512, help="SPP of GPU variants")
    parser.add_argument("--seeds", type=int, default=4, help="seed indices of GPU variants")
    parser.add_argument("--cpu-spp", type=int, default=64, help="SPP of CPU variants")
    parser.add_argument("--cpu-seeds", type=int, default=1, help="seed indices of CPU variants")
    parser.add_argument("--tiny", action="store_true", help="small sizes: a check that it runs")
    parser.add_argument("--no-render", action="store_true", help="skip the renders (part 1)")
    parser.add_argument("--no-probe", action="store_true", help="skip the probe (part 2)")
    parser.add_argument(
        "--fixed-steps",
        type=int,
        default=200,
        help="probe: steps of the fixed-step training on each device",
    )
    parser.add_argument(
        "--twin-steps",
        type=int,
        default=100,
        help="probe: steps of the CPU's twin rate (without --cpu-plateau)",
    )
    parser.add_argument(
        "--cpu-plateau",
        action="store_true",
        help="probe: train to the plateau and the twin on the CPU as well",
    )
    parser.add_argument("--test-scenes", type=int, default=2, help="probe: held-out scenes")
    parser.add_argument(
        "--test-seeds",
        type=int,
        default=3,
        help="probe: networks per group (condition, twin, control) of the test",
    )
    parser.add_argument(
        "--cpu-test-seeds",
        type=int,
        default=1,
        help="probe: the same on the CPU where a GPU runs the full test",
    )
    parser.add_argument("--max-disparity", type=int, default=20, help="probe: D of the test")
    parser.add_argument("--json", help="write every number to this file")
    args = parser.parse_args(argv)
    if args.tiny:
        args.spp, args.seeds, args.cpu_spp, args.cpu_seeds = 8, 2, 8, 1
        args.fixed_steps, args.twin_steps, args.test_seeds, args.cpu_test_seeds = 4, 4, 1, 1
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
