"""What an import finds and what it records: the warnings it can give and their thresholds
(:data:`WARNING_KINDS`), the report of a frame and of an audit (:class:`FrameReport`,
:class:`ImportReport`), each frame's import record
(``results/audit/{name}/import/{frame}.json``, :func:`~stereovar.layout.import_record`:
:func:`load_record`, :func:`write_record`), and the temporaries a killed import leaves
(:func:`killed_imports`).
"""

from __future__ import annotations

import json
import os
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from ..io.store import remove_stale_temporaries, stale_temporaries, write_file
from ..layout import import_record
from .layout import Discovery
from .settings import settings_digest

WARNING_KINDS = {
    "sign_check": "sign check inconclusive",
    "sign_check_error": "sign check error high",
    "disparity_offset": "disparity offset",
    "outside": "matches outside the other view",
    "transfer": "PNG transfer assumed",
    "quantisation": "variance quantised",
    "clipped": "clipped pixels",
    "glass_ids": "glass ids match nothing",
}
"""Kinds of import warnings (each a flagged row of the verdict page) and their labels."""

QUANTISED_WARNING = 0.001
"""Share of a view's valid pixels whose renders are all identical (8-bit PNG) from which the
import warns: quantisation floored their variance to 0."""

HALF_STEPS = 2.0
"""A pixel of half-float renders (:func:`~stereovar.audit.decoding.half_renders`) is
quantised when its spread across the seeds is below this many half-float steps (at its
seed mean) in every channel: its few distinct values distort its variance."""

OUTSIDE_WARNING = 0.5
"""Share of a frame's left pixels whose match falls outside the right image above which the
import warns: the disparity is too large for the image (a depth map, another unit)."""

CLIPPED_WARNING = 0.001
"""Share of a view's valid pixels at full scale in some render (PNG) above which the
import warns: a clipped pixel's variance is cut off."""


@dataclass
class FrameReport:
    """What importing one frame found (in a dry run: that it would be imported)."""

    name: str
    imported: bool
    nonfinite_pixels: dict = field(default_factory=dict)
    invalid_disparity: int = 0
    outside: int = 0
    valid: int = 0
    floored: dict = field(default_factory=dict)
    clipped: dict = field(default_factory=dict)
    """View to the share of its valid pixels at full scale in some render (PNG only)."""
    half: dict = field(default_factory=dict)
    """View to the share of its valid pixels whose spread across the seeds is below
    :data:`HALF_STEPS` half-float steps (renders in half precision only)."""
    sign: dict = field(default_factory=dict)
    offset: dict = field(default_factory=dict)
    """The offset check's findings (:meth:`stereovar.audit.offset.OffsetCheck.facts`)."""
    n_seeds: int = 0

    def facts(self) -> dict:
        """What the import found, as JSON for the frame's
        :func:`~stereovar.layout.import_record`."""
        return {
            "valid": self.valid,
            "invalid_disparity": self.invalid_disparity,
            "outside": self.outside,
            "nonfinite_pixels": self.nonfinite_pixels,
            "floored": self.floored,
            "clipped": self.clipped,
            "half": self.half,
            "sign": self.sign,
            "offset": self.offset,
            "n_seeds": self.n_seeds,
        }


