"""Where an audit's files are: path templates with fields, and what they match on disk.

A template names one file per value of its fields, e.g.
``renders/{frame}/{view}/seed_{seed}.exr``. The renders template has ``{view}`` and
``{seed}`` (and ``{frame}`` for more than one frame); the ground-truth templates (disparity,
depth, glass mask, segmentation) have ``{frame}`` and, for one file per view, ``{view}``.
``{view}`` takes the values of ``audit.views`` (``left: L``, ``right: R``). A renders template
without ``{view}`` names files that hold both views: BlenderProc's stereo HDF5 (each dataset
with a leading axis of 2, or ``<key>_0`` and ``<key>_1``), whose headers say so. Frames,
views and seeds are discovered from the files; :func:`discover` checks that they form N >= 2
renders per view of every frame, with ground truth, before any pixel is read. The files a
generator states its cameras in (Kubric's ``metadata.json``, Infinigen's ``camview``) are
found beside the depth files and renders by the generator's naming
(:func:`stereovar.audit.generators.camera_file`) and belong to the frame.
"""

from __future__ import annotations

import glob
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import AuditError
from ..io import hdf5
from ..io.files import reading_header, regular_file
from ..io.formats import image_format
from ..rig import VIEWS
from .generators import camera_file

FIELDS = ("frame", "view", "seed")
"""Template fields."""

NAME = re.compile(r"[A-Za-z0-9_-]+")
"""What an audit or frame name may contain (it becomes a path component and a wildcard)."""

SINGLE_FRAME = "frame"
"""The frame name of a renders template without ``{frame}`` (unless ``audit.frame``)."""

GROUND_TRUTH_KEYS = ("disparity", "depth", "glass_mask", "segmentation")
"""Ground-truth templates of ``audit:``."""


def _template_regex(template: str, views: dict) -> re.Pattern:
    parts = re.split(r"(\{[a-z]+\})", template)
    out = []
    for part in parts:
        m = re.fullmatch(r"\{([a-z]+)\}", part)
        if not m:
            out.append(re.escape(part))
            continue
        name = m.group(1)
        if name not in FIELDS:
            raise AuditError(
                f"audit template {template!r}: unknown field {{{name}}}; use "
                f"{', '.join('{' + f + '}' for f in FIELDS)}"
            )
        if name == "view":
            values = "|".join(re.escape(str(v)) for v in views.values())
            out.append(f"(?P<view>{values})" if "(?P<view>" not in "".join(out) else "(?P=view)")
        elif f"(?P<{name}>" in "".join(out):
            out.append(f"(?P={name})")
        else:
            out.append(f"(?P<{name}>[^/]+?)")
    return re.compile("".join(out))


def template_fields(template: str) -> set:
    """The fields a template uses."""
    return set(re.findall(r"\{([a-z]+)\}", template))


def _glob(template: str) -> str:
    return re.sub(r"\{[a-z]+\}", "*", glob.escape(template))


def _seed_key(label: str):
    return (0, int(label), "") if label.isdigit() else (1, 0, label)


def match_template(template: str, views: dict, root: Path) -> list[tuple[dict, Path]]:
    """Files under ``root`` matching ``template``, with their field values (``view``
    translated back to ``left``/``right``), sorted by path."""
    regex = _template_regex(template, views)
    back = {str(v): k for k, v in views.items()}
    found = []
    for path in sorted(glob.glob(str(root / _glob(template)))):
        rel = Path(path).relative_to(root).as_posix() if not Path(template).is_absolute() else path
        m = regex.fullmatch(rel)
        if m is None:
            continue
        values = m.groupdict()
        if "view" in values:
            values["view"] = back[values["view"]]
        found.append((values, Path(path)))
    return found


@dataclass
class Frame:
    """One stereo frame's files: renders per view (seed label to path, seed order), its
    ground-truth files (view to path; a template without ``{view}`` gives ``left`` only)
    and the files stating its cameras (view to path: Kubric's ``metadata.json``,
    Infinigen's ``camview_*.npz``)."""

    name: str
    renders: dict = field(default_factory=dict)
    ground_truth: dict = field(default_factory=dict)
    cameras: dict = field(default_factory=dict)

    def images(self) -> list[Path]:
        """The frame's renders and ground-truth files, renders first, each once (a file
        holding both views, or renders and depth, is listed once)."""
        out = [p for view in VIEWS for p in self.renders[view].values()]
        for paths in self.ground_truth.values():
            out += list(paths.values())
        return list(dict.fromkeys(out))

    def files(self) -> list[Path]:
        """Every file of the frame, each once: :meth:`images`, then the camera files."""
        return list(dict.fromkeys(self.images() + list(self.cameras.values())))

    @property
    def n_seeds(self) -> int:
        return len(self.renders[VIEWS[0]])


