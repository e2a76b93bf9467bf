"""Import an audit's files into the project's render and ground-truth store contracts.

:func:`import_audit` discovers the frames (:func:`stereovar.audit.layout.discover`), checks
every file's size from its header and re-imports only the frames whose files, or whose import
settings, changed since the last import (one record per frame,
``results/audit/{name}/import/{frame}.json``: :func:`~stereovar.layout.import_record`).
Whether a file changed is decided on its content (SHA-256), never on its size and time stamps
alone: ``cp -p``, ``rsync -a`` and ``tar x`` keep both. The workflow imports one frame per job
(:func:`import_frame`, rule ``audit_import``); Snakemake decides which frames to import again
(:func:`~stereovar.audit.hashing.frame_fingerprint` is the rule's ``params``). A frame is
imported by decoding all of its files, checking them, settling the disparity sign
photometrically (:func:`stereovar.audit.sign.sign_check`), checking it for an offset
(:func:`stereovar.audit.offset.offset_check`: a warning) and only then writing its stores,
each atomically: a bad file stops the import with one line and leaves every store already
imported as it was.

Each file is hashed and decoded while one open descriptor holds it, and checked afterwards
(:func:`~stereovar.audit.hashing.read_verified`): a file replaced or rewritten meanwhile stops
the import, so the SHA-256 recorded with a store is always that of the bytes decoded into it.

This module runs the import; its parts live beside it: :mod:`~stereovar.audit.layout` finds
the files (discovery), :mod:`~stereovar.audit.settings` checks and digests the settings,
:mod:`~stereovar.audit.hashing` hashes and fingerprints the files,
:mod:`~stereovar.audit.decoding` decodes a frame's renders and ground truth, and
:mod:`~stereovar.audit.records` holds what an import finds and records. The names callers use
are importable from here as well (:data:`__all__`).
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from pathlib import Path

from ..errors import AuditError
from ..experiment import audit_source
from ..io.contracts import config_digest
from ..io.formats import image_format
from ..io.headers import integer_bits
from ..io.renders import render_dataset
from ..io.store import atomic_path, remove_stale_temporaries, write_zarr
from ..layout import import_record
from ..rig import VIEWS
from .decoding import (
    check_distinct,
    check_finite,
    check_geometry,
    check_sizes,
    clipped_fraction,
    decode_view,
    floored_fraction,
    frame_fields,
    frame_glass,
    frame_optics,
    half_quantised_fraction,
    half_renders,
    integer_kind,
    seed_mean,
)
from .ground_truth import CONVENTIONS, imported_ground_truth
from .hashing import (
    FINGERPRINT_KEYS,
    RECENT_NS,
    Reads,
    frame_fingerprint,
    read_verified,
    sha256,
    unchanged_frame,
)
from .layout import Frame, discover
from .offset import offset_check
from .records import (
    CLIPPED_WARNING,
    HALF_STEPS,
    OUTSIDE_WARNING,
    QUANTISED_WARNING,
    WARNING_KINDS,
    FrameReport,
    ImportReport,
    killed_imports,
    load_record,
    store_folders,
    write_record,
)
from .settings import (
    IMPORT_KEYS,
    PATH_KEYS,
    RELATIONS,
    audit_spp,
    check_paths,
    check_settings,
    frame_stores,
    import_settings,
    settings_digest,
)
from .sign import HIGH_ERROR, sign_check

__all__ = [
    "CLIPPED_WARNING",
    "FINGERPRINT_KEYS",
    "HALF_STEPS",
    "IMPORT_KEYS",
    "OUTSIDE_WARNING",
    "PATH_KEYS",
    "QUANTISED_WARNING",
    "RECENT_NS",
    "WARNING_KINDS",
    "FrameReport",
    "ImportReport",
    "audit_spp",
    "check_paths",
    "check_settings",
    "frame_fingerprint",
    "frame_stores",
    "import_audit",
    "import_frame",
    "import_record",
    "import_settings",
    "load_record",
    "read_verified",
    "settings_digest",
    "sha256",
]
"""The import's own functions and the names of its parts that callers use from here."""


