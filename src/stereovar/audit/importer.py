"""Import an audit's files into the project's render and ground-truth store contracts.

:func:`import_audit` discovers the frames (:func:`stereovar.audit.layout.discover`), checks
every file's size from its header, hashes every file (SHA-256) and re-imports only the
frames whose files, or whose import settings, changed since the last import (the record is
``results/audit/{name}/import.json``). A frame is imported by decoding all of its files,
checking them, settling the disparity sign photometrically
(:func:`stereovar.audit.sign.sign_check`) and only then writing its stores, each atomically:
a bad file stops the import with one line and leaves every store already imported as it was.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
import warnings
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import AuditError
from ..experiment import audit_source, batch_label, ground_truth_store, render_store
from ..io.contracts import config_digest
from ..io.images import image_format, image_size, read_field, read_image
from ..io.renders import render_dataset
from ..io.store import atomic_path, write_file, write_zarr
from ..rig import VIEWS
from .ground_truth import CONVENTIONS, disparity_from_depth, imported_ground_truth
from .layout import NAME, Discovery, Frame, discover
from .sign import sign_check

IMPORT_KEYS = (
    "views",
    "convention",
    "transfer",
    "scale",
    "disparity_scale",
    "focal_px",
    "baseline_m",
    "glass_ids",
    "spp",
)
"""``audit:`` settings that change what a frame imports to (a change re-imports it)."""

DEFAULT_DISPARITY_SCALE = 256.0
"""PNG disparity is value / 256 (KITTI); 0 is invalid."""


def manifest_path(name: str) -> str:
    """The import record of an audit: ``results/audit/{name}/import.json``."""
    return f"results/{audit_source(name)}/import.json"


def audit_spp(settings: dict) -> int:
    """The SPP the audit's stores are labelled with: ``audit.spp``, or 0 (not given)."""
    return int(settings.get("spp") or 0)


def frame_stores(settings: dict, frame: str, n_seeds: int) -> dict:
    """View (and ``ground_truth``) to the store paths of one imported frame."""
    source = audit_source(settings["name"])
    batch = batch_label(range(n_seeds))
    stores = {
        view: render_store(source, frame, view, audit_spp(settings), batch) for view in VIEWS
    }
    stores["ground_truth"] = ground_truth_store(source, frame)
    return stores


def sha256(path) -> str:
    """SHA-256 of a file's bytes."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


@dataclass
class FrameReport:
    """What importing one frame found."""

    name: str
    imported: bool
    nonfinite_pixels: dict = field(default_factory=dict)
    invalid_disparity: int = 0
    outside: int = 0
    valid: int = 0
    floored: dict = field(default_factory=dict)
    sign: dict = field(default_factory=dict)


@dataclass
class ImportReport:
    """An audit's import: what was found, what was imported, and the warnings."""

    name: str
    discovery: Discovery
    frames: list
    warnings: list = field(default_factory=list)
    seconds: dict = field(default_factory=dict)
    """Wall-clock seconds per phase (``hash``, ``ground truth``, ``decode``, ``sign check``,
    ``write``), summed over the frames."""

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
            f"audit {self.name}: {self.discovery.summary()}; imported "
            f"{len(imported)} frame{'s' * (len(imported) != 1)}"
            + (f" ({', '.join(imported)})" if imported else "")
            + f", {kept} unchanged"
        ]
        for f in self.frames:
            if not f.imported:
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


def _settings_digest(settings: dict) -> str:
    return config_digest({k: settings.get(k) for k in IMPORT_KEYS})


def _load_manifest(name: str) -> dict:
    path = Path(manifest_path(name))
    try:
        return json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        return {}


def _file_records(frame: Frame, old: dict, pool) -> dict:
    """Path to ``{sha256, size, mtime_ns}``; a file whose size and mtime match the last
    import keeps its recorded hash (as ``git status`` does)."""
    stats = {str(p): os.stat(p) for p in frame.files()}
    records, to_hash = {}, []
    for path, st in stats.items():
        prev = old.get(path)
        if prev and prev["size"] == st.st_size and prev["mtime_ns"] == st.st_mtime_ns:
            records[path] = prev
        else:
            to_hash.append(path)
    for path, digest in zip(to_hash, pool.map(sha256, to_hash), strict=True):
        st = stats[path]
        records[path] = {"sha256": digest, "size": st.st_size, "mtime_ns": st.st_mtime_ns}
    return records


