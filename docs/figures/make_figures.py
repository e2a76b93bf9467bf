"""Make the documentation's figures from two tiny runs, and write them to ``docs/figures/``.

Run it from the checkout (about a minute on 2 cores; ``make docs-figures``)::

    .venv/bin/python docs/figures/make_figures.py

- **The tiny run**: the workflow copied to a temporary folder with the two scenes and the
  configuration of ``tests/test_workflow.py`` (its ``TINY``, imported: 48x27 pixels, SPP 2, N = 2
  seeds; the test suite runs the same), asked for the main run's figures with
  ``snakemake -j2 --configfile tiny.yaml <figures>``. Its figures go in the user guide.
- **The example audit**: the two synthetic frames that ``stereovar init --example`` writes
  (:func:`stereovar.audit.synthetic.write_synthetic_audit`), audited by the workflow as
  ``stereovar audit audit.yaml`` does, asked for the verdict page's figures with
  ``snakemake -j2 <figures> --configfile audit.yaml``. Its figures go on the audit page.

Each PNG is reduced to a 256-colour palette (at most 1000 pixels wide), which keeps it under
150 KB; the pages say which run and command made each figure.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml
from PIL import Image

REPO = Path(__file__).resolve().parents[2]
OUT = Path(__file__).resolve().parent

sys.path.insert(0, str(REPO))
from tests.test_workflow import SCENES, TINY  # noqa: E402  the suite's tiny configuration

#: Figures of the tiny run: its path under the run, the name written here.
RUN_FIGURES = {
    "results/mitsuba/seeds/figures/fig1_teaser.png": "tiny_fig1_teaser.png",
    "results/mitsuba/seeds/figures/statistics_dots.png": "tiny_statistics_dots.png",
}
#: Figures of the example audit.
AUDIT_FIGURES = {
    "results/audit/synthetic/figures/teaser_f00.png": "audit_teaser_f00.png",
    "results/audit/synthetic/figures/calibration.png": "audit_calibration.png",
}

MAX_WIDTH = 1000


def snakemake(root: Path, *args: str) -> None:
    """``snakemake -j2 ARGS`` in ``root``, failing loudly."""
    subprocess.run([sys.executable, "-m", "snakemake", "-j2", *args, "--quiet", "rules"], cwd=root,
                   check=True)  # fmt: skip


def copy_workflow(root: Path) -> Path:
    """The checkout's workflow, configs and the tiny run's scenes, copied to ``root``."""
    root.mkdir(parents=True)
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(REPO / name, root / name)
    for name in ("workflow", "profiles", "envs"):
        shutil.copytree(REPO / name, root / name)
    (root / "scenes").mkdir()
    for scene in SCENES:
        shutil.copy(REPO / "scenes" / f"{scene}.yaml", root / "scenes")
    return root


def small_png(source: Path, target: Path) -> int:
    """``source`` as a palette PNG of at most :data:`MAX_WIDTH` pixels; returns its bytes."""
    image = Image.open(source).convert("RGB")
    if image.width > MAX_WIDTH:
        height = round(image.height * MAX_WIDTH / image.width)
        image = image.resize((MAX_WIDTH, height), Image.Resampling.LANCZOS)
    image.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(target, optimize=True)
    return target.stat().st_size


def tiny_run(work: Path) -> Path:
    root = copy_workflow(work / "tiny")
    (root / "tiny.yaml").write_text(yaml.safe_dump(TINY))
    snakemake(root, *RUN_FIGURES, "--configfile", "tiny.yaml")
    return root


def example_audit(work: Path) -> Path:
    from stereovar.audit.synthetic import write_synthetic_audit

    root = copy_workflow(work / "audit")
    settings, _ = write_synthetic_audit(root / "data" / "synthetic")
    settings = {**settings, **{k: str(Path(v).relative_to(root)) for k, v in settings.items()
                               if isinstance(v, str) and v.startswith(str(root))}}
    (root / "audit.yaml").write_text(yaml.safe_dump({"audit": settings}, sort_keys=False))
    snakemake(root, *AUDIT_FIGURES, "--configfile", "audit.yaml")
    return root


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="stereovar-docs-figures-") as tmp:
        work = Path(tmp)
        for root, figures in ((tiny_run(work), RUN_FIGURES), (example_audit(work), AUDIT_FIGURES)):
            for source, name in figures.items():
                size = small_png(root / source, OUT / name)
                print(f"{OUT / name}: {size / 1024:.0f} KB (from {source})")


if __name__ == "__main__":
    main()
