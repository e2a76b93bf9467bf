"""The layout page's map of the workflow (``docs/_ext/stereovar_docs.py``,
``workflow_map``) names every rule file with each of its rules, and every input file with
each of its functions, read from ``workflow/rules`` as it is."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

RULES = Path(__file__).resolve().parents[1] / "workflow" / "rules"
EXT = Path(__file__).resolve().parents[1] / "docs" / "_ext" / "stereovar_docs.py"


def generated_map() -> str:
    spec = importlib.util.spec_from_file_location("stereovar_docs", EXT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.workflow_map(RULES)


def rows(text: str) -> dict:
    """First cell of each list-table row -> the row's other cells, joined."""
    out, key = {}, None
    for line in text.splitlines():
        if line.startswith("   * - "):
            key = line[len("   * - "):]
            out[key] = ""
        elif line.startswith("     - ") and key is not None:
            out[key] += line[len("     - "):] + "\n"
    return out


def test_every_rule_and_every_input_function_is_on_the_map():
    table = rows(generated_map())
    rule_files = [p for p in sorted(RULES.glob("*.smk")) if p.name != "common.smk"]
    assert len(rule_files) >= 15
    for path in rule_files:
        for rule in re.findall(r"^rule (\w+):", path.read_text(), re.M):
            assert f"``{rule}``" in table[f"``{path.name}``"], (path.name, rule)
    inputs = sorted(RULES.glob("inputs/*.smk"))
    assert inputs
    for path in [RULES / "common.smk", *inputs]:
        name = path.relative_to(RULES).as_posix()
        for function in re.findall(r"^def (\w+)\(", path.read_text(), re.M):
            assert f"``{function}``" in table[f"``{name}``"], (name, function)


def test_a_rule_file_names_the_input_files_whose_functions_it_calls():
    table = rows(generated_map())
    assert "``inputs/probe.smk``" in table["``probe.smk``"]
    assert "``inputs/mitigations.smk``" in table["``mitigations.smk``"]
    assert "``inputs/probe.smk``" not in table["``render.smk``"]