def _check_sizes(frame: Frame) -> tuple[int, int]:
    """The frame's size from its files' headers; a file whose header gives another size than
    most of the frame's files is named, before any file is decoded."""
    sizes = {path: image_size(path) for path in frame.files()}
    size, count = Counter(sizes.values()).most_common(1)[0]  # a tie: the first render's
    for path, other in sizes.items():
        if other != size:
            others = (
                f"the frame's other {count} files are"
                if count == len(sizes) - 1
                else f"{count} of the frame's {len(sizes)} files are"
            )
            raise AuditError(
                f"{path} is {other[1]}x{other[0]} px but {others} {size[1]}x{size[0]} px; every "
                "render, disparity, depth and mask of a frame needs the same size: export them "
                "at one resolution"
            )
    return size


def _is_png8(path) -> bool:
    if image_format(path) != "png":
        return False
    with open(path, "rb") as f:
        head = f.read(25)
    return len(head) == 25 and head[24] == 8


def _disparity(settings: dict, frame: Frame) -> dict:
    gt = frame.ground_truth
    if "disparity" in gt:
        scale = float(settings.get("disparity_scale") or DEFAULT_DISPARITY_SCALE)
        return {v: read_field(p, png_scale=scale) for v, p in gt["disparity"].items()}
    focal, baseline = settings.get("focal_px"), settings.get("baseline_m")
    if not (focal and baseline):
        raise AuditError(
            "audit.depth needs audit.focal_px and audit.baseline_m to give disparity "
            "(d = f B / z); set both, or give audit.disparity"
        )
    return {
        v: disparity_from_depth(read_field(p), focal_px=float(focal), baseline_m=float(baseline))
        for v, p in gt["depth"].items()
    }


def _depth(settings: dict, frame: Frame, disparity: dict) -> dict:
    if "depth" in frame.ground_truth:
        return {v: read_field(p) for v, p in frame.ground_truth["depth"].items()}
    focal, baseline = settings.get("focal_px"), settings.get("baseline_m")
    if focal and baseline:
        return {
            v: disparity_from_depth(d, focal_px=float(focal), baseline_m=float(baseline))
            for v, d in disparity.items()
        }
    return {}


def _glass(settings: dict, frame: Frame):
    gt = frame.ground_truth
    if "glass_mask" in gt:
        path = gt["glass_mask"][VIEWS[0]]
        return read_field(path) > 0, f"glass mask {path}"
    if "segmentation" in gt:
        ids = settings.get("glass_ids") or []
        if not ids:
            raise AuditError(
                "audit.segmentation needs audit.glass_ids, the segment ids that are glass; "
                "list them (e.g. glass_ids: [3, 7])"
            )
        path = gt["segmentation"][VIEWS[0]]
        seg = read_field(path)
        return np.isin(np.rint(seg).astype(np.int64), ids), f"segmentation {path}"
    return None, None