def _import_frame(settings, frame: Frame, size, pool, report: ImportReport):
    """Import one frame: its ground truth, then its renders, the sign check and the stores.

    Every file is hashed as it is decoded (:func:`read_verified`); the SHA-256 recorded in
    the stores' provenance and returned are of the bytes decoded. Every store is written to
    a temporary path and renamed into place only once every file of the frame decoded and
    the sign check passed, so a failure leaves the frame's old stores as they were.

    Returns
    -------
    FrameReport, dict
        What the import found; each file's :func:`read_verified` record.
    """
    transfer, scale = settings["transfer"], settings["scale"]
    sign = CONVENTIONS[settings["convention"]]
    source = audit_source(settings["name"])
    fr = FrameReport(frame.name, True, n_seeds=frame.n_seeds)
    reads = Reads()
    with report.timed("ground truth"):
        gt, gt_files = _frame_ground_truth(
            settings, frame, size, sign, source, fr, reads, report
        )
    datasets, means, view_files, depths = {}, {}, {}, {}
    for view in VIEWS:
        labels = list(frame.renders[view])
        paths = view_files[view] = [str(p) for p in frame.renders[view].values()]
        with report.timed("decode"):
            render_channel = settings["channels"].get("render")
            images, n_bad, stored = decode_view(
                paths, size, pool, transfer, scale, reads,
                channel=render_channel, view=VIEWS.index(view),
            )
        fr.nonfinite_pixels[view] = int(n_bad.sum())
        check_finite(images, n_bad, frame.name, view, paths)
        check_distinct(images, frame.name, view, paths)
        means[view] = seed_mean(images, n_bad)
        valid = gt["valid"].sel(view=view).values
        bits = [integer_bits(p, channel=render_channel) for p in paths]
        depths[view] = _bit_depth(bits, paths, frame.name, view)
        if 8 in bits:
            fr.floored[view] = floored_fraction(images, valid)
        if any(b is not None for b in bits):
            fr.clipped[view] = clipped_fraction(images, valid, scale)
        elif half_renders(stored, images):
            fr.half[view] = half_quantised_fraction(images, valid, means[view])
        datasets[view] = render_dataset(
            images,
            view=view,
            seeds=list(range(len(paths))),
            sampler_seeds=[int(s) if s.isdigit() else k for k, s in enumerate(labels)],
            n_nonfinite=n_bad,
            attrs={
                "scene": frame.name,
                "renderer": source,
                "renderer_version": "",
                "variant": "imported",
                "spp": audit_spp(settings),
                "seed_policy": "unknown",
                "width": int(size[1]),
                "height": int(size[0]),
                "seed_labels": labels,
                "source_files": paths,
            },
        )
    storage = _storage(depths, view_files, frame.name, transfer, scale)
    with report.timed("hash"):  # ground truth no statistic reads (a right-view mask)
        for path in frame.files():
            if str(path) not in reads.records:
                reads(None, path)
    files = {str(p): reads.records[str(p)]["sha256"] for p in frame.files()}
    digest = config_digest({"files": files, "settings": settings_digest(settings)})
    for view in VIEWS:
        datasets[view].attrs.update(
            scene_digest=digest, source_sha256=[files[p] for p in view_files[view]], **storage
        )
    gt.attrs.update(scene_digest=digest, source_sha256=[files[p] for p in gt_files])
    with report.timed("sign check"):
        _check_sign(settings, frame, gt, means, sign, fr, report)
    with report.timed("offset check"):
        _check_offset(frame, gt, means, sign, fr, report)
    datasets["ground_truth"] = gt
    stores = frame_stores(settings, frame.name, frame.n_seeds)
    with report.timed("write"), ExitStack() as staged:  # renamed into place together
        for key, ds in datasets.items():
            tmp = staged.enter_context(atomic_path(stores[key]))
            write_zarr(ds, tmp, chunk_dims={"seed": 1} if key in VIEWS else None)
    for view, fraction in fr.floored.items():
        if fraction < QUANTISED_WARNING:
            continue
        report.warn(
            "quantisation",
            f"frame {frame.name}, {view}: 8-bit {integer_kind(frame, view)} quantisation "
            "floors the variance to 0 at "
            f"{100 * fraction:.1f}% of the valid pixels (all {frame.n_seeds} renders "
            "identical); export 16-bit PNG or EXR for an audit that can see small variance",
            frame.name,
        )
    for view, fraction in fr.half.items():
        if fraction < QUANTISED_WARNING:
            continue
        report.warn(
            "quantisation",
            f"frame {frame.name}, {view}: the renders hold half-float (16-bit) values, and at "
            f"{100 * fraction:.1f}% of the valid pixels their spread across the "
            f"{frame.n_seeds} renders is below {HALF_STEPS:g} half-float steps, so "
            "quantisation distorts the variance; export 32-bit float EXR (Blender: Color "
            "Depth Float (Full)) for an audit that can see small variance",
            frame.name,
        )
    for view, fraction in fr.clipped.items():
        if fraction > CLIPPED_WARNING:
            report.warn(
                "clipped",
                f"frame {frame.name}, {view}: {100 * fraction:.1f}% of the valid pixels are "
                "at the PNG's full scale in some render, where the variance is cut off; "
                "export EXR (or lower the exposure) so bright pixels keep their noise",
                frame.name,
            )
    return fr, {str(p): reads.records[str(p)] for p in frame.files()}


