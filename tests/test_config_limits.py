"""Inputs past what the workflow can hold: YAML alias bombs in every YAML entry point, tags
that build Python objects, images whose jobs need more memory than there is, and results
the run cannot write. Each stops with one line naming the file or key and the fix, in
seconds and in bounded memory."""

from __future__ import annotations

import math
import os
import resource
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml

from stereovar import resources as sizing
from stereovar.config import load_config, validate_config
from stereovar.errors import ConfigError
from stereovar.schema import MAX_YAML_VALUES, parse_yaml

from .test_workflow import TINY, copy_workflow

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"

MEMORY_LIMIT = 2 * 2**30
"""Address space of every subprocess here: an alias bomb that expanded would hit it."""

TIMEOUT_S = 60


def _bounded():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run_bounded(args, cwd, *, prefix=()) -> subprocess.CompletedProcess:
    """Run ``args`` with at most :data:`MEMORY_LIMIT` of memory and :data:`TIMEOUT_S`."""
    return subprocess.run(
        [*prefix, *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        preexec_fn=_bounded,
    )


def laughs(levels: int = 9) -> tuple[str, str]:
    """Anchors ``a`` .. of a "billion laughs" document (each list repeats the previous one
    nine times) and the name of the last: ``9**levels`` strings once expanded."""
    names = "abcdefghijklmnop"[:levels]
    lines = [f"{names[0]}: &{names[0]} [{', '.join(['lol'] * 9)}]"]
    for prev, name in zip(names, names[1:], strict=False):
        lines.append(f"{name}: &{name} [{', '.join([f'*{prev}'] * 9)}]")
    return "\n".join(lines) + "\n", names[-1]


def one_stereovar_line(proc) -> str:
    """The run stopped with exactly one ``stereovar`` line on stderr, which is returned."""
    assert proc.returncode != 0, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr, proc.stdout + proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("stereovar")]
    assert len(lines) == 1, proc.stderr
    return lines[0]


# ------------------------------------------------------------------------- alias bombs


def bounded_python(code: str, cwd) -> list[str]:
    """Run ``code`` in a bounded subprocess (:func:`run_bounded`); its stdout lines."""
    proc = run_bounded([sys.executable, "-c", textwrap.dedent(code)], cwd)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.splitlines()


LAUGHS = """
tree = ["lol"] * 9
for _ in range(8):
    tree = [tree] * 9
"""
"""Python for the 9**9 strings of :func:`laughs` as shared references (cheap until copied)."""


def test_expanded_size_counts_shared_references_without_expanding_them(tmp_path):
    out = bounded_python(
        LAUGHS
        + """
from stereovar.schema import expanded_size
print(expanded_size({"scenes": tree}))
looped = []
looped.append(looped)
try:
    expanded_size({"a": looped})
except ValueError as err:
    print(err)
""",
        tmp_path,
    )
    # a mapping counts itself, its keys and its values; the tree 1 + 9 + ... + 9**9 lists
    # and strings
    assert out == [str(1 + 1 + sum(9**k for k in range(10))), "a list or mapping contains itself"]


def test_parse_yaml_keeps_small_aliases_and_refuses_a_bomb_at_its_line():
    assert parse_yaml("a: &a [1, 2]\nb: *a\nc: {<<: {x: 1}, y: 2}\n") == {
        "a": [1, 2],
        "b": [1, 2],
        "c": {"x": 1, "y": 2},
    }
    text, last = laughs()
    with pytest.raises(yaml.YAMLError) as err:
        parse_yaml(text + f"scenes: *{last}\n", name="bomb.yaml")
    # the first line whose aliases pass the bound: level k holds 1 + 9 + ... + 9**k values
    totals = [sum(sum(9**j for j in range(k + 2)) for k in range(n)) for n in range(1, 10)]
    line = next(n for n, total in enumerate(totals, start=1) if total > MAX_YAML_VALUES)
    assert err.value.problem_mark.line + 1 == line
    assert "more than 100,000 values" in err.value.problem
    with pytest.raises(yaml.YAMLError, match="contains it"):
        parse_yaml("a: &a [1, *a]\n")


