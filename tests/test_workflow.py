"""Tiny end-to-end Snakemake runs: outputs, no-op reruns, partial reruns, config errors."""

import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from stereovar.io.store import open_dataset
from stereovar.io.tables import read_rows
from stereovar.statistics.registry import METHODS

REPO = Path(__file__).resolve().parents[1]
SCENES = ["scene_000", "scene_001"]
TINY = {
    "scenes": SCENES,
    "resolution": {"width": 48, "height": 27},
    "render": {
        "spp": 2,
        "n_seeds": 2,
        "seeds_per_job": 2,
        "spp_sweep": {"scene": "scene_000", "spp": [1, 2]},
    },
    "preview": {"spp": 4},
    "mitigations": {"names": []},  # tests/test_mitigations.py runs the mitigations
    # one replicate through a denoiser: the denoising rows' jobs run, at a fraction of their cost
    "calibration": {"replicates": 4, "denoised_replicates": 1},
}
#: Jobs that depend on one non-sweep scene at the main SPP.
SCENE_CHAIN = {"render": 1, "variance": 1, "warp": 1, "correlation": 1}
SUMMARIES = {
    "statistics_table": 1,
    "rho_vs_seeds_figure": 1,
    "statistics_dot_figure": 1,
    "claims": 1,
    "results_page": 1,
}
"""Jobs downstream of every scene's correlation rows."""
RUN = "results/mitsuba/seeds"

pytestmark = pytest.mark.workflow


def snakemake(workdir, *args, check=True, config=None, env=None):
    """Run snakemake on the tiny config, plus ``config`` overrides merged on top, with ``env``
    changes (None removes a variable)."""
    files = ["tiny.yaml"]
    if config:
        (workdir / "override.yaml").write_text(yaml.safe_dump(config))
        files.append("override.yaml")
    environ = dict(os.environ)
    for key, value in (env or {}).items():
        if value is None:
            environ.pop(key, None)
        else:
            environ[key] = value
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "--configfile", *files, *args],
        cwd=workdir,
        capture_output=True,
        text=True,
        env=environ,
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


def planned_jobs(workdir, *targets, config=None) -> dict:
    """Job counts per rule of a dry run (empty when nothing is to be done)."""
    out = snakemake(workdir, "-n", *targets, config=config).stdout
    counts = {}
    if "Job stats:" not in out:
        return counts
    table = out.split("Job stats:", 1)[1]
    for line in table.splitlines()[3:]:
        m = re.match(r"^(\w+)\s+(\d+)$", line.strip())
        if not m:
            break
        counts[m.group(1)] = int(m.group(2))
    counts.pop("total", None)
    return counts


def copy_workflow(root: Path, config: dict) -> Path:
    """A copy of the workflow in ``root`` with the tiny scenes and ``config`` as tiny.yaml."""
    root.mkdir(parents=True, exist_ok=True)
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    for name in ("workflow", "profiles", "envs"):
        shutil.copytree(REPO / name, root / name)
    (root / "scenes").mkdir()
    for scene in SCENES:
        shutil.copy(REPO / "scenes" / f"{scene}.yaml", root / "scenes")
    (root / "tiny.yaml").write_text(yaml.safe_dump(config))
    return root


@pytest.fixture(scope="module")
def workdir(tiny_run):
    """A copy of the workflow with two scenes, run once to completion (shared with other
    modules: a test that changes it puts it back)."""
    return tiny_run


