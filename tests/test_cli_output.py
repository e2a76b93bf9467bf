"""What `stereovar audit` prints: one line per stage (the last with all of the run's jobs),
the verdict's summary, the page and the log file (Snakemake's whole output, never
overwritten); -v shows that output live; a failed job gives its one-line error and the log's
path."""

import re
import subprocess
import sys

import pytest
import yaml

from stereovar import cli
from stereovar.audit.synthetic import write_synthetic_audit

from .test_workflow import TINY, copy_workflow

pytestmark = pytest.mark.workflow

STAGES = [
    "import",
    "statistics",
    "controls",
    "intervention",
    "calibration",
    "tables and figures",
    "verdict",
]


def audit(root, *args):
    return subprocess.run(
        [sys.executable, "-m", "stereovar.cli", "audit", *args],
        cwd=root,
        capture_output=True,
        text=True,
    )


def write_config(root, name, data, *, render_format="exr"):
    settings, _ = write_synthetic_audit(
        root / data,
        name=name,
        n_frames=1,
        width=40,
        height=24,
        n_seeds=4,
        render_format=render_format,
    )
    settings["renders"] = f"{data}/renders/{{frame}}/{{view}}/seed_{{seed}}.{render_format}"
    settings["disparity"] = f"{data}/disparity/{{frame}}.pfm"
    (root / f"{name}.yaml").write_text(yaml.safe_dump({"audit": settings}))
    return f"{name}.yaml"


def log_of(root, out):
    """The log file the last line of ``out`` names."""
    last = out.strip().splitlines()[-1]
    assert last.startswith("log: logs/audit/"), out
    path = root / last.removeprefix("log: ").split(" (")[0]
    assert path.is_file()
    return path


@pytest.fixture(scope="module")
def audited(tmp_path_factory):
    """A one-frame synthetic audit (PNG renders: the import warns) run once, by default."""
    root = copy_workflow(tmp_path_factory.mktemp("cli") / "wf", TINY)
    proc = audit(root, write_config(root, "tiny", "data", render_format="png"))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return root, proc


def stage_lines(err: list) -> list:
    """The lines that end a stage (``<stage> ... done``), each stage's last; the others say
    where the run stood inside a stage that took long (30 s on a slow machine)."""
    # a stage's line may say that the next one started while it waited
    done = [line for line in err if re.fullmatch(r".+ \.\.\. (· .+ started )?done.*", line)]
    for line in err:
        if line not in done:
            assert re.search(r" \.\.\. .*(\d+ of \d+ in all|last change .+ ago)", line), line
    return done


def test_default_output_is_the_stages_the_verdict_and_the_log(audited):
    root, proc = audited
    err = proc.stderr.splitlines()
    done = stage_lines(err)
    assert [line.split(":")[0].split(" ...")[0] for line in done] == STAGES, proc.stderr
    assert err[0] == "import: 1 frame × 2 views × 4 seeds ... done"
    # the last line counts every job of the run
    assert err[-1] == done[-1] and re.search(r"; (\d+) of \1 in all\)$", err[-1]), err
    out = proc.stdout.splitlines()
    assert len(out) + len(done) <= 20 and len(out) <= 15, proc.stdout
    summary = yaml.safe_load((root / "results/audit/tiny/summary.json").read_text())["summary"]
    assert out[: len(summary)] == summary  # once, from the verdict job's summary.json
    assert out[0].startswith(("RED:", "AMBER:", "GREEN:"))
    # the import's warnings are in the summary: not printed a second time
    assert sum("PNG renders without audit.transfer" in line for line in out + err) == 1
    assert out[-2] == f"verdict page: {root / 'results/audit/tiny/verdict.html'}"
    log = log_of(root, proc.stdout).read_text()
    assert "Job stats:" in log and "rule audit_verdict:" in log and "Finished job" in log
    assert log.count("audit tiny: 1 frame × 2 views × 4 seeds; imported 1 frame") >= 1
    assert "imported 1 frame" not in proc.stdout + proc.stderr


def test_verbose_shows_the_log_live_and_logs_are_never_overwritten(audited):
    root, first = audited
    config = write_config(root, "again", "again_data")
    proc = audit(root, config, "-v", "--import-only")
    assert proc.returncode == 0, proc.stderr
    assert "rule audit_import:" in proc.stderr  # the job log, as Snakemake writes it
    assert "audit again: 1 frame × 2 views × 4 seeds; imported 1 frame (f00)" in proc.stderr
    assert proc.stdout.startswith("imported again: one record per frame in ")
    log = log_of(root, proc.stdout)
    assert "rule audit_import:" in log.read_text()
    # the full audit's imports again: nothing to do, said in two lines, the import's
    # warnings (no summary to carry them now) once each, and a new log beside the first
    again = audit(root, "tiny.yaml", "--import-only")
    assert again.returncode == 0, again.stderr
    err = again.stderr.splitlines()
    assert err[:2] == [
        "import: 1 frame × 2 views × 4 seeds ... up to date",
        "Nothing to be done: every result is up to date",
    ]
    assert err[2].startswith("warning: PNG renders without audit.transfer are decoded as sRGB")
    assert all(line.startswith("warning: ") for line in err[2:]) and len(set(err)) == len(err)
    assert log_of(root, again.stdout) != log_of(root, first.stdout)
    assert len(list((root / "logs/audit/tiny").glob("stereovar-audit-*.log"))) == 2


def test_a_truncated_render_stops_with_its_one_line_error_and_the_log(audited):
    root, _ = audited
    config = write_config(root, "broken", "broken_data")
    render = root / "broken_data/renders/f00/R/seed_002.exr"
    render.write_bytes(render.read_bytes()[: render.stat().st_size // 2])
    proc = audit(root, config)
    assert proc.returncode != 0
    assert proc.stdout == ""
    err = proc.stderr.splitlines()
    assert len(err) == 3, proc.stderr
    assert err[0] == "import: 1 frame × 2 views × 4 seeds ... failed"
    assert err[1].startswith(f"stereovar: error: {render.relative_to(root)}: cannot read")
    assert "truncated" in err[1]
    assert err[2].endswith("(the failed job's: logs/audit/broken/import/f00.log)")
    log = log_of(root, proc.stderr).read_text()
    assert "Error in rule audit_import:" in log and err[1].split("error: ", 1)[1] in log


def test_new_log_files_do_not_clobber_one_of_the_same_second(tmp_path, monkeypatch):
    monkeypatch.setattr("time.strftime", lambda _fmt: "20260101-000000")
    paths = []
    for _ in range(3):
        path, log = cli._audit_log(tmp_path, "a")
        log.write(str(len(paths)))
        log.close()
        paths.append(path)
    assert [p.name for p in paths] == [
        "stereovar-audit-20260101-000000.log",
        "stereovar-audit-20260101-000000-2.log",
        "stereovar-audit-20260101-000000-3.log",
    ]
    assert [p.read_text() for p in paths] == ["0", "1", "2"]


def test_an_error_before_any_job_is_one_line(tmp_path):
    # what the logger plugin recorded of Snakemake's error (its ERROR event)
    monitor = cli._Run(tmp_path / "run.log")
    monitor.summary = {
        "errors": [
            {
                "exception": "AuditError",
                "message": 'AuditError in file "/wf/workflow/rules/common.smk", line 40:\n'
                "data/renders/f00/L/seed_001.exr: gone since the files were found; render it again",
            }
        ]
    }
    assert monitor.errors(1) == [
        "data/renders/f00/L/seed_001.exr: gone since the files were found; render it again"
    ]
    assert cli._Run(tmp_path / "none.log").errors(3) == ["snakemake stopped with exit status 3"]
