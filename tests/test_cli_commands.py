"""The command line as a new user meets it: ``python -m stereovar``, a bare ``stereovar``
and ``--help`` (examples and the documentation's address), ``run --help``'s targets against
the workflow's own rules, the stages ``run --help`` and ``audit --help`` list against those a
run prints, Snakemake's own options on ``run``'s line (``stereovar run -n``), tab completion,
``init --example`` run twice, and the CI gate ``audit --fail-on``."""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from stereovar import cli
from stereovar.audit.synthetic import write_synthetic_audit
from stereovar.cli.audit import FAIL_ON_STATUS, verdict_fails
from stereovar.cli.workflow import RUN_TARGETS
from stereovar.links import docs_page
from stereovar.progress import Progress
from stereovar.stages import AUDIT_STAGES, RUN_STAGES

REPO = Path(__file__).resolve().parents[1]


def python_m(module: str, *args, env=None, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", module, *args], capture_output=True, text=True, env=env,
        cwd=cwd, timeout=60, check=False,
    )  # fmt: skip


# -- python -m stereovar, a bare stereovar, --help ---------------------------------------------


def test_python_m_stereovar_is_the_stereovar_command():
    proc = python_m("stereovar", "--version")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split()[0] == "stereovar"
    bare = python_m("stereovar")
    assert bare.returncode == 0 and bare.stdout.startswith("usage: stereovar"), bare.stderr


def examples(text: str) -> list[str]:
    """The example commands of a help text: its lines that start with ``  stereovar``."""
    return [
        line.split("#")[0].strip() for line in text.splitlines() if line.startswith("  stereovar ")
    ]


def test_a_bare_stereovar_prints_help_with_three_examples_and_the_docs(capsys):
    assert cli.main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: stereovar")
    shown = examples(out)
    assert len(shown) == 3
    assert {"stereovar init --example", "stereovar run -j2", "stereovar audit audit.yaml"} == set(
        shown
    )
    assert docs_page("getting-started") in out
    assert "docs/" not in out.replace(docs_page(""), "")  # an address, never a repository path
    for command in shown:  # each example is a command the parser takes
        args = cli.build_parser().parse_args(shlex.split(command)[1:])
        assert callable(args.func)