def test_a_config_of_shared_references_is_refused_naming_its_key(tmp_path):
    out = bounded_python(
        LAUGHS
        + f"""
from stereovar.config import validate_config
from stereovar.errors import ConfigError
looped = {{}}
looped["render"] = looped
cases = [
    ({{"scenes": tree}}, None),
    ({{}}, {{"render": {{"spp_sweep": {{"spp": tree}}}}}}),
    (looped, None),
]
for config, command_line in cases:
    try:
        validate_config(config, {str(SCHEMA)!r}, command_line=command_line)
        print("accepted")
    except ConfigError as err:
        print(err)
""",
        tmp_path,
    )
    held = (9**10 - 1) // 8  # 1 + 9 + ... + 9**9 lists and strings
    fix = "more than the 100,000 a config may hold; write the values out or repeat fewer aliases"
    assert out == [
        f"config key 'scenes': holds {held:,} values once its YAML aliases are expanded, {fix}",
        f"--config key 'render.spp_sweep.spp': holds {held:,} values once its YAML aliases are "
        f"expanded, {fix}",
        "config key 'render': contains itself (a recursive YAML alias); give the values in full",
    ]


def test_an_alias_bomb_in_a_configfile_stops_the_workflow_naming_file_and_line(tmp_path):
    root = copy_workflow(tmp_path / "wf", TINY)
    text, last = laughs()
    (root / "bomb.yaml").write_text(text + f"scenes: *{last}\n")
    proc = run_bounded(
        [sys.executable, "-m", "snakemake", "-n", "all", "--configfile", "bomb.yaml"], root
    )
    line = one_stereovar_line(proc)
    assert "config file 'bomb.yaml' is not valid YAML at line 6" in line
    assert "more than 100,000 values" in line


def test_an_alias_bomb_in_a_scene_spec_is_one_line(tmp_path):
    text, last = laughs()
    spec = tmp_path / "bomb_scene.yaml"
    spec.write_text(text + f"name: bomb_scene\nobjects: *{last}\n")
    validate = ["scenes", "validate", str(spec), "--variant", "none"]
    proc = run_bounded([sys.executable, "-m", "stereovar.cli", *validate], tmp_path)
    assert proc.returncode == 2
    line = one_stereovar_line(proc)
    assert f"{spec}: (yaml): parse error at line 6, column 8: the aliases up to here" in line
    assert "more than 100,000 values" in line


def test_an_alias_bomb_in_an_audit_config_stops_before_any_import(tmp_path):
    from stereovar.audit.synthetic import write_synthetic_audit

    project = tmp_path / "project"
    (project / "workflow").mkdir(parents=True)
    (project / "Snakefile").write_text("")
    settings, _ = write_synthetic_audit(tmp_path / "data", width=16, height=12, n_seeds=2)
    text, last = laughs()
    audit = yaml.safe_dump({"audit": {**settings, "glass_ids": "GLASS"}})
    (project / "audit.yaml").write_text(text + audit.replace("GLASS", f"*{last}"))
    proc = run_bounded(
        [sys.executable, "-m", "stereovar.cli", "audit", "audit.yaml", "--import-only"], project
    )
    line = one_stereovar_line(proc)
    assert "audit config 'audit.yaml' is not valid YAML at line 6" in line
    assert not (project / "results").exists(), "nothing is imported"


# ------------------------------------------------------------------ tags of Python objects


def test_a_python_tag_in_config_yaml_names_the_file_and_the_tag(tmp_path):
    root = copy_workflow(tmp_path / "wf", TINY)
    text = (root / "config.yaml").read_text()
    assert "  width: 320\n" in text
    (root / "config.yaml").write_text(
        text.replace("  width: 320\n", "  width: !!python/object:collections.OrderedDict {}\n")
    )
    line_no = text.splitlines().index("  width: 320") + 1
    proc = run_bounded([sys.executable, "-m", "snakemake", "-n", "--configfile", "tiny.yaml"], root)
    line = one_stereovar_line(proc)
    assert f"config file 'config.yaml' is not valid YAML at line {line_no}" in line
    assert "!!python/object:collections.OrderedDict" in line and "remove the tag" in line


def test_a_python_name_tag_in_a_configfile_names_the_file_and_the_tag(tmp_path):
    # Snakemake's loader builds the object (a function here) and runs on with it.
    root = copy_workflow(tmp_path / "wf", TINY)
    (root / "tagged.yaml").write_text("generator:\n  seed: !!python/name:os.getpid\n")
    proc = run_bounded(
        [sys.executable, "-m", "snakemake", "-n", "--configfile", "tagged.yaml"], root
    )
    line = one_stereovar_line(proc)
    assert "config file 'tagged.yaml' is not valid YAML at line 2, column 9" in line
    assert "the tag !!python/name:os.getpid would build a Python object" in line