@dataclass
class ImportReport:
    """An audit's import: what was found, what was imported, and the warnings."""

    name: str
    discovery: Discovery
    frames: list
    warnings: list = field(default_factory=list)
    """The warnings' texts, in order."""
    flags: list = field(default_factory=list)
    """The warnings as ``{"kind", "frame", "text"}`` (``kind`` one of
    :data:`WARNING_KINDS`; ``frame`` None for the whole audit)."""
    seconds: dict = field(default_factory=dict)
    """Wall-clock seconds per phase (``hash`` of unchanged frames, ``ground truth``,
    ``decode`` (each including its files' hashes), ``sign check``, ``offset check``,
    ``write``), summed over the frames."""
    dry_run: bool = False
    """Nothing was written: :attr:`frames` that are ``imported`` would be."""
    temporaries: list = field(default_factory=list)
    """Temporaries of killed imports removed (in a dry run: that would be)."""

    def warn(self, kind: str, text: str, frame: str | None = None) -> None:
        """Add a warning of a :data:`WARNING_KINDS` kind."""
        if kind not in WARNING_KINDS:
            raise ValueError(f"unknown warning kind {kind!r}; use one of {list(WARNING_KINDS)}")
        self.warnings.append(text)
        self.flags.append({"kind": kind, "frame": frame, "text": text})

    @contextmanager
    def timed(self, phase: str):
        """Add the time spent in the block to :attr:`seconds` ``[phase]``."""
        start = time.perf_counter()
        try:
            yield
        finally:
            elapsed = time.perf_counter() - start
            self.seconds[phase] = self.seconds.get(phase, 0.0) + elapsed

    def lines(self) -> list[str]:
        """Human-readable summary lines."""
        imported = [f.name for f in self.frames if f.imported]
        kept = len(self.frames) - len(imported)
        out = [
            f"audit {self.name}: {self.discovery.summary()}; "
            f"{'would import' if self.dry_run else 'imported'} "
            f"{len(imported)} frame{'s' * (len(imported) != 1)}"
            + (f" ({', '.join(imported)})" if imported else "")
            + f", {kept} unchanged"
            + (" (dry run: nothing written)" if self.dry_run else "")
        ]
        if self.temporaries:
            n = len(self.temporaries)
            pids = sorted({int(str(p.name).rsplit(".tmp-", 1)[1].split("-")[0])
                           for p in self.temporaries})
            shown = ", ".join(str(p) for p in self.temporaries[:3])
            out.append(
                f"  {'would remove' if self.dry_run else 'removed'} {n} "
                f"temporar{'y' if n == 1 else 'ies'} of killed imports "
                f"(process{'es' * (len(pids) > 1)} {', '.join(map(str, pids))}): {shown}"
                + (f" and {n - 3} more" if n > 3 else "")
            )
        for f in self.frames:
            if not f.imported or self.dry_run:
                continue
            bad = sum(f.nonfinite_pixels.values())
            out.append(
                f"  {f.name}: {f.valid} valid left pixels; {f.invalid_disparity} with NaN, "
                f"zero or negative disparity and {f.outside} whose match falls outside the "
                f"right image are invalid; {bad} render pixels with NaN/Inf (excluded)"
                + (
                    f"; sign check: median error {100 * f.sign['error']:.1f}% declared, "
                    f"{100 * f.sign['opposite_error']:.1f}% opposite"
                    if f.sign
                    else ""
                )
            )
        out += [f"  warning: {w}" for w in self.warnings]
        return out



def load_record(name: str, frame: str) -> dict:
    """The :func:`~stereovar.layout.import_record` of a frame (empty when there is none or it
    is unreadable)."""
    path = Path(import_record(name, frame))
    try:
        return json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        return {}



def store_folders(name: str) -> tuple[list, Path]:
    """The folders the import writes stores in, and the one of its records."""
    base = Path(import_record(name, "frame")).parent.parent
    folders = []
    for sub in ("renders", "ground_truth"):
        for folder, dirs, _ in os.walk(base / sub):
            folders.append(folder)
            dirs[:] = [d for d in dirs if not d.endswith(".zarr") and not d.startswith(".")]
    return folders, base


def killed_imports(name: str, *, remove: bool) -> list:
    """Temporaries that killed imports of ``name`` left (removed with ``remove``)."""
    folders, base = store_folders(name)
    find = remove_stale_temporaries if remove else stale_temporaries
    return find(folders) + find([Path(import_record(name, "frame")).parent])



def write_record(settings: dict, frame: str, files: dict, stores: dict, found: dict) -> None:
    """Write a frame's :func:`~stereovar.layout.import_record` atomically (not again when
    unchanged): ``found`` is what the import found (:meth:`FrameReport.facts` and its ``warnings``),
    which the verdict page shows."""
    record = {
        "audit": settings["name"],
        "frame": frame,
        "settings": settings_digest(settings),
        "files": files,
        "stores": stores,
        "found": found,
    }
    text = json.dumps(record, indent=1)
    path = Path(import_record(settings["name"], frame))
    try:
        if path.read_text() == text:
            return
    except (OSError, UnicodeDecodeError):
        pass
    write_file(path, lambda tmp: Path(tmp).write_text(text))
