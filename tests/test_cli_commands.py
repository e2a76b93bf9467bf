"""The command line as a new user meets it: ``python -m stereovar``, a bare ``stereovar``
and ``--help`` (examples and the documentation's address), ``run --help``'s targets against
the workflow's own rules, tab completion, ``init --example`` run twice, and the CI gate
``audit --fail-on``."""

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