def _depth_word(depth: int) -> str:
    return f"{depth}-bit integer" if depth else "float"


def _bit_depth(bits: list, paths: list, frame: str, view: str) -> int:
    """The bit depth of one view's renders (:func:`~stereovar.io.headers.integer_bits` of
    each file, ``bits``): 8 or 16 when every file stores integers of that depth, 0 when every
    one stores floats. A view whose files mix depths is refused (one line naming a file of
    each): its variance would mix the quantisations, and the matched null passes every
    frame through one encoding."""
    found = {int(b or 0): p for b, p in zip(bits, paths, strict=True)}
    if len(found) > 1:
        raise AuditError(
            f"frame {frame}, view {view}: its renders are stored at different depths ("
            + ", ".join(f"{_depth_word(d)} {p}" for d, p in sorted(found.items()))
            + "); export every render alike (all 8-bit PNG, all 16-bit PNG or all float "
            "EXR) and import again"
        )
    return next(iter(found))


def _storage(depths: dict, view_files: dict, frame: str, transfer, scale) -> dict:
    """How a frame's renders were stored, for every render store's attrs (and so, as
    :data:`~stereovar.io.contracts.RENDER_PROVENANCE`, every store computed from them):
    ``bit_depth`` (:func:`_bit_depth`; 0: floats), the ``transfer`` that decoded them
    (``audit.transfer``, else ``srgb``, for integers; ``linear`` for floats, which
    :func:`~stereovar.io.images.read_image` reads as they are), ``full_scale`` (``audit.scale``
    for integers; 0 for floats, which it does not scale) and ``file_format`` (the files'
    format, e.g. ``PNG``). The calibration draws its matched null through this encoding
    (:func:`stereovar.jobs.calibration.scene_frames`). A frame whose two views are stored at
    different depths is refused: one encoding passes both views of the null."""
    if depths["left"] != depths["right"]:
        raise AuditError(
            f"frame {frame}: its left renders are {_depth_word(depths['left'])} "
            f"({view_files['left'][0]}) and its right renders {_depth_word(depths['right'])} "
            f"({view_files['right'][0]}); export both views alike and import again"
        )
    depth = depths["left"]
    formats = {image_format(p).upper() for paths in view_files.values() for p in paths}
    return {
        "bit_depth": depth,
        "transfer": (transfer or "srgb") if depth else "linear",
        "full_scale": float(scale) if depth else 0.0,
        "file_format": "/".join(sorted(formats)),
    }


