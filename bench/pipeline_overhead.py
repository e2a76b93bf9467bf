"""Pipeline overhead of the render stage: `snakemake -j2` against a bare in-process loop.

Both sides render exactly the same (scene, view, spp, seed) list of the given config with the
same seeds and thread count. The baseline is one Python process that loads each scene once and
calls ``mi.render`` in a loop (no files written); the pipeline is ``snakemake -j2`` on the
render stores in a fresh copy of the workflow (process start-up, scene compilation per job,
atomic zarr writes, Snakemake's own scheduling). It prints the ratio pipeline / baseline.

Usage::

    .venv/bin/python bench/pipeline_overhead.py                  # the default config.yaml
    .venv/bin/python bench/pipeline_overhead.py --scenes 1       # a quicker subset
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow/schemas/config.schema.yaml"

BARE_LOOP = r"""
import json, sys, time
start = time.perf_counter()
from stereovar.renderers.mitsuba.backend import load_mitsuba
from stereovar.experiment import VIEWS, scene_spp_pairs
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.renderers.mitsuba.render import render_view
from stereovar.renderers.mitsuba.sensor import integrator_dict
from stereovar.seeding import derive_seed
from stereovar.rig import make_rig
from stereovar.scenes.spec import load_scene_spec
import drjit as dr

config = json.loads(sys.argv[1])
r = config["render"]
mi = load_mitsuba(r["variant"])
dr.set_thread_count(2)
integ = integrator_dict(r["integrator"], r["max_depth"])
by_scene = {}
for scene, spp in scene_spp_pairs(config):
    by_scene.setdefault(scene, []).append(spp)
samples = 0
for name, spps in by_scene.items():
    spec = load_scene_spec(f"scenes/{name}.yaml")
    scene, cam = load_scene(mi, spec)
    rig = make_rig(cam.to_world, cam.fov_deg, width=config["resolution"]["width"],
                   height=config["resolution"]["height"],
                   baseline_m=config["rig"]["baseline_m"], convention=config["rig"]["convention"])
    for spp in spps:
        for view in VIEWS:
            for index in range(r["n_seeds"]):
                render_view(mi, scene, rig, view, spp=spp, seed=derive_seed(name, view, spp, index),
                            integrator=integ, rfilter=r["rfilter"], sampler=r["sampler"])
                samples += rig.width * rig.height * spp
print(json.dumps({"seconds": time.perf_counter() - start, "samples": samples}))
"""


def load_config(paths: list[Path]) -> dict:
    from stereovar.config import load_config as load

    return load([str(p) for p in paths], SCHEMA)


def copy_workflow(dest: Path, config: dict) -> None:
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, dest / name)
    for name in ("workflow", "profiles", "envs", "scenes"):
        shutil.copytree(REPO / name, dest / name)
    (dest / "bench.yaml").write_text(yaml.safe_dump(config))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--configfile",
        type=Path,
        action="append",
        default=[],
        help="config files merged over config.yaml (like snakemake's)",
    )
    parser.add_argument("--scenes", type=int, help="use only the first N scenes")
    parser.add_argument("--no-sweep", action="store_true", help="drop the SPP sweep")
    args = parser.parse_args(argv)

    config = load_config([REPO / "config.yaml", *args.configfile])
    if args.scenes:
        config["scenes"] = config["scenes"][: args.scenes]
        config["render"]["spp_sweep"]["scene"] = config["scenes"][0]
    if args.no_sweep:
        config["render"]["spp_sweep"]["spp"] = [config["render"]["spp"]]
    from stereovar.experiment import render_stores, scene_spp_pairs, seed_batches

    targets = render_stores(config)
    render = config["render"]
    n_jobs = len(scene_spp_pairs(config)) * len(
        seed_batches(render["n_seeds"], render["seeds_per_job"])
    )

    with tempfile.TemporaryDirectory(prefix="stereovar-bench-") as tmp:
        work = Path(tmp)
        copy_workflow(work, config)
        start = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "snakemake", "-j2", *targets, "--configfile", "bench.yaml"],
            cwd=work,
            capture_output=True,
            text=True,
        )
        pipeline = time.perf_counter() - start
        if proc.returncode != 0:
            print(proc.stdout[-3000:], proc.stderr[-3000:], file=sys.stderr)
            return 1
        bare = subprocess.run(
            [sys.executable, "-c", BARE_LOOP, json.dumps(config)],
            cwd=work,
            capture_output=True,
            text=True,
            check=True,
        )
        baseline = json.loads(bare.stdout.strip().splitlines()[-1])

    ratio = pipeline / baseline["seconds"]
    print(
        f"renders: {len(targets)} stores in {n_jobs} jobs, "
        f"{baseline['samples'] / 1e6:.0f} M samples, "
        f"{config['resolution']['width']}x{config['resolution']['height']}"
    )
    print(
        f"baseline (bare mi.render loop, one process): {baseline['seconds']:.1f} s "
        f"({baseline['samples'] / baseline['seconds'] / 1e6:.2f} M samples/s)"
    )
    print(
        f"pipeline (snakemake -j2, seeds_per_job={config['render']['seeds_per_job']}): "
        f"{pipeline:.1f} s"
    )
    print(f"ratio pipeline / baseline: {ratio:.3f} (goal <= 1.15)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
