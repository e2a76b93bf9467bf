"""The workflow plans the same jobs as the reference: a change to its wiring (the rule files,
``workflow/rules/inputs/``, :mod:`stereovar.workflow_inputs`) that is meant to change nothing
changes nothing a user runs.

The dry-run job lists of the user targets on the default ``config.yaml`` (every job's rule,
wildcards, input, output and log files, params, threads and resources:
``tests/dryrun_jobs.py``) equal those recorded in ``tests/golden/dryrun/`` before the
workflow's ``common.smk`` and the audit's importer were split into modules. The suite plans
:data:`SUITE` (one dry run each, in one process): ``all`` (whose plan holds every job of
``mitigations`` and ``calibration`` too: their listings differ from its lines only by their
own target rule), the synthetic example's audit, and ``generators`` and ``export``, which
``all`` does not build. ``probe``, ``mitigations`` and ``calibration`` are checked by the
same command with every listing::

    python tests/dryrun_jobs.py --write /tmp/listings && diff -r /tmp/listings tests/golden/dryrun

A change that is meant to change the plan (a new param, a renamed output) updates the
reference with ``python tests/dryrun_jobs.py --write tests/golden/dryrun`` in the same
commit, so the diff shows what it changed. The golden tables of the tiny run (that the jobs
compute the same numbers) are checked by ``tests/test_workflow.py`` and
``tests/test_moments_workflow.py``.
"""

from __future__ import annotations

import difflib
import json
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden" / "dryrun"
#: The listings the suite plans (``tests/dryrun_jobs.py`` LISTINGS has every user target).
SUITE = ("all", "audit", "generators", "export")

pytestmark = pytest.mark.workflow


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> Path:
    """The listings of :data:`SUITE`, planned now in fresh copies of this checkout's
    workflow (one process)."""
    out = tmp_path_factory.mktemp("dryrun")
    subprocess.run(
        [sys.executable, str(HERE / "dryrun_jobs.py"), "--write", str(out), *SUITE],
        check=True,
        capture_output=True,
        text=True,
    )
    return out


def test_every_user_target_has_a_reference_listing():
    from tests.dryrun_jobs import LISTINGS

    assert sorted(p.stem for p in GOLDEN.glob("*.txt")) == sorted(LISTINGS)
    assert set(SUITE) <= set(LISTINGS)


@pytest.mark.parametrize("name", SUITE)
def test_the_dry_run_plans_the_reference_jobs(planned, name):
    now = (planned / f"{name}.txt").read_text().splitlines()
    reference = (GOLDEN / f"{name}.txt").read_text().splitlines()
    assert now, f"the {name} dry run planned no job"
    if now != reference:
        rules = sorted({json.loads(line)["rule"] for line in set(now) ^ set(reference)})
        diff = "\n".join(
            difflib.unified_diff(reference, now, "golden", "now", n=0, lineterm="")
        )[:4000]
        pytest.fail(
            f"the {name} dry run plans other jobs than tests/golden/dryrun/{name}.txt "
            f"(rules {', '.join(rules)}); if that is meant, rewrite the reference with "
            f"`python tests/dryrun_jobs.py --write tests/golden/dryrun`:\n{diff}"
        )