def test_run_produces_ground_truth_previews_and_tables(workdir):
    for scene in SCENES:
        ds = open_dataset(workdir / f"results/ground_truth/{scene}.zarr")
        assert set(ds.data_vars) >= {"disparity", "depth", "material", "glass", "valid"}
        assert dict(ds.sizes) == {"view": 2, "y": 27, "x": 48}
        assert ds.attrs["convention"] == "paper" and ds.attrs["disparity_sign"] == 1
        assert ds.attrs["scene"] == scene and len(ds.attrs["scene_digest"]) == 64
        assert np.isfinite(ds.disparity.values).all()
        png = workdir / f"results/mitsuba/previews/{scene}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (workdir / f"logs/ground_truth/{scene}.log").is_file()
    for scene, spp in (("scene_000", 1), ("scene_000", 2), ("scene_001", 2)):
        rows = (workdir / f"{RUN}/correlation/{scene}/spp{spp}.csv").read_text().splitlines()
        assert rows[0].startswith("scene,spp,n_seeds,region,method,rho,n_pixels,fisher_low")
        assert rows[0].endswith(",renderer,estimator") and rows[1].endswith(",mitsuba,seeds")
        assert len(rows) == 1 + 3 * len(METHODS)
        renders = [
            open_dataset(workdir / f"results/mitsuba/renders/{scene}/{v}/spp{spp}/seeds0-1.zarr")
            for v in ("left", "right")
        ]
        assert len({s for r in renders for s in r["sampler_seed"].values.tolist()}) == 4
        assert all(r["seed"].values.tolist() == [0, 1] for r in renders)
        var = open_dataset(workdir / f"{RUN}/variance/{scene}/spp{spp}.zarr")
        assert dict(var["variance"].sizes) == {"view": 2, "y": 27, "x": 48}
        assert var.attrs["n_seeds"] == 2
        assert var.attrs["estimator"] == "seeds" and var.attrs["renderer"] == "mitsuba"
        assert var["variance"].attrs["units"] == "W2 m-4 sr-2"
        warped = open_dataset(workdir / f"{RUN}/warped/{scene}/spp{spp}.zarr")
        assert warped["warped_variance"].attrs["units"] == "W2 m-4 sr-2"
        assert warped["x"].attrs["units"] == "px"
    for scene in SCENES:
        rows = (workdir / f"{RUN}/intervention/{scene}.csv").read_text().splitlines()
        assert rows[0].startswith("scene,spp,n_seeds,max_disparity,window,block,source,cost,metric")
        # 5 metrics x 3 regions (all, non_glass, glass) x 2 conditions x render and sensor
        assert len(rows) == 1 + 5 * 3 * 2 * 2
        margins = (workdir / f"{RUN}/intervention/margins/{scene}.csv").read_text()
        assert margins.startswith("scene,cost,region,condition,seed,y,x,margin")
    for name in ("cross_scene", "spp_sweep", "spp_sweep_fit", "intervention"):
        for ext in ("csv", "md", "tex"):
            assert (workdir / f"{RUN}/tables/{name}.{ext}").stat().st_size > 0
        md = (workdir / f"{RUN}/tables/{name}.md").read_text()
        assert "renderer mitsuba, estimator seeds" in md.splitlines()[0]
    for fig in (
        "fig1_teaser",
        "fig2_rho_vs_spp",
        "fig3_material_scatter",
        "fig4_intervention_margins",
    ):
        assert (workdir / f"{RUN}/figures/{fig}.png").read_bytes()[:4] == b"\x89PNG"
    csv = (workdir / "results/tables/scenes.csv").read_text().splitlines()
    assert csv[0].startswith("scene,") and len(csv) == 1 + len(SCENES)
    assert (workdir / "results/tables/scenes.tex").read_text().count(r"\\") >= 1 + len(SCENES)
    # Committed specs are inputs, never regenerated (no generate_scene job ran).
    assert not (workdir / "logs/scenes").exists()
    for scene in SCENES:
        spec = f"scenes/{scene}.yaml"
        assert (workdir / spec).read_bytes() == (REPO / spec).read_bytes()
    leftovers = [p for p in (workdir / "results").rglob(".*tmp-*")]
    assert not leftovers


def test_second_run_does_nothing(workdir):
    assert planned_jobs(workdir, "all") == {}


def test_editing_one_scene_reruns_only_that_scene(workdir):
    spec = workdir / "scenes/scene_001.yaml"
    original = spec.read_text()
    data = yaml.safe_load(original)
    data["camera"]["fov_deg"] += 1.0
    time.sleep(0.01)
    spec.write_text(yaml.safe_dump(data, sort_keys=False))
    try:
        jobs = planned_jobs(workdir, "all")
        assert jobs == {
            "ground_truth": 1,
            "preview": 1,
            "scene_summary": 1,
            **SCENE_CHAIN,
            "cross_scene_table": 1,
            "intervention": 1,
            "intervention_table": 1,
            "margin_figure": 1,
            "calibration_scene": 1,
            "calibration_table": 1,
            **SUMMARIES,
            "all": 1,
        }
        out = snakemake(workdir, "-n", "all").stdout
        assert "wildcards: scene=scene_001" in out and "wildcards: scene=scene_000" not in out
    finally:
        spec.write_text(original)
    # Back to the content the results were made from: nothing to do (content, not mtime).
    assert planned_jobs(workdir, "all") == {}