def test_load_config_names_the_tag(tmp_path):
    tagged = tmp_path / "tagged.yaml"
    tagged.write_text("render:\n  spp: !!python/object/apply:os.getpid []\n")
    with pytest.raises(ConfigError) as err:
        load_config(tagged, SCHEMA)
    assert str(err.value) == (
        f"config file '{tagged}' is not valid YAML at line 2, column 8: the tag "
        "!!python/object/apply:os.getpid would build a Python object, which is never read; "
        "remove the tag and give the plain value"
    )


# ------------------------------------------------------------------------ job memory


def analysis_request(width: int, height: int) -> int:
    """An intervention job's request by hand: 1024 MB plus 24 float64 RGB images."""
    return 1024 + math.ceil(24 * 8 * 3 * width * height / 2**20)


def test_the_largest_job_and_the_largest_fitting_size_against_hand_calculations():
    config = validate_config({"resolution": {"width": 30000, "height": 30000}}, SCHEMA)
    requests = sizing.job_mem_requests(config)
    assert requests["analysis"] == analysis_request(30000, 30000) == 495_409
    # render: 8 seeds per job, 64 + 24 * 7 bytes per pixel; moments: 200 bytes per pixel
    assert requests["render"] == 1536 + math.ceil(232 * 30000**2 / 2**20)
    assert requests["moments"] == 1536 + math.ceil(200 * 30000**2 / 2**20)
    with pytest.raises(ConfigError) as err:
        sizing.check_job_memory(config, 16_000, sizing.MACHINE)
    message = str(err.value)
    side = max(s for s in range(1, 30000) if analysis_request(s, s) <= 16_000)
    assert message == (
        "config key 'resolution': 30000x30000 makes each analysis job request 495,409 MB of "
        "memory, more than the 16,000 MB of this machine's memory; use at most "
        f"{side}x{side} (on a cluster, set cluster.max_mem_mb to the memory of its largest "
        "node)"
    )
    sizing.check_job_memory({**config, "resolution": {"width": side, "height": side}}, 16_000, "x")


def test_the_bound_is_the_cluster_node_or_this_machine_lowered_by_resources():
    config = validate_config({}, SCHEMA)
    assert sizing.memory_limit(config, machine_mb=8000) == (8000, sizing.MACHINE)
    assert sizing.memory_limit(config, machine_mb=8000, global_mem_mb=3000) == (
        3000,
        "--resources mem_mb",
    )
    cluster = validate_config({"cluster": {"max_mem_mb": 64000}}, SCHEMA)
    assert sizing.memory_limit(cluster, machine_mb=8000) == (64000, "cluster.max_mem_mb")
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 10**6
    assert 0 < sizing.machine_mem_mb() <= total


PRESETS = {"default": ["config.yaml"], "paper": ["config.yaml", "workflow/presets/paper.yaml"]}


@pytest.mark.parametrize("presets", PRESETS.values(), ids=PRESETS.keys())
def test_the_default_and_paper_configs_fit_a_4_gb_machine(presets):
    config = load_config([REPO / p for p in presets], SCHEMA)
    sizing.check_job_memory(config, 4000, sizing.MACHINE)


def test_a_huge_resolution_stops_the_dry_run_with_the_request(tmp_path):
    root = copy_workflow(tmp_path / "wf", TINY)
    base = [sys.executable, "-m", "snakemake", "-n", "all", "--configfile", "tiny.yaml"]
    huge = run_bounded([*base, "--config", "resolution={width: 30000, height: 30000}"], root)
    line = one_stereovar_line(huge)
    assert "30000x30000 makes each analysis job request 495,409 MB of memory" in line
    # a profile's or the command line's `resources: mem_mb=...` bounds every job
    capped = run_bounded(
        [*base, "--config", "resolution={width: 2000, height: 1000}", "--resources", "mem_mb=2000"],
        root,
    )
    need = analysis_request(2000, 1000)
    assert need > 2000
    assert f"request {need:,} MB of memory, more than the 2,000 MB of --resources mem_mb" in (
        one_stereovar_line(capped)
    )


