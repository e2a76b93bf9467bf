"""Shared fixtures."""

import pytest


@pytest.fixture(scope="session")
def mi():
    """Mitsuba with the automatically selected variant (LLVM on CI machines)."""
    from stereovar.renderers.mitsuba.backend import load_mitsuba

    return load_mitsuba("auto")


@pytest.fixture
def tree_snapshot():
    """A function of a folder: every path under it (``.snakemake`` and the run locks'
    ``.locks``, which every run takes, aside) with its mtime and, for a file, the SHA-256 of
    its bytes; equal snapshots mean nothing was written there."""
    import hashlib
    import os
    from pathlib import Path

    def snapshot(root) -> dict:
        out = {}
        for folder, dirs, files in os.walk(root):
            dirs[:] = [d for d in dirs if d not in (".snakemake", ".locks")]
            for name in dirs + files:
                path = Path(folder, name)
                st = path.lstat()
                digest = (
                    hashlib.sha256(path.read_bytes()).hexdigest()
                    if path.is_file() and not path.is_symlink()
                    else None
                )
                out[str(path.relative_to(root))] = (st.st_mtime_ns, digest)
        return out

    return snapshot


@pytest.fixture(scope="session")
def verdict_summary():
    """A function of a light and the summary's lines: the smallest ``summary.json`` of that
    verdict that its schema takes (checked here), for stand-ins of the verdict job."""
    from stereovar.audit.summary_schema import SUMMARY_SCHEMA_VERSION, validate_summary

    def make(light: str, lines: list, name: str = "gate") -> dict:
        summary = {
            "schema_version": SUMMARY_SCHEMA_VERSION, "audit": name,
            "found": "1 frame × 2 views × 4 seeds", "mc_specific": None,
            "mc_specific_rho": {"value": None, "low": None, "high": None, "null": None,
                                "interval": "", "light": light},
            "provenance": {"stereovar_version": "0.1.0", "created": "2026-01-01T00:00:00Z",
                           "inputs_sha256": "0" * 64, "n_inputs": 0, "config_sha256": ""},
            "matched_null": False, "strength": "not testable", "matching_cue": None,
            "text": lines[0], "light": light, "decision": lines[:1], "shared_streams": None,
            "seeding": "", "flags": [], "summary": list(lines), "mitigations": [],
            "probe": None, "calibration": "", "rules": "", "rows": [], "csv": "",
            "strongest": None,
        }
        validate_summary(summary)
        return summary

    return make


@pytest.fixture(scope="session")
def textured_pair():
    """A function of ``(height, width, disparity, seed)``: a grey textured clean image (its
    log a smooth Gaussian field, mean about 0.3) whose right view is the left moved
    ``disparity`` pixels to the right (bilinear), with a uniform ground truth: ``(mean,
    truth)``, each a dict by view, as :class:`stereovar.calibration.replicates.SceneFrames`
    takes them."""
    import numpy as np
    from scipy.ndimage import gaussian_filter, shift

    def make(height, width, disparity, seed):
        rng = np.random.default_rng(seed)
        texture = gaussian_filter(rng.normal(0.0, 1.0, (height, width)), 1.5)
        left = np.repeat((0.3 * np.exp(texture / texture.std() - 1.0))[..., None], 3, axis=-1)
        right = np.stack([shift(left[..., c], (0, disparity), order=1, mode="nearest")
                          for c in range(3)], axis=-1)
        truth = {v: {"disparity": np.full((height, width), float(disparity)),
                     "valid": np.ones((height, width), bool)} for v in ("left", "right")}
        return {"left": left, "right": right}, truth

    return make


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """A copy of the workflow with the tiny config of ``tests/test_workflow.py``, run once to
    completion (``snakemake -j2 all``) and shared by every module that reads such a run;
    a test that changes it works on a copy (:func:`tiny_run_copy`)."""
    from .test_workflow import TINY, copy_workflow, snakemake

    root = copy_workflow(tmp_path_factory.mktemp("tiny") / "wf", TINY)
    snakemake(root, "-j2", "all")
    return root


@pytest.fixture(scope="session")
def tiny_run_copy(tiny_run):
    """A function of a folder: a copy of :func:`tiny_run` there, file times kept (so
    Snakemake finds every result up to date), to change freely."""
    import shutil

    def copy(root):
        return shutil.copytree(tiny_run, root, symlinks=True)

    return copy