@dataclass
class Discovery:
    """What the templates matched: frames in name order."""

    frames: list

    @property
    def n_seeds(self) -> int:
        return self.frames[0].n_seeds

    def summary(self) -> str:
        """``"3 frames × 2 views × 16 seeds"``."""
        n = len(self.frames)
        return f"{n} frame{'s' * (n != 1)} × {len(VIEWS)} views × {self.n_seeds} seeds"


def _root(settings: dict) -> Path:
    return Path(settings.get("root") or ".")


def discover(settings: dict) -> Discovery:
    """Frames, views and seeds of an audit from its files (no pixel is read).

    Parameters
    ----------
    settings : dict
        The ``audit:`` config section: ``renders`` (template), ``views``, ``disparity`` or
        ``depth``, optional ``glass_mask`` or ``segmentation``, optional ``root``.

    Raises
    ------
    AuditError
        A template field matches nothing, a frame or view has fewer than 2 renders, views or
        frames have different seed counts, or a frame lacks its ground truth.
    ImageError
        A ground-truth path is a named pipe, a device or a directory, not a file.
    """
    root = _root(settings)
    views = dict(settings.get("views") or {v: v for v in VIEWS})
    if len({str(v) for v in views.values()}) < len(VIEWS):
        raise AuditError(
            f"audit.views gives both views the value {str(views[VIEWS[0]])!r}, so no file "
            "can be told to be the left or the right view; give each its own {view} value "
            "(e.g. views: {left: L, right: R})"
        )
    template = settings["renders"]
    fields = template_fields(template)
    missing = [f for f in ("view", "seed") if f not in fields]
    if missing == ["view"] and image_format_or_none(template) == "hdf5":
        missing = []  # files that hold both views: checked below
    if missing:
        raise AuditError(
            f"audit.renders {template!r} has no {{{missing[0]}}} field; name the "
            f"{'view' if missing[0] == 'view' else 'seed'} in the path, e.g. "
            "renders/{frame}/{view}/seed_{seed}.exr"
        )
    matched = match_template(template, views, root)
    if not matched:
        anything = sorted(glob.glob(str(root / _glob(template))))
        hint = (
            f"; files like {anything[0]} exist but their view is none of "
            f"{', '.join(map(str, views.values()))} (audit.views)"
            if anything
            else ""
        )
        raise AuditError(
            f"audit.renders {template!r} matches no file under {root.resolve()}{hint}; "
            "fix the template, audit.views or audit.root"
        )
    frames: dict = {}
    for values, path in matched:
        name = values.get("frame", settings.get("frame") or SINGLE_FRAME)
        if not NAME.fullmatch(name):
            raise AuditError(
                f"{path}: frame name {name!r} may only contain letters, digits, _ and -; "
                "rename the frames or move the punctuation out of {frame}"
            )
        frame = frames.setdefault(name, Frame(name, {v: {} for v in VIEWS}))
        if "view" in values:
            frame.renders[values["view"]][values["seed"]] = path
        else:
            _check_both_views(path, settings)
            for view in VIEWS:
                frame.renders[view][values["seed"]] = path
    for frame in frames.values():
        for view in VIEWS:
            frame.renders[view] = dict(
                sorted(frame.renders[view].items(), key=lambda kv: _seed_key(kv[0]))
            )
        _check_seeds(frame, template, views)
        frame.ground_truth = _ground_truth_files(frame.name, settings, views, root, fields)
        frame.cameras = _camera_files(frame)
    ordered = [frames[k] for k in sorted(frames)]
    counts = {f.name: f.n_seeds for f in ordered}
    if len(set(counts.values())) > 1:
        low = min(counts, key=counts.get)
        raise AuditError(
            f"frame {low} has {counts[low]} renders per view, frame "
            f"{max(counts, key=counts.get)} {max(counts.values())}; every frame needs the "
            "same N: add the missing renders or leave the extra seeds out of the template"
        )
    return Discovery(ordered)