def _frame_ground_truth(
    settings, frame: Frame, size, sign, source, fr: FrameReport, reads: Reads,
    report: ImportReport,
):
    """The frame's ground-truth dataset (its ``scene_digest`` and ``source_sha256`` are set
    once every file is read) and its files; fills the disparity counts of ``fr``."""
    optics = frame_optics(settings, frame, size, reads)
    check_geometry(settings, frame, optics, sign)
    disparity, depth = frame_fields(settings, frame, size, optics, reads)
    glass, glass_source, unmatched = frame_glass(settings, frame, reads)
    if unmatched:
        report.warn("glass_ids", f"frame {frame.name}: {unmatched}", frame.name)
    gt_files = [str(p) for paths in frame.ground_truth.values() for p in paths.values()]
    gt_files = list(dict.fromkeys(gt_files + [str(p) for p in frame.cameras.values()]))
    gt, counts = imported_ground_truth(
        disparity[VIEWS[0]],
        sign=sign,
        disparity_right=disparity.get(VIEWS[1]),
        depth=depth,
        glass=glass,
        material_source=glass_source,
        attrs={
            "scene": frame.name,
            "renderer": source,
            "baseline_m": float(optics.baseline_m or 0.0),
            "focal_px": float(optics.focal_px or 0.0),
            "source_files": gt_files,
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
    total = int(gt.sizes["y"] * gt.sizes["x"])
    if counts["outside"] > OUTSIDE_WARNING * total:
        report.warn(
            "outside",
            f"frame {frame.name}: {counts['outside']} of the {total} left pixels "
            f"({100 * counts['outside'] / total:.1f}%) have a disparity whose match falls "
            f"outside the right image ({gt.sizes['x']} px wide, {RELATIONS[sign]}): the "
            "disparity is too large for these images, as a depth map or a disparity in "
            "another unit or scale is; check audit.disparity (or audit.depth), its channel and "
            "audit.disparity_scale",
            frame.name,
        )
    return gt, gt_files


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
        raise AuditError(
            f"frame {frame.name}: the disparity follows the other convention: the right seed "
            f"mean warped into the left matches with a median error of "
            f"{100 * check.opposite_error:.1f}% under {RELATIONS[-sign]} but "
            f"{100 * check.error:.1f}% under the declared {RELATIONS[sign]}; set "
            f"audit.convention: {other}"
        )
    convention = settings.get("convention") or "conventional"
    errors = (
        f"median error {100 * check.error:.1f}% declared, "
        f"{100 * check.opposite_error:.1f}% opposite"
    )
    if not check.conclusive and settings.get("sign_check", "stop") != "warn":
        raise AuditError(
            f"frame {frame.name}: the sign check is inconclusive: {check.reason} ({errors}), "
            "so the disparity may be wrong (another convention, a wrong file or channel); "
            "check audit.disparity or audit.depth and audit.convention, or set "
            f"audit.sign_check: warn to go on with convention {convention} taken as given"
        )
    if not check.conclusive:
        report.warn(
            "sign_check",
            f"frame {frame.name}: the sign check is inconclusive: {check.reason} ({errors}); "
            f"audit.convention: {convention} is taken as given (audit.sign_check: warn)",
            frame.name,
        )
    if check.conclusive and check.high_error:
        report.warn(
            "sign_check_error",
            f"frame {frame.name}: the declared convention wins the sign check but matches "
            f"poorly ({errors}; above {100 * HIGH_ERROR:.0f}% the right seed mean warped "
            "into the left does not reproduce it): the disparity may not be this frame's (a "
            "depth map, another frame, file or channel, a wrong scale) or the seed means are "
            "very noisy; check audit.disparity or audit.depth and audit.channels",
            frame.name,
        )
    gt.attrs.update(check.attrs())
    fr.sign = {
        "error": check.error,
        "opposite_error": check.opposite_error,
        "conclusive": check.conclusive,
        "high_error": check.high_error,
        "reason": check.reason,
    }


def _check_offset(frame: Frame, gt, means, sign, fr: FrameReport, report) -> None:
    """The photometric offset check (:func:`stereovar.audit.offset.offset_check`) of one
    frame, on the pixels the sign check compares: a warning naming the offset, the errors
    and the fix when the disparity shifted by whole pixels matches clearly better."""
    left_gt = gt.sel(view="left")
    compare = left_gt["valid"].values & ~left_gt["glass"].values & ~left_gt["occluded"].values
    check = offset_check(
        means["left"], means["right"], left_gt["disparity"].values, sign=sign, valid=compare
    )
    if check.fires:
        report.warn(
            "disparity_offset",
            f"frame {frame.name}: {check.finding()}; check the disparity's units, offset and "
            "convention (e.g. a crop or a principal-point shift, audit.disparity_scale): the "
            "cross-view cue measured with this disparity is unreliable",
            frame.name,
        )
    gt.attrs.update(check.attrs())
    fr.offset = check.facts()



def _png_transfer_warning(settings: dict, frames, report: ImportReport) -> None:
    """Warn once when integer renders (PNG, BlenderProc's integer ``colors``) are decoded
    as sRGB because ``audit.transfer`` is not set."""
    if settings["transfer"]:
        return
    renders = list(dict.fromkeys(p for f in frames for v in VIEWS for p in f.renders[v].values()))
    if any(image_format(p) == "png" for p in renders):
        report.warn(
            "transfer",
            "PNG renders without audit.transfer are decoded as sRGB; set audit.transfer: "
            "linear or srgb to say how they were written",
        )
    channel = settings["channels"].get("render")
    hdf5_bits = {
        integer_bits(p, channel=channel) for p in renders if image_format(p) == "hdf5"
    }
    if hdf5_bits - {None}:
        report.warn(
            "transfer",
            f"BlenderProc {'/'.join(f'{b}-bit' for b in sorted(hdf5_bits - {None}))} colors "
            "without audit.transfer are decoded as sRGB, which does not undo Blender's view "
            "transform (Filmic in BlenderProc's defaults) or its clipping at 1; render with "
            "bproc.renderer.set_output_format('OPEN_EXR', 32) for linear float colors, or "
            "set audit.transfer: linear or srgb to say how they were written",
        )


def _import_and_record(
    settings, frame: Frame, size, pool, report: ImportReport, tokens=None
) -> FrameReport:
    """Import one frame (:func:`_import_frame`), then write its :func:`import_record` (with
    each file's :func:`frame_fingerprint` token from ``tokens``)."""
    try:
        fr, records = _import_frame(settings, frame, size, pool, report)
    except MemoryError:
        raise AuditError(
            f"frame {frame.name}: its renders do not fit in memory; import fewer seeds per "
            "frame"
        ) from None
    stores = frame_stores(settings, frame.name, frame.n_seeds)
    for path, token in (tokens or {}).items():
        if path in records and token is not None:
            records[path] = {**records[path], "token": token}
    flags = [f for f in report.flags if f["frame"] in (None, frame.name)]
    write_record(settings, frame.name, records, stores, {**fr.facts(), "warnings": flags})
    return fr


def import_audit(settings: dict, *, workers: int = 2, dry_run: bool = False) -> ImportReport:
    """Import an audit's files into the render and ground-truth store contracts.

    Every frame whose files or import settings changed since its :func:`import_record`
    (judged by SHA-256) is imported; the workflow imports one frame per job instead
    (:func:`import_frame`). For notebooks, benchmarks and tests.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section (see ``workflow/schemas/config.schema.yaml``), as
        written or with the schema's defaults filled in (one import either way).
    workers : int, keyword-only
        Threads that hash and decode files.
    dry_run : bool, keyword-only
        Only find what an import would do (which frames changed: their files are hashed),
        and write nothing.

    Returns
    -------
    ImportReport
        Frames found, imported (or that would be) and unchanged, temporaries of killed
        imports removed, and warnings (8-bit PNG floors, PNG transfer assumed, inconclusive
        sign checks).

    Raises
    ------
    AuditError, ImageError
        One line naming the file and the fix; stores already imported are left as they are.
    """
    check_settings(settings)
    settings = {**settings, **import_settings(settings)}
    found = discover(settings)
    name = settings["name"]
    report = ImportReport(name, found, [], dry_run=dry_run)
    report.temporaries = killed_imports(name, remove=not dry_run)
    digest = settings_digest(settings)
    _png_transfer_warning(settings, found.frames, report)
    sizes = [check_sizes(frame) for frame in found.frames]
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        for frame, size in zip(found.frames, sizes, strict=True):
            prev = load_record(name, frame.name)
            stores = frame_stores(settings, frame.name, frame.n_seeds)
            with report.timed("hash"):
                unchanged = prev.get("settings") == digest and unchanged_frame(
                    frame, prev, stores, pool
                )
            if unchanged:
                report.frames.append(FrameReport(frame.name, False))
            elif dry_run:
                report.frames.append(FrameReport(frame.name, True))
            else:
                report.frames.append(_import_and_record(settings, frame, size, pool, report))
    return report


def import_frame(
    settings: dict, frame: str, *, workers: int = 2, fingerprint: str | None = None
) -> ImportReport:
    """Import one frame of an audit, whatever its last import recorded: the job of the
    workflow's ``audit_import`` rule, which Snakemake runs when the frame's files (their
    time stamps, or :func:`frame_fingerprint`) or the import settings changed.

    The frame's files are found again (:func:`~stereovar.audit.layout.discover`), their
    sizes checked from their headers, then decoded and checked (:func:`_import_frame`:
    truncated files, the sign check, ...) before any store is written; the stores and the
    frame's :func:`import_record` are each written atomically.

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section.
    frame : str
        The frame's name.
    workers : int, keyword-only
        Threads that hash and decode files.
    fingerprint : str, keyword-only, optional
        The frame's :func:`frame_fingerprint` when Snakemake planned the job: each file's
        token is recorded.

    Returns
    -------
    ImportReport
        With the one frame.

    Raises
    ------
    AuditError, ImageError
        One line naming the file and the fix; no store of the frame is written.
    """
    check_settings(settings)
    settings = {**settings, **import_settings(settings)}
    found = discover(settings)
    match = [f for f in found.frames if f.name == frame]
    if not match:
        raise AuditError(
            f"frame {frame}: no file of it matches audit.renders {settings['renders']!r} any "
            "more; run the workflow again (it finds the frames anew)"
        )
    report = ImportReport(settings["name"], found, [])
    names = {Path(p).name for p in frame_stores(settings, frame, match[0].n_seeds).values()}
    folders, _ = store_folders(settings["name"])
    report.temporaries = remove_stale_temporaries(folders, names=names) + (
        remove_stale_temporaries(
            [Path(import_record(settings["name"], frame)).parent],
            names=[Path(import_record(settings["name"], frame)).name],
        )
    )
    _png_transfer_warning(settings, match, report)
    size = check_sizes(match[0])
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        tokens = json.loads(fingerprint)["files"] if fingerprint else None
        report.frames.append(
            _import_and_record(settings, match[0], size, pool, report, tokens)
        )
    return report