@pytest.fixture(scope="session")
def docs_site(tmp_path_factory):
    """The documentation built once per session as ``make docs`` builds it (warnings are
    errors), into a temporary folder; the build's output is in the failure message. Its
    modules share one xdist group (``test_docs``), so the site is built once."""
    import subprocess
    import sys
    from pathlib import Path

    pytest.importorskip("sphinx", reason="the docs extra is not installed (make setup does)")
    repo = Path(__file__).resolve().parents[1]
    out = tmp_path_factory.mktemp("docs")
    result = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(out / "doctrees"), str(repo / "docs"), str(out / "html")],
        cwd=repo, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert result.returncode == 0, (
        f"the documentation build failed (warnings are errors):\n{result.stdout}{result.stderr}"
    )
    return out / "html"


@pytest.fixture(scope="session")
def interval_problems():
    """A function of a page's shown text and its quantities ``(value, low, high)``: the
    problems of its intervals, one line each. Every correlation-style interval (three
    decimals, ``v [a, b]``) lies inside [-1, 1], and wherever a quantity's value is shown
    with an interval, that interval is the quantity's own: one interval per quantity."""
    import math
    import re

    shown = re.compile(r"(?<![\d.])(-?\d+\.\d{3}) \[(-?\d+\.\d{3}), (-?\d+\.\d{3})\]")

    def problems(text: str, quantities=()) -> list[str]:
        out = [f"interval outside [-1, 1]: {m.group(0)}" for m in shown.finditer(text)
               if not all(-1.0 <= float(x) <= 1.0 for x in m.groups()[1:])]
        for value, low, high in quantities:
            if not all(math.isfinite(float(x)) for x in (value, low, high)):
                continue
            own = f"{value:.3f} [{low:.3f}, {high:.3f}]"
            out += [f"{m.group(0)} where {own} is meant" for m in shown.finditer(text)
                    if m.group(1) == f"{value:.3f}" and m.group(0) != own]
        return out

    return problems