def _seed_mean(stack: np.ndarray, n_nonfinite) -> np.ndarray:
    """Mean over seeds, skipping NaN/Inf (a plain float64 mean when every value is finite)."""
    if not np.any(n_nonfinite):
        return stack.mean(axis=0, dtype=np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN pixels stay NaN
        return np.nanmean(np.where(np.isfinite(stack), stack, np.nan), axis=0)


def _floored_fraction(stack: np.ndarray, valid: np.ndarray) -> float:
    """Fraction of ``valid`` pixels whose N renders are identical in every channel (their
    estimated variance is 0: quantisation floored it)."""
    same = (stack == stack[:1]).all(axis=(0, 3))
    return float((same & valid).sum() / max(int(valid.sum()), 1))


def _decode_view(paths: list, size: tuple, pool, transfer, scale) -> tuple:
    """Decode one view's renders into one ``(n, H, W, 3)`` float32 stack, each file straight
    into its slice by a worker thread, which also counts its NaN/Inf pixels."""
    stack = np.empty((len(paths), *size, 3), dtype=np.float32)

    def one(k):
        image = read_image(paths[k], transfer=transfer, scale=scale, out=stack[k])
        if np.isfinite(image.sum(dtype=np.float64)):  # one pass when every value is finite
            return 0
        return int((~np.isfinite(image)).any(axis=-1).sum())

    return stack, np.asarray(list(pool.map(one, range(len(paths)))), dtype=np.int64)


def _import_frame(settings, frame: Frame, size, records: dict, pool, report: ImportReport):
    """Import one frame: its ground truth, then its renders, the sign check and the stores.

    Every store is written to a temporary path and renamed into place only once every file
    of the frame decoded and the sign check passed, so a failure leaves the frame's old
    stores as they were.
    """
    transfer, scale = settings.get("transfer"), float(settings.get("scale") or 1.0)
    sign = CONVENTIONS[settings.get("convention") or "conventional"]
    files = {str(p): records[str(p)]["sha256"] for p in frame.files()}
    digest = config_digest({"files": files, "settings": _settings_digest(settings)})
    source = audit_source(settings["name"])
    fr = FrameReport(frame.name, True)
    with report.timed("ground truth"):
        gt = _frame_ground_truth(settings, frame, sign, digest, source, files, fr)
    datasets, means = {}, {}
    for view in VIEWS:
        labels = list(frame.renders[view])
        paths = [str(p) for p in frame.renders[view].values()]
        with report.timed("decode"):
            images, n_bad = _decode_view(paths, size, pool, transfer, scale)
        fr.nonfinite_pixels[view] = int(n_bad.sum())
        means[view] = _seed_mean(images, n_bad)
        if any(_is_png8(p) for p in paths):
            fr.floored[view] = _floored_fraction(images, gt["valid"].sel(view=view).values)
        datasets[view] = render_dataset(
            images,
            view=view,
            seeds=list(range(len(paths))),
            sampler_seeds=[int(s) if s.isdigit() else k for k, s in enumerate(labels)],
            n_nonfinite=n_bad,
            attrs={
                "scene": frame.name,
                "scene_digest": digest,
                "renderer": source,
                "renderer_version": "",
                "variant": "imported",
                "spp": audit_spp(settings),
                "seed_policy": "unknown",
                "width": int(size[1]),
                "height": int(size[0]),
                "seed_labels": labels,
                "source_files": paths,
                "source_sha256": [files[p] for p in paths],
                "transfer": transfer or "",
            },
        )
    with report.timed("sign check"):
        _check_sign(settings, frame, gt, means, sign, fr, report)
    datasets["ground_truth"] = gt
    stores = frame_stores(settings, frame.name, frame.n_seeds)
    with report.timed("write"), ExitStack() as staged:  # renamed into place together
        for key, ds in datasets.items():
            tmp = staged.enter_context(atomic_path(stores[key]))
            write_zarr(ds, tmp, chunk_dims={"seed": 1} if key in VIEWS else None)
    for view, fraction in fr.floored.items():
        report.warnings.append(
            f"frame {frame.name}, {view}: 8-bit PNG quantisation floors the variance to 0 at "
            f"{100 * fraction:.1f}% of the valid pixels (all {frame.n_seeds} renders "
            "identical); export 16-bit PNG or EXR for an audit that can see small variance"
        )
    return fr


def _frame_ground_truth(settings, frame: Frame, sign, digest, source, files, fr: FrameReport):
    """The frame's ground-truth dataset; fills the disparity counts of ``fr``."""
    disparity = _disparity(settings, frame)
    glass, glass_source = _glass(settings, frame)
    gt_files = [str(p) for paths in frame.ground_truth.values() for p in paths.values()]
    gt, counts = imported_ground_truth(
        disparity[VIEWS[0]],
        sign=sign,
        disparity_right=disparity.get(VIEWS[1]),
        depth=_depth(settings, frame, disparity),
        glass=glass,
        material_source=glass_source,
        attrs={
            "scene": frame.name,
            "scene_digest": digest,
            "renderer": source,
            "baseline_m": float(settings.get("baseline_m") or 0.0),
            "focal_px": float(settings.get("focal_px") or 0.0),
            "source_files": gt_files,
            "source_sha256": [files[p] for p in gt_files],
        },
    )
    if counts["valid"] == 0:
        path = frame.ground_truth.get("disparity", frame.ground_truth.get("depth"))[VIEWS[0]]
        raise AuditError(
            f"{path}: no valid disparity (NaN, zero or negative everywhere, or every match "
            "outside the right image); give positive disparity magnitudes in px"
        )
    fr.invalid_disparity, fr.outside, fr.valid = (
        counts["invalid_disparity"],
        counts["outside"],
        counts["valid"],
    )
    return gt


def _check_sign(settings, frame: Frame, gt, means, sign, fr: FrameReport, report) -> None:
    """The photometric sign check (:func:`stereovar.audit.sign.sign_check`) of one frame:
    one line naming the convention to set when the opposite one matches clearly better."""
    left_gt = gt.sel(view="left")
    compare = left_gt["valid"].values & ~left_gt["glass"].values & ~left_gt["occluded"].values
    check = sign_check(
        means["left"], means["right"], left_gt["disparity"].values, sign=sign, valid=compare
    )
    if check.opposite_wins:
        other = "conventional" if sign == 1 else "paper"
        rel = {1: "x_R = x_L + d", -1: "x_R = x_L - d"}
        raise AuditError(
            f"frame {frame.name}: the disparity follows the other convention: the right seed "
            f"mean warped into the left matches with a median error of "
            f"{100 * check.opposite_error:.1f}% under {rel[-sign]} but "
            f"{100 * check.error:.1f}% under the declared {rel[sign]}; set audit.convention: "
            f"{other}"
        )
    if not check.conclusive:
        report.warnings.append(
            f"frame {frame.name}: the sign check is inconclusive: {check.reason} (median error "
            f"{100 * check.error:.1f}% declared, {100 * check.opposite_error:.1f}% opposite); "
            f"audit.convention: {settings.get('convention') or 'conventional'} is taken as given"
        )
    gt.attrs.update(check.attrs())
    fr.sign = {"error": check.error, "opposite_error": check.opposite_error}


def check_settings(settings: dict) -> None:
    """The ``audit:`` settings that need no file: the name and the convention."""
    name = str(settings.get("name") or "")
    if not NAME.fullmatch(name):
        raise AuditError(
            f"audit.name {name!r} may only contain letters, digits, _ and - (it names "
            "results/audit/<name>/); pick another name"
        )
    convention = settings.get("convention") or "conventional"
    if convention not in CONVENTIONS:
        raise AuditError(
            f"audit.convention {convention!r} is unknown; use paper (x_R = x_L + d) or "
            "conventional (x_R = x_L - d)"
        )


def import_audit(settings: dict, *, workers: int = 2) -> ImportReport:
    """Import an audit's files into the render and ground-truth store contracts.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section (see ``workflow/schemas/config.schema.yaml``).
    workers : int, keyword-only
        Threads that hash and decode files.

    Returns
    -------
    ImportReport
        Frames found, imported and unchanged, with warnings (8-bit PNG floors, PNG
        transfer assumed, inconclusive sign checks).

    Raises
    ------
    AuditError, ImageError
        One line naming the file and the fix; stores already imported are left as they are.
    """
    check_settings(settings)
    found = discover(settings)
    name = settings["name"]
    old = _load_manifest(name)
    digest = _settings_digest(settings)
    report = ImportReport(name, found, [])
    pngs = [p for f in found.frames for v in VIEWS for p in f.renders[v].values()]
    if not settings.get("transfer") and any(image_format(p) == "png" for p in pngs):
        report.warnings.append(
            "PNG renders without audit.transfer are decoded as sRGB; set audit.transfer: "
            "linear or srgb to say how they were written"
        )
    sizes = [_check_sizes(frame) for frame in found.frames]
    manifest = {"settings": digest, "frames": {}}
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        for frame, size in zip(found.frames, sizes, strict=True):
            prev = old.get("frames", {}).get(frame.name, {})
            with report.timed("hash"):
                records = _file_records(frame, prev.get("files", {}), pool)
            stores = frame_stores(settings, frame.name, frame.n_seeds)
            unchanged = (
                old.get("settings") == digest
                and {p: r["sha256"] for p, r in prev.get("files", {}).items()}
                == {p: r["sha256"] for p, r in records.items()}
                and all(Path(s).is_dir() for s in stores.values())
            )
            if unchanged:
                report.frames.append(FrameReport(frame.name, False))
            else:
                try:
                    fr = _import_frame(settings, frame, size, records, pool, report)
                    report.frames.append(fr)
                except MemoryError:
                    raise AuditError(
                        f"frame {frame.name}: its renders do not fit in memory; import fewer "
                        "seeds per frame"
                    ) from None
            manifest["frames"][frame.name] = {"files": records, "stores": stores}
            _write_manifest(name, old, manifest)
    return report


def _write_manifest(name: str, old: dict, manifest: dict) -> None:
    """Record the frames imported so far; frames not reached yet keep their old record."""
    frames = {**old.get("frames", {}), **manifest["frames"]}
    if old.get("settings") != manifest["settings"]:
        frames = dict(manifest["frames"])
    text = json.dumps({"settings": manifest["settings"], "frames": frames}, indent=1)
    write_file(manifest_path(name), lambda tmp: Path(tmp).write_text(text))