def test_changing_preview_spp_rerenders_only_previews(workdir):
    jobs = planned_jobs(workdir, "all", config={"preview": {"spp": 2}})
    assert jobs == {"preview": 2, "all": 1}


def test_single_target_builds_only_what_it_needs(workdir):
    jobs = planned_jobs(
        workdir, "results/ground_truth/scene_000.zarr", "--forcerun", "ground_truth"
    )
    assert jobs == {"ground_truth": 1}
    target = f"{RUN}/correlation/scene_001/spp2.csv"
    assert planned_jobs(workdir, target, "--forceall") == {"ground_truth": 1, **SCENE_CHAIN}
    assert "scene_000" not in snakemake(workdir, "-n", target, "--forceall").stdout


def test_analysis_parameter_change_renders_nothing(workdir):
    jobs = planned_jobs(workdir, "all", config={"analysis": {"min_pixels": 40}})
    assert jobs == {
        "correlation": 3,
        "cross_scene_table": 1,
        "spp_sweep_table": 1,
        "rho_vs_spp_figure": 1,
        "calibration_scene": 2,
        "calibration_table": 1,
        **SUMMARIES,
        "all": 1,
    }


def test_adding_seeds_renders_only_the_new_seeds(workdir):
    config = {"render": {"n_seeds": 4}}
    jobs = planned_jobs(workdir, "all", config=config)
    assert jobs["render"] == 3 and jobs["variance"] == 3 and "ground_truth" not in jobs
    out = snakemake(workdir, "-n", "all", config=config).stdout
    assert "batch=2-3" in out and "batch=0-1" not in out


def test_bad_config_stops_before_any_job_with_one_line(workdir):
    gt = workdir / "results/ground_truth/scene_000.zarr"
    before = gt.stat().st_mtime
    proc = snakemake(workdir, "-j2", "all", config={"rig": {"convention": "left"}}, check=False)
    assert proc.returncode != 0
    text = proc.stdout + proc.stderr
    assert "Traceback" not in text
    lines = [ln for ln in text.splitlines() if "rig.convention" in ln]
    assert lines and "paper" in lines[0] and "conventional" in lines[0]
    assert gt.stat().st_mtime == before
    assert not re.search(r"^rule \w+:", proc.stdout, flags=re.M)


def test_missing_generated_scene_is_generated_by_its_rule(workdir):
    jobs = planned_jobs(workdir, "all", config={"scenes": ["scene_000", "scene_007"]})
    assert jobs.get("generate_scene") == 1
    assert jobs.get("ground_truth") == 1


def test_unknown_scene_without_spec_is_one_line_error(workdir):
    config = {"scenes": ["my_room"], "render": {"spp_sweep": {"scene": "my_room"}}}
    proc = snakemake(workdir, "-n", "all", config=config, check=False)
    assert proc.returncode != 0
    assert "my_room" in proc.stdout + proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr


def job_resources(dry_run: str) -> dict:
    """Rule name -> list of its jobs' resource dicts, from a dry run's listing."""
    jobs: dict = {}
    rule = None
    for line in dry_run.splitlines():
        m = re.match(r"^\s*(?:local)?rule (\w+):$", line)
        if m:
            rule = m.group(1)
        elif rule and line.strip().startswith("resources:"):
            items = dict(kv.split("=", 1) for kv in line.split(":", 1)[1].strip().split(", "))
            jobs.setdefault(rule, []).append(items)
            rule = None
    return jobs


def test_cluster_profiles_size_jobs_and_request_gpus_for_renders_only(workdir):
    for profile, gpus in (("profiles/slurm", None), ("profiles/slurm-gpu", "1")):
        proc = snakemake(workdir, "--profile", profile, "--executor", "dryrun", "all", "--forceall")
        jobs = job_resources(proc.stdout + proc.stderr)
        renders = jobs["render"]
        assert len(renders) == 3
        assert all(r.get("gpu") == gpus for r in renders)
        assert all(r.get("gpu") == gpus for r in jobs["preview"])
        for name in ("ground_truth", "variance", "warp", "correlation", "intervention"):
            assert all("gpu" not in r for r in jobs[name]), name
        # Sized from the job: 48x27 renders ask for the base memory plus 64 B per pixel and
        # 24 B per pixel for each further seed of the batch held until its store is written.
        per_pixel = 64 + 24 * (TINY["render"]["seeds_per_job"] - 1)
        assert {r["mem_mb"] for r in renders} == {
            str(1536 + math.ceil(per_pixel * 48 * 27 / 2**20))
        }
        threads = "4" if gpus else "2"
        assert {r["cpus_per_task"] for r in renders} == {threads}