@pytest.fixture(scope="session")
def headless_chromium():
    """A function ``load(path, *, width=1280, height=900, expression=None)``: open a local
    HTML file in headless Chromium (Debian's ``chromium``) through the DevTools protocol on a
    pipe, and return its ``errors`` (console errors, uncaught exceptions and failed loads,
    one line each), a viewport ``screenshot`` (PNG bytes) and the ``value`` of the
    JavaScript ``expression`` evaluated after the page has loaded. Skips where Chromium is
    not installed (``scripts/setup.sh`` installs it where it can)."""
    import base64
    import fcntl
    import json
    import os
    import select
    import shutil
    import subprocess
    import tempfile
    import time
    from pathlib import Path
    from types import SimpleNamespace

    binary = next(
        (b for b in ("chromium", "chromium-browser") if shutil.which(b)), None
    )
    if binary is None:
        pytest.skip(
            "Chromium is not installed (Debian/Ubuntu: apt-get install chromium; "
            "scripts/setup.sh installs it where it can)"
        )

    def load(path, *, width=1280, height=900, expression=None, timeout=60.0):
        deadline = time.monotonic() + timeout
        to_browser, from_browser = os.pipe(), os.pipe()
        # the browser reads commands on fd 3 and writes replies on fd 4; both ends are
        # moved above 4 first, so that dup2 onto 3 and 4 clobbers neither
        ends = [fcntl.fcntl(to_browser[0], fcntl.F_DUPFD, 10),
                fcntl.fcntl(from_browser[1], fcntl.F_DUPFD, 10)]

        def child_fds():
            os.dup2(ends[0], 3)
            os.dup2(ends[1], 4)

        profile = tempfile.mkdtemp(prefix="chromium-profile-")
        proc = subprocess.Popen(
            [binary, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
             "--remote-debugging-pipe", f"--user-data-dir={profile}", "--no-first-run",
             f"--window-size={width},{height}", "about:blank"],
            preexec_fn=child_fds, close_fds=False,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        )
        for fd in (*to_browser[:1], from_browser[1], *ends):
            os.close(fd)
        write_fd, read_fd = to_browser[1], from_browser[0]
        buffer, events, counter = b"", [], [0]

        def receive():
            nonlocal buffer
            while b"\0" not in buffer:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([read_fd], [], [], left)[0]:
                    raise TimeoutError(f"Chromium did not answer within {timeout:.0f} s")
                chunk = os.read(read_fd, 1 << 20)
                if not chunk:
                    raise RuntimeError("Chromium closed the DevTools pipe")
                buffer += chunk
            message, buffer = buffer.split(b"\0", 1)
            return json.loads(message)

        def call(method, params=None, session=None):
            counter[0] += 1
            message = {"id": counter[0], "method": method, "params": params or {}}
            if session:
                message["sessionId"] = session
            os.write(write_fd, json.dumps(message).encode() + b"\0")
            while True:
                reply = receive()
                if reply.get("id") == counter[0]:
                    if "error" in reply:
                        raise RuntimeError(f"{method}: {reply['error']}")
                    return reply["result"]
                events.append(reply)

        try:
            targets = call("Target.getTargets")["targetInfos"]
            page = next(t for t in targets if t["type"] == "page")
            session = call(
                "Target.attachToTarget", {"targetId": page["targetId"], "flatten": True}
            )["sessionId"]
            for domain in ("Page", "Runtime", "Log"):
                call(f"{domain}.enable", session=session)
            call("Emulation.setDeviceMetricsOverride",
                 {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
                 session=session)
            call("Page.navigate", {"url": Path(path).resolve().as_uri()}, session=session)
            while not any(e.get("method") == "Page.loadEventFired" for e in events):
                events.append(receive())
            value = None
            if expression is not None:
                value = call("Runtime.evaluate",
                             {"expression": expression, "returnByValue": True},
                             session=session)["result"].get("value")
            shot = call("Page.captureScreenshot", {"format": "png"}, session=session)
            call("Browser.close")
        finally:
            os.close(write_fd)
            os.close(read_fd)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            shutil.rmtree(profile, ignore_errors=True)
        errors = []
        for e in events:
            method, params = e.get("method"), e.get("params", {})
            if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                errors.append("console: " + " ".join(
                    str(a.get("value", a.get("description", ""))) for a in params["args"]))
            elif method == "Runtime.exceptionThrown":
                errors.append("exception: " + params["exceptionDetails"].get("text", ""))
            elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
                entry = params["entry"]
                errors.append(f"{entry['source']}: {entry['text']} {entry.get('url', '')}")
        return SimpleNamespace(
            errors=errors, screenshot=base64.b64decode(shot["data"]), value=value
        )

    return load


#: Fixtures whose one session-wide run several modules share: the tests that use them stay
#: on one xdist worker (``make test`` runs ``-n 2 --dist loadgroup``), so the run is made
#: once, and a test that changes it and puts it back is never seen half-way by another.
SHARED_RUN_FIXTURES = frozenset({"tiny_run", "tiny_run_copy"})
SHARED_RUN_GROUP = "tiny_run"

#: Groups that take minutes, longest first, so that no worker is left with one at the
#: end (the rest follow in collection order; ``make test``'s ``--durations`` shows what to
#: add). xdist gives each of the three workers two groups at the start: the fourth waits
#: behind the first.
FIRST = (
    SHARED_RUN_GROUP,
    "test_audit_workflow",
    "test_mitigations",
    "test_docs",  # short: it waits behind the shared run on the first worker
    "test_cycles",
    "test_moments_workflow",
    "test_audit_jobs",
    "test_faults",
    "test_probe_workflow",
    "test_ground_truth",
    "test_install",
    "test_photometric",
    "test_audit_cli_errors",
)


def xdist_group(item) -> str:
    """The xdist group of a test: its own mark, else the shared run's group for a test that
    uses :data:`SHARED_RUN_FIXTURES`, else its module (whose module-scoped fixtures are then
    made once)."""
    mark = item.get_closest_marker("xdist_group")
    if mark is not None:
        return str(mark.args[0] if mark.args else mark.kwargs.get("name", "default"))
    if SHARED_RUN_FIXTURES & set(getattr(item, "fixturenames", ())):
        return SHARED_RUN_GROUP
    return item.nodeid.split("::", 1)[0].rsplit("/", 1)[-1].removesuffix(".py")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Give every test its xdist group and put the longest groups first (a stable sort, so
    a group's tests keep their order)."""
    groups = {}
    for item in items:
        groups[item.nodeid] = group = xdist_group(item)
        if item.get_closest_marker("xdist_group") is None:
            item.add_marker(pytest.mark.xdist_group(group))
    rank = {name: i for i, name in enumerate(FIRST)}
    items.sort(key=lambda item: rank.get(groups[item.nodeid], len(rank)))