def image_format_or_none(path) -> str | None:
    """:func:`~stereovar.io.formats.image_format` of a path, or None for an unknown one."""
    try:
        return image_format(path)
    except Exception:
        return None


def _check_both_views(path: Path, settings: dict) -> None:
    """Refuse a file of a renders template without ``{view}`` unless its header says it
    holds both views (BlenderProc's stereo HDF5)."""
    regular_file(path)
    channel = (settings.get("channels") or {}).get("render")
    with reading_header(path):  # a truncated file: one line, as for any header
        views = hdf5.render_views(path, channel)
    if views != 2:
        raise AuditError(
            f"{path}: its render holds one view, and audit.renders {settings['renders']!r} "
            "has no {view} field; name the view in the path (e.g. "
            "bp/seed_{seed}/{view}.hdf5 with views {left: 0, right: 1}), or give files that "
            "hold both views (BlenderProc with bproc.renderer.toggle_stereo(True))"
        )


def _camera_files(frame: Frame) -> dict:
    """View to the file stating its camera (:func:`~stereovar.audit.generators.camera_file`),
    from the view's depth file, else from its first render; views with none are left out."""
    depth = frame.ground_truth.get("depth", {})
    out = {}
    for view in VIEWS:
        candidates = [depth[view]] if view in depth else []
        candidates += list(frame.renders[view].values())[:1]
        for path in candidates:
            found = camera_file(path)
            if found is not None:
                out[view] = found
                break
    return out


def _check_seeds(frame: Frame, template: str, views: dict) -> None:
    for view in VIEWS:
        seeds = frame.renders[view]
        if len(seeds) == 1:
            from ..estimators.single import refusal

            raise AuditError(
                f"frame {frame.name}, view {view} ({views[view]}): 1 render "
                f"({next(iter(seeds.values()))}) match {template!r}; {refusal()}"
            )
        if len(seeds) < 2:
            have = f" ({next(iter(seeds.values()))})" if seeds else ""
            raise AuditError(
                f"frame {frame.name}, view {view} ({views[view]}): {len(seeds)} render"
                f"{'s' * (len(seeds) != 1)}{have} match {template!r}; an audit needs N >= 2 "
                "independent renders (different seeds) per view: render more seeds"
            )
    left, right = (set(frame.renders[v]) for v in VIEWS)
    if left != right:
        only = sorted(left ^ right, key=_seed_key)
        side = "left" if only[0] in left else "right"
        other = "right" if side == "left" else "left"
        raise AuditError(
            f"frame {frame.name}: seed {only[0]} has a {side} render "
            f"({frame.renders[side][only[0]]}) but no {other} one; every seed needs both "
            "views: add the missing render or remove this one"
        )


def _ground_truth_files(frame, settings, views, root, render_fields) -> dict:
    out = {}
    for key in GROUND_TRUTH_KEYS:
        template = settings.get(key)
        if not template:
            continue
        fields = template_fields(template)
        if "seed" in fields:
            raise AuditError(
                f"audit.{key} {template!r} has a {{seed}} field; ground truth is one file per "
                "frame (and view): remove {seed}"
            )
        if "frame" not in fields and "frame" in render_fields:
            raise AuditError(
                f"audit.{key} {template!r} has no {{frame}} field but audit.renders has; add "
                "{frame} so each frame finds its own file"
            )
        paths = {}
        for view in VIEWS if "view" in fields else VIEWS[:1]:
            rel = template.replace("{frame}", frame).replace("{view}", str(views[view]))
            path = Path(rel) if Path(rel).is_absolute() else root / rel
            if path.exists():
                regular_file(path)  # a named pipe or a device is named as such
                paths[view] = path
            elif view == VIEWS[0]:  # the right view's ground truth is optional
                raise AuditError(
                    f"frame {frame}: no {key.replace('_', ' ')} file {path} (audit.{key} "
                    f"{template!r}); add it or fix the template"
                )
        out[key] = paths
    if "disparity" not in out and "depth" not in out:
        raise AuditError(
            "audit: no ground truth; set audit.disparity (a template), or audit.depth with "
            "audit.focal_px and audit.baseline_m"
        )
    return out