# The golden tables: the tiny config's renders and ground truth as a renderer wrote them
# (tests/fixtures/tiny/inputs) and every CSV the workflow computed from them
# (tests/fixtures/tiny/expected; tests/fixtures/tiny/regenerate.py writes both).
#
# Renders are not compared across machines: Dr.Jit compiles for the host CPU, and a last-bit
# difference flips discrete path decisions (Russian roulette, a Fresnel choice), so at SPP 2 a
# pixel's whole sample changes. Compiling the same tiny run for another target on one CPU
# (STEREOVAR_JIT_TARGET=avx2-w4 against znver3/8) moved glass-region statistics by O(1)
# (warped rho -0.017 against 0.071, n_fireflies 12 against 13, a NaN pixel more) while the
# ground truth moved by at most 6e-7 relative. So the golden tables are recomputed from the
# stored renders, and the renders are checked through the ground truth and elsewhere against
# analytic and statistical references.
GOLDEN = REPO / "tests" / "fixtures" / "tiny"
GOLDEN_INPUTS = ("ground_truth", "mitsuba/renders")
GOLDEN_REL, GOLDEN_ABS = 1e-9, 1e-12
"""Tolerance of the golden tables: the analysis reads the same bytes and computes in float64;
what may differ between machines is the order of summation (numpy's SIMD dispatch, the BLAS
kernel), about 1e-16 per operation on these sums of at most 1296 pixels."""
GROUND_TRUTH_REL = 1e-5
"""Tolerance of ground-truth depth and disparity across CPUs: float32 ray tracing and
projection, a few ulp (1.2e-7) per step (measured across two targets: 6e-7)."""


def golden_tables(results: Path) -> list[str]:
    """The CSVs under ``results`` that the golden comparison covers, relative to it: every
    table computed from the renders and ground truth (the claims table, whose rules are
    data, and the calibration's, whose rates count thresholds crossed by random draws, so
    that a last-bit difference between CPUs can move a count by one, have their own
    tests)."""
    return sorted(
        str(p.relative_to(results))
        for p in results.rglob("*.csv")
        if p.name != "claims.csv"
        and not p.name.startswith("calibration")
        and "calibration" not in p.relative_to(results).parts
    )


GOLDEN_FILES = sorted(
    str(p.relative_to(GOLDEN / "expected")) for p in (GOLDEN / "expected").rglob("*.csv*")
)


@pytest.fixture(scope="module")
def golden_run(tmp_path_factory):
    """The tiny workflow run on the golden renders and ground truth (copied with fresh
    mtimes, so Snakemake keeps them): (workdir, snakemake's output)."""
    root = copy_workflow(tmp_path_factory.mktemp("golden"), TINY)
    for rel in GOLDEN_INPUTS:
        shutil.copytree(
            GOLDEN / "inputs" / rel, root / "results" / rel, copy_function=shutil.copy
        )
    # a GPU machine would plan CUDA previews beside the stored LLVM renders
    proc = snakemake(root, "-j2", "all", config={"render": {"allow_mixed_backends": True}})
    return root, proc.stdout + proc.stderr


def test_golden_run_renders_nothing(golden_run):
    _, log = golden_run
    assert "rule correlation:" in log
    assert "rule render:" not in log and "rule ground_truth:" not in log


@pytest.mark.parametrize("rel", GOLDEN_FILES)
def test_tables_equal_the_golden_tables(golden_run, rel):
    """Every row and column of every table computed from the golden renders: text and
    integers (pixel counts, firefly counts) exactly, numbers to :data:`GOLDEN_REL`."""
    root, _ = golden_run
    want = read_rows(GOLDEN / "expected" / rel)
    got = read_rows(root / "results" / rel.removesuffix(".gz"))
    assert len(got) == len(want) and want, rel
    for row_want, row_got in zip(want, got, strict=True):
        assert list(row_got) == list(row_want), rel
        for key, value in row_want.items():
            have = row_got[key]
            if isinstance(value, float) and math.isnan(value):
                assert isinstance(have, float) and math.isnan(have), (rel, key, have)
            elif isinstance(value, float):
                assert have == pytest.approx(value, rel=GOLDEN_REL, abs=GOLDEN_ABS), (
                    rel,
                    key,
                    have,
                )
            else:
                assert have == value, (rel, key, have, value)