def test_the_dry_run_requests_what_the_check_computes(tmp_path):
    """Every job's memory request, read from Snakemake's API (not its printed text, whose
    order varies), is one the memory check bounds: render jobs ask the render request,
    ground truth and previews (one-image renders) at most that, every other job at most the
    analysis request. On a cluster the chains grouped into one job (``scene_setup``: ground
    truth then preview; ``analysis``: variance, warp, correlation) run one after another,
    so a group job asks the largest of its members, within the same bounds."""
    import json

    root = copy_workflow(tmp_path / "wf", {**TINY, "resolution": {"width": 1000, "height": 600}})
    script = Path(__file__).with_name("planned_resources.py")
    proc = run_bounded(
        [sys.executable, str(script), "--configfile", "tiny.yaml", "--", "all", "estimators"],
        root,
    )
    assert proc.returncode == 0, proc.stderr
    planned = json.loads(proc.stdout)
    asked: dict[str, int] = {}
    for job in planned:
        if "rule" in job and "mem_mb" in job["resources"]:
            asked[job["rule"]] = max(asked.get(job["rule"], 0), job["resources"]["mem_mb"])
    groups: dict[str, int] = {}
    for group in planned:
        if "group" in group:
            name = group["group"]
            groups[name] = max(groups.get(name, 0), group["resources"]["mem_mb"])
            members = max(asked[rule] for rule in group["rules"])
            assert group["resources"]["mem_mb"] == members, group
    config = load_config([root / "config.yaml", root / "tiny.yaml"], SCHEMA)
    requests = sizing.job_mem_requests(config)
    assert asked.pop("render") == requests["render"]
    assert asked.pop("render_moments") == requests["moments"]
    for one_image in ("ground_truth", "preview"):
        assert asked.pop(one_image) == sizing.render_mem_mb(1000, 600, batch=1)
    assert sizing.render_mem_mb(1000, 600, batch=1) <= requests["render"]
    assert {"intervention", "estimator_check", "variance", "warp", "correlation"} <= set(asked)
    assert max(asked.values()) == requests["analysis"]
    assert set(groups) == {"scene_setup", "analysis"}
    assert groups["scene_setup"] <= requests["render"]
    assert groups["analysis"] <= requests["analysis"]


# --------------------------------------------------------------------- read-only results


def read_only(path: Path) -> tuple:
    """Make ``path`` unwritable for a workflow run: without write permission for a user, a
    read-only bind mount (in a private mount namespace) for root, whom permissions do not
    stop. Returns the command prefix the run needs."""
    if os.geteuid() != 0:
        for sub in [path, *path.rglob("*")]:
            sub.chmod(sub.stat().st_mode & ~0o222)
        return ()
    assert shutil.which("unshare"), "root needs unshare(1) for a read-only mount"
    script = f'mount --bind "{path}" "{path}" && mount -o remount,bind,ro "{path}" && exec "$@"'
    return ("unshare", "-m", "sh", "-c", script, "sh")


def test_read_only_results_stop_the_run_naming_the_directory_and_the_fix(tmp_path):
    root = copy_workflow(tmp_path / "wf", TINY)
    store = root / "results" / "ground_truth" / "scene_000.zarr"
    store.mkdir(parents=True)
    (store / ".zgroup").write_text('{"zarr_format": 2}')
    for p in (store / ".zgroup", store):
        os.utime(p, (0, 0))  # older than the spec: the run must replace it
    prefix = read_only(root / "results")
    try:
        target = ["results/ground_truth/scene_000.zarr"]
        for mode in (["-n"], ["-j1"]):
            proc = run_bounded(
                [sys.executable, "-m", "snakemake", *mode, *target, "--configfile", "tiny.yaml"],
                root,
                prefix=prefix,
            )
            line = one_stereovar_line(proc)
            assert line.startswith("stereovar: results is ") and "this run writes there" in line
            assert ("remount it read-write" in line) or ("chmod -R u+w results" in line)
            assert "ProtectedOutputException" not in proc.stdout + proc.stderr
        assert (store / ".zgroup").read_text() == '{"zarr_format": 2}'
    finally:
        for sub in [root / "results", *(root / "results").rglob("*")]:
            sub.chmod(sub.stat().st_mode | 0o200)