def test_help_has_the_same_examples_and_docs_address(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert cli.main([]) == 0
    assert capsys.readouterr().out == out
    assert len(examples(out)) == 3 and docs_page("getting-started") in out


def test_options_after_dashes_without_a_command_are_a_usage_error(capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["--", "-n"])
    assert stop.value.code == 2
    assert "after -- are for run and report only" in capsys.readouterr().err


# -- run --help lists the workflow's targets ---------------------------------------------------


def workflow_rules() -> dict[str, str]:
    """Every rule of the workflow (the Snakefile and ``workflow/rules/*.smk``) with its body,
    read from the files' text: ``rule NAME:`` up to the next unindented line."""
    rules = {}
    for path in [REPO / "Snakefile", *sorted((REPO / "workflow" / "rules").glob("*.smk"))]:
        text = path.read_text()
        for match in re.finditer(r"^(?:rule|checkpoint) (\w+):\n((?:[ \t]+.*\n|\n)*)", text, re.M):
            rules[match.group(1)] = match.group(2)
    return rules


def target_rules() -> set[str]:
    """The rules a user asks for by name: those that collect other rules' outputs and make
    no file of their own (an ``input:`` and no ``output:``)."""
    return {
        name
        for name, body in workflow_rules().items()
        if re.search(r"^\s+input:", body, re.M) and not re.search(r"^\s+output:", body, re.M)
    }


def test_the_target_rules_are_found():
    rules = workflow_rules()
    assert len(rules) > 40 and "render" in rules and "audit_verdict" in rules
    assert {"all", "mitigations", "probe", "calibration", "generators", "export"} <= target_rules()
    assert "render" not in target_rules()


def test_run_help_lists_every_target_rule_and_only_rules(capsys):
    assert set(RUN_TARGETS) == target_rules()
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    out = capsys.readouterr().out
    listed = out[out.index("targets (") :].splitlines()[1:]
    names = [line.split()[0] for line in listed if line.startswith("  ") and line[2] != " "]
    assert names == list(RUN_TARGETS)
    for line in listed:
        if line.startswith("  ") and line[2] != " ":
            assert re.search(r"\(~?\d+ min\)|\(seconds\)", line) or len(line) > 70, line


# -- the stages the help lists are those a run prints -------------------------------------------


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


@pytest.mark.parametrize(("group", "stages"), [("audit", AUDIT_STAGES), ("run", RUN_STAGES)])
def test_the_help_lists_the_stages_a_run_prints(capsys, group, stages):
    """The stages ``--help`` names, in its order, are the lines a run with a job in every
    stage prints (its events given here), one definition for both."""
    with pytest.raises(SystemExit):
        cli.main([group, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("one line per stage with jobs, in this order: ", 1)[1]
    listed = listed.split(";", 1)[0].split(", ")
    clock = Clock()
    progress = Progress(stages, clock=clock)
    rules = [names[0] for names in stages.values()]
    printed = progress.plan({rule: 1 for rule in rules})
    for jobid, rule in enumerate(rules):
        printed += progress.job(jobid, rule)
        clock.t += 1.0
        printed += progress.done(jobid)
    printed += progress.finish()
    assert listed == [line.split(" ... ")[0] for line in printed.splitlines()] == list(stages)
    assert printed.splitlines()[-1].endswith(f"{len(rules)} of {len(rules)} in all)")


# -- Snakemake's options on run's line ----------------------------------------------------------


@pytest.fixture
def run_args(tmp_path, monkeypatch):
    """``run_args(*words)``: the options ``stereovar <words>`` hands Snakemake (a stand-in
    that records them), in an empty folder."""
    monkeypatch.chdir(tmp_path)
    seen = []
    monkeypatch.setattr(cli, "_snakemake", lambda args, root: seen.append(list(args)) or 0)

    def run(*words):
        seen.clear()
        assert cli.main(list(words)) == 0
        (args,) = seen
        return args

    return run


@pytest.mark.parametrize(
    ("words", "snakemake"),
    [
        (["run", "-n"], ["-j", "2", "all", "-n"]),
        (["run", "--dry-run", "-j1"], ["-j", "1", "all", "--dry-run"]),
        (["run", "-np", "mitigations"], ["-j", "2", "-np", "mitigations"]),
        (["run", "mitigations", "-n"], ["-j", "2", "mitigations", "-n"]),
        (["run", "-R", "render", "-j", "4"], ["-j", "4", "-R", "render"]),
        (["run", "probe", "--forcerun=render"], ["-j", "2", "probe", "--forcerun=render"]),
        (["run", "--config", "spp=2", "-n"], ["-j", "2", "--config", "spp=2", "-n"]),
        (["run", "-n", "--", "-p"], ["-j", "2", "all", "-n", "-p"]),
        (["run", "--", "-n", "mitigations"], ["-j", "2", "-n", "mitigations"]),
        (["report", "--notemp"], ["--report", "results/report.html", "--notemp"]),
    ],
)  # fmt: skip
def test_options_run_does_not_take_go_to_snakemake(run_args, words, snakemake):
    """An option of Snakemake's on run's line is Snakemake's, as after --; a word after it is
    Snakemake's too (its value or a target), and run names no target of its own then
    (Snakemake's default target is all); --config is Snakemake's, not short for
    --configfile."""
    assert run_args(*words) == snakemake


def test_run_n_is_run_dashes_n(run_args):
    """The same command to Snakemake, so the same run (the dry run itself: below)."""
    assert run_args("run", "-n") == run_args("run", "--", "-n")
    assert run_args("run", "-n", "-j3", "-v") == run_args("run", "-j3", "-v", "--", "-n")


def test_an_option_no_command_takes_is_refused_by_the_others(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "_snakemake", lambda args, root: pytest.fail("ran"))
    with pytest.raises(SystemExit) as stop:
        cli.main(["export", "--format", "npy", "-n"])
    assert stop.value.code == 2
    assert "unrecognized arguments: -n" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:  # stereovar's -v fused with Snakemake's -n
        cli.main(["run", "-vn"])
    err = capsys.readouterr().err.splitlines()[-1]
    assert stop.value.code == 2 and "-vn: -v is stereovar's option" in err and "-v -n" in err


def cli_in(folder: Path, *words) -> subprocess.Popen:
    folder.mkdir()
    return subprocess.Popen([sys.executable, "-m", "stereovar.cli", *words], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_run_n_is_a_dry_run_of_the_default_workflow_that_writes_nothing(tmp_path,
                                                                       tree_snapshot):
    """Real Snakemake, two commands at once in empty folders: ``run -n`` (Snakemake's command
    that of ``run -- -n``: above) prints the plan by stage and writes only its log; a
    mistyped option, which Snakemake does not take either, is one line, and leaves no log."""
    procs = {name: cli_in(tmp_path / name, *words)
             for name, words in {"n": ["run", "-n"], "typo": ["run", "--dryrunn"]}.items()}
    out = {name: (*proc.communicate(timeout=120), proc.returncode)
           for name, proc in procs.items()}
    plan, err, rc = out["n"]
    assert rc == 0, err
    lines = plan.splitlines()
    assert lines[0].startswith("scenes: ") and re.fullmatch(
        r"\d+ jobs in all \(a dry run: nothing was run\)", lines[-1])
    assert [line.split(":")[0] for line in lines[:-1]] == [
        stage for stage in RUN_STAGES if any(line.startswith(f"{stage}:") for line in lines)]
    (log,) = err.splitlines()
    assert re.fullmatch(r"log: logs/stereovar-run-[\d-]+\.log", log)
    assert set(tree_snapshot(tmp_path / "n")) == {"logs", log.removeprefix("log: ")}
    _, typo, rc = out["typo"]
    assert rc == 2 and typo.splitlines() == [
        "stereovar: error: snakemake refused its options: unrecognized arguments: --dryrunn "
        "(stereovar run and report pass the options they do not take to snakemake; stereovar "
        "run --help and snakemake --help list them)"]
    assert not list((tmp_path / "typo").glob("logs/*"))


# -- tab completion ------------------------------------------------------------------------------


def complete(line: str, tmp_path: Path) -> list[str]:
    """What argcomplete answers the shell for the command line ``line`` (cursor at its end),
    through its environment protocol, with the answer written to a file."""
    out = tmp_path / "completions"
    env = {
        **os.environ,
        "_ARGCOMPLETE": "1",
        "_ARGCOMPLETE_SHELL": "bash",
        "COMP_LINE": line,
        "COMP_POINT": str(len(line)),
        "COMP_TYPE": "9",
        "_ARGCOMPLETE_STDOUT_FILENAME": str(out),
        "_ARGCOMPLETE_IFS": "\n",
    }
    proc = python_m("stereovar.cli", env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    return [word.strip() for word in out.read_text().split("\n") if word.strip()]


def test_completion_of_a_group_and_of_run_targets(tmp_path):
    assert complete("stereovar ru", tmp_path) == ["run"]
    offered = complete("stereovar run ", tmp_path)  # the targets, and the options
    assert {word for word in offered if not word.startswith("-")} == set(RUN_TARGETS)
    assert complete("stereovar run gen", tmp_path) == ["generators"]


@pytest.mark.parametrize("shell", ["bash", "zsh", "fish"])
def test_completion_prints_the_shells_code(shell, capsys):
    import argcomplete

    assert cli.main(["completion", shell]) == 0
    out = capsys.readouterr().out
    assert out == argcomplete.shellcode(["stereovar"], shell=shell)
    assert "stereovar" in out


def test_the_entry_modules_carry_argcompletes_marker():
    """argcomplete's global completion looks for the marker in the first 1024 bytes of the
    module a console script runs."""
    for module in ("cli/__init__.py", "cli/__main__.py", "__main__.py"):
        head = (REPO / "src" / "stereovar" / module).read_bytes()[:1024]
        assert b"PYTHON_ARGCOMPLETE_OK" in head, module


# -- init --example, twice -----------------------------------------------------------------------


def test_init_example_a_second_time_keeps_every_file_and_says_so(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["init", "--example"]) == 0
    first = capsys.readouterr().out
    files = sorted(p for p in tmp_path.rglob("*") if p.is_file())
    assert {tmp_path / "config.yaml", tmp_path / "audit.yaml"} <= set(files)
    assert any("data/synthetic" in p.as_posix() for p in files)
    before = {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in files}
    assert "wrote" in first and "kept" not in first

    assert cli.main(["init", "--example"]) == 0
    again = capsys.readouterr()
    assert again.err == ""
    for name in ("data/synthetic", "config.yaml", "audit.yaml"):
        assert f"kept {tmp_path / name} (it exists)" in again.out, again.out
    assert "wrote" not in again.out
    assert sorted(p for p in tmp_path.rglob("*") if p.is_file()) == files
    assert {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in files} == before


def test_init_example_beside_a_starter_audit_config_names_it(tmp_path, monkeypatch, capsys):
    """``init`` then ``init --example``: the example's audit.yaml cannot be written, so the
    example is not, in one line that names the file."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(["init"]) == 0
    capsys.readouterr()
    assert cli.main(["init", "--example"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and str(tmp_path / "audit.yaml") in err[0]
    assert not (tmp_path / "data").exists()


# -- audit --fail-on -----------------------------------------------------------------------------

#: Whether ``--fail-on LEVEL`` fails a verdict of LIGHT, written out case by case.
GATE = {
    ("amber", "green"): False,
    ("amber", "amber"): True,
    ("amber", "red"): True,
    ("red", "green"): False,
    ("red", "amber"): False,
    ("red", "red"): True,
}


@pytest.mark.parametrize(("level", "light"), sorted(GATE))
def test_the_gate_fails_at_its_level_and_worse(level, light):
    assert verdict_fails(light, level) is GATE[level, light]


@pytest.mark.parametrize("light", ["green", "amber", "red", "grey", None])
def test_no_level_no_gate_and_an_unknown_light_fails_every_gate(light):
    assert verdict_fails(light, None) is False
    if light not in ("green", "amber", "red"):
        assert verdict_fails(light, "red") and verdict_fails(light, "amber")


def test_an_unknown_level_is_refused():
    with pytest.raises(ValueError, match="amber or red"):
        verdict_fails("red", "green")


@pytest.fixture
def audited(tmp_path, monkeypatch, verdict_summary):
    """``audit(light, *options)``: ``stereovar audit`` of a one-frame synthetic audit in
    ``tmp_path`` whose Snakemake run is a stand-in that writes a finished audit's
    ``summary.json`` with verdict ``light``; returns the exit status."""
    monkeypatch.chdir(tmp_path)
    settings, _ = write_synthetic_audit(
        tmp_path / "data", name="gate", n_frames=1, width=40, height=24, n_seeds=4
    )
    settings["renders"] = "data/renders/{frame}/{view}/seed_{seed}.exr"
    settings["disparity"] = "data/disparity/{frame}.pfm"
    (tmp_path / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}))

    def audit(light, *options):
        def finished(args, root):
            summary = Path(root) / "results" / "audit" / "gate" / "summary.json"
            summary.parent.mkdir(parents=True, exist_ok=True)
            lines = [f"{light.upper()}: the verdict's headline.", "a second line"]
            summary.write_text(json.dumps(verdict_summary(light, lines)))
            return 0

        monkeypatch.setattr(cli, "_snakemake", finished)
        return cli.main(["audit", "audit.yaml", *options])

    return audit


@pytest.mark.parametrize(
    ("light", "level", "status"),
    [("red", "amber", FAIL_ON_STATUS), ("amber", "red", 0), ("amber", "amber", FAIL_ON_STATUS),
     ("green", "amber", 0), ("red", None, 0)],
)  # fmt: skip
def test_audit_fail_on_exits_with_the_verdict_line(audited, capsys, light, level, status):
    rc = audited(light, *(["--fail-on", level] if level else []))
    out, err = capsys.readouterr()
    assert rc == status
    assert out.startswith(f"{light.upper()}: the verdict's headline.\n")  # printed either way
    gate = [line for line in err.splitlines() if "--fail-on" in line]
    if status:
        assert gate == [f"stereovar: --fail-on {level}: {light.upper()}: the verdict's headline."]
    else:
        assert gate == []


def test_fail_on_with_import_only_is_refused_before_anything_runs(audited, capsys):
    """An import makes no verdict: a gate on it would pass every time."""
    assert audited("red", "--fail-on", "red", "--import-only") == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1 and "--import-only" in err
    assert not Path("results").exists()


def test_fail_on_status_is_none_of_the_others():
    assert FAIL_ON_STATUS not in (0, 1, 2)