def test_every_table_is_golden(golden_run):
    """The golden set covers every table the run writes (a new table needs
    tests/fixtures/tiny/regenerate.py)."""
    root, _ = golden_run
    expected = {r.removesuffix(".gz") for r in GOLDEN_FILES}
    assert set(golden_tables(root / "results")) == expected


def test_ground_truth_agrees_with_the_golden_one_across_cpus(workdir):
    """This machine's ground truth against the golden one (traced on another CPU, or with
    another JIT target): depth and disparity to :data:`GROUND_TRUTH_REL`, masks and indices
    identical but for at most 2 pixels whose ray grazes an edge."""
    for scene in SCENES:
        here = open_dataset(workdir / f"results/ground_truth/{scene}.zarr")
        gold = open_dataset(GOLDEN / f"inputs/ground_truth/{scene}.zarr")
        assert set(here.data_vars) == set(gold.data_vars)
        for name in here.data_vars:
            a, b = here[name].values, gold[name].values
            if a.dtype.kind == "f":
                both = np.isfinite(a) & np.isfinite(b)
                assert (np.isfinite(a) == np.isfinite(b)).all(), (scene, name)
                np.testing.assert_allclose(a[both], b[both], rtol=GROUND_TRUTH_REL, atol=1e-6)
            else:
                assert (a != b).sum() <= 2, (scene, name)


def _md_cells(lines):
    rows = [
        [c.strip() for c in re.split(r"(?<!\\)\|", ln.strip()[1:-1])]
        for ln in lines
        if ln.startswith("|")
    ]
    return [rows[0], *rows[2:]]


def _cell(value) -> str:
    if isinstance(value, float):
        return "NaN" if math.isnan(value) else f"{value:.4g}"
    return str(value)


def test_markdown_and_latex_tables_hold_the_csv_cells(workdir):
    """The Markdown table holds the CSV's cells to 4 significant digits; the LaTeX table is a
    booktabs tabular with one line per row; both captions name the run."""
    names = ("cross_scene", "spp_sweep", "spp_sweep_fit", "intervention", "scenes", "statistics")
    for name in names:
        where = "results/tables" if name == "scenes" else f"{RUN}/tables"
        rows = read_rows(workdir / f"{where}/{name}.csv")
        cells = _md_cells((workdir / f"{where}/{name}.md").read_text().splitlines())
        header = cells[0]
        assert [[_cell(r[c]) for c in header] for r in rows] == cells[1:], name
        tex = (workdir / f"{where}/{name}.tex").read_text()
        assert "\\toprule" in tex and tex.count("\\\\\n") >= len(rows) + 1
    claims = (workdir / "results/tables/claims.md").read_text()
    assert "mitsuba" in claims and "verdict" in claims


def test_one_views_renders_stack_with_open_mfdataset(workdir):
    import xarray as xr

    paths = sorted((workdir / "results/mitsuba/renders/scene_000/left/spp2").glob("seeds*.zarr"))
    stacked = xr.open_mfdataset(
        [str(p) for p in paths], combine="nested", concat_dim="seed", engine="zarr"
    )
    assert stacked["radiance"].dims == ("seed", "y", "x", "channel")
    assert stacked["seed"].values.tolist() == [0, 1]
    assert stacked["radiance"].attrs["units"] == "W m-2 sr-1"


def test_every_store_describes_itself(workdir):
    """y/x pixel coordinates with units, a long_name on every variable, units on every
    physical quantity, and the provenance that says what made the store."""
    stores = sorted((workdir / "results").rglob("*.zarr"))
    kinds = {p.relative_to(workdir / "results").parts[1] for p in stores}
    assert {"renders", "seeds"} <= kinds and len(stores) >= 2 + 6 + 3 + 3
    for path in stores:
        ds = open_dataset(path)
        assert ds["y"].attrs["units"] == "px" and ds["x"].attrs["units"] == "px", path
        for name, var in ds.data_vars.items():
            assert var.attrs.get("long_name"), (path, name)
            if var.dtype.kind == "f":
                assert var.attrs.get("units"), (path, name)
        assert ds.attrs["renderer"] == "mitsuba" and len(ds.attrs["scene_digest"]) == 64, path
        if "/variance/" in str(path) or "/warped/" in str(path):
            assert ds.attrs["estimator"] == "seeds" and ds.attrs["seed_policy"] == "independent"
            assert len(ds.attrs["config_digest"]) == 64
