"""Which channels of an OpenEXR file hold a render, depth, disparity, a segmentation or a
glass mask: picked by what their names mean, never by position.

Renderers name an EXR's channels ``<layer>.<channel>``; Blender's multilayer files add the
view layer, ``<ViewLayer>.<Pass>.<Channel>``, and Blender 5 writes each pass as its own part
of a multi-part file (``ViewLayer.Combined`` with ``ViewLayer.Combined.R/G/B/A``,
``ViewLayer.Depth`` with ``ViewLayer.Depth.Z``, ``ViewLayer.Object Index`` with
``ViewLayer.Object Index.X``; older Blender: ``IndexOB``). A channel's *pass* is the
component before its last one (``Depth`` of ``ViewLayer.Depth.Z``; ``Depth`` of Kubric's
``Depth.V``); a name without a dot is its own pass (plain ``Z``, Kubric's ``depth``). The pass
says what the channel holds, so ``ViewLayer.Mist.Z`` and ``ViewLayer.Normal.Z`` are not depth
although they end in ``Z``.

Recognised passes (case, spaces, ``_`` and ``-`` ignored):

========================  ===============================================================
role                      passes
========================  ===============================================================
``render``                ``R, G, B`` of the layer ``Combined`` (Blender), ``Image``
                          (Blender's compositor, Kubric's EXR), ``rgba`` (Kubric),
                          ``colors``/``rgb`` (BlenderProc), or plain ``R, G, B``
``depth``                 ``Depth`` (Blender, Kubric), ``depth`` (BlenderProc), plain ``Z``
``disparity``             ``disparity``
``segmentation``          ``IndexOB``/``Object Index`` (Blender), ``segmentation`` (Kubric),
                          ``*_segmaps`` (BlenderProc: ``instance_segmaps``,
                          ``class_segmaps``, ``category_id_segmaps``)
``glass_mask``            ``glass_mask``, ``glass``
========================  ===============================================================

BlenderProc's ``distance`` is the distance along the camera ray, not planar depth, and is
refused for depth. A file with one channel is that field unless its name says it holds
something else (:func:`named_as`): a one-channel ``ViewLayer.Depth.Z`` given as disparity,
a ``disparity`` given as depth, a normal, albedo or mist pass given as any field, or a
field given as a render is refused; a plain ``Z``, ``V`` or ``Y`` (our own field files,
Blender's BW output) says nothing and is read. Anything else is one
:class:`~stereovar.errors.ImageError` line naming the file, the role, the channels it has
and the fix: ``audit.channels`` names the channel (for ``render``, the layer whose
``R, G, B`` are read), and a channel it names is read as that role whatever its name.

The functions here work on channel names only; :mod:`stereovar.io.images` reads the pixels.
"""

from __future__ import annotations

import re

from ..errors import ImageError

ROLES = ("render", "depth", "segmentation", "disparity", "glass_mask")
"""What a file read by the audit holds; the keys of ``audit.channels``."""

FIELD_ROLES = ROLES[1:]
"""The roles of one scalar channel (all but ``render``)."""

RENDER_LAYERS = frozenset({"", "combined", "image", "rgba", "rgb", "colors", "color"})
"""Layer names (normalised, :func:`normalised`) of a render's ``R, G, B``; ``""``: plain."""

PASSES = {
    "depth": frozenset({"depth"}),
    "disparity": frozenset({"disparity"}),
    "segmentation": frozenset({"indexob", "objectindex", "segmentation", "segmap"}),
    "glass_mask": frozenset({"glassmask", "glass"}),
    "distance": frozenset({"distance"}),
}
"""Pass names (normalised) of each field role, and of ray distance (refused for depth)."""

PLAIN = {"z": "depth"}
"""Undotted channel names whose meaning is not their pass name: OpenEXR's ``Z`` is depth."""

RENDER_PASSES = frozenset({"combined", "rgba", "colors", "noisyimage"})
"""Pass names (normalised) that mean a render, and no field, by themselves (``Image``, the
default input name of Blender's File Output node, may hold any field)."""

OTHER_PASSES = {
    "surface normals": frozenset({"normal", "normals", "denoisingnormal"}),
    "albedo": frozenset(
        {"albedo", "denoisingalbedo", "diffcol", "diffusecolor", "glosscol", "glossycolor",
         "transcol", "transmissioncolor"}
    ),
    "mist (a 0-1 distance ramp)": frozenset({"mist"}),
    "motion vectors": frozenset({"vector", "flow", "forwardflow", "backwardflow"}),
    "UV coordinates": frozenset({"uv"}),
    "positions": frozenset({"position", "objectcoordinates"}),
    "a material index": frozenset({"indexma", "materialindex"}),
    "a light pass": frozenset(
        {"emit", "emission", "env", "environment", "ao", "shadow", "diffdir", "diffind",
         "glossdir", "glossind", "transdir", "transind", "volumedir", "volumeind",
         "diffusedirect", "diffuseindirect", "glossydirect", "glossyindirect",
         "transmissiondirect", "transmissionindirect", "volumedirect", "volumeindirect"}
    ),
}
"""Passes (normalised names) that hold none of :data:`ROLES`, by what they hold (Blender's
and Kubric's names)."""

WORDS = {
    "render": "a render",
    "depth": "depth",
    "disparity": "disparity",
    "segmentation": "a segmentation",
    "glass_mask": "a glass mask",
    "distance": "ray distance",
}
"""What a role (and ray distance) holds, in words, for error lines."""

SEGMAPS_SUFFIX = "segmaps"
"""BlenderProc names its segmentation maps ``<attribute>_segmaps``."""

LISTED = 24
"""At most this many channel names are listed in an error line."""


def normalised(word: str) -> str:
    """``word`` lower-cased without spaces, ``_`` and ``-`` (``Object Index`` ->
    ``objectindex``).

    Examples
    --------
    >>> normalised("Object Index"), normalised("instance_segmaps")
    ('objectindex', 'instancesegmaps')
    """
    return re.sub(r"[\s_\-]+", "", word).lower()


def pass_name(channel: str) -> str:
    """The pass a channel belongs to: the component before its last one, or the whole name
    when it has no dot.

    Examples
    --------
    >>> pass_name("ViewLayer.Depth.Z"), pass_name("Depth.V"), pass_name("depth")
    ('Depth', 'Depth', 'depth')
    >>> pass_name("ViewLayer.001.Object Index.X")
    'Object Index'
    """
    parts = channel.split(".")
    return parts[-2] if len(parts) > 1 else parts[0]


def meaning(channel: str) -> str | None:
    """The field a channel holds by its name: one of :data:`FIELD_ROLES`, ``"distance"``
    (ray distance), or None (not a field, or unknown).

    Examples
    --------
    >>> [meaning(c) for c in ("ViewLayer.Depth.Z", "Z", "ViewLayer.Mist.Z", "Normal.Z")]
    ['depth', 'depth', None, None]
    >>> meaning("ViewLayer.Object Index.X"), meaning("instance_segmaps"), meaning("distance")
    ('segmentation', 'segmentation', 'distance')
    """
    key = normalised(pass_name(channel))
    if "." not in channel and key in PLAIN:
        return PLAIN[key]
    for role, names in PASSES.items():
        if key in names:
            return role
    if key.endswith(SEGMAPS_SUFFIX):
        return "segmentation"
    return None


def named_as(channel: str) -> str | None:
    """What the name of a channel says it holds, whatever it is read as: a
    :data:`FIELD_ROLES` role, ``"distance"``, ``"render"`` or a key of
    :data:`OTHER_PASSES`; None when the name says nothing (a plain ``Z``, ``V`` or ``Y``,
    the one channel of a field file, or an unknown pass).

    Parameters
    ----------
    channel : str
        A channel's full name (``ViewLayer.Depth.Z``).

    Returns
    -------
    str or None
        What the name says the channel holds, or None.

    Examples
    --------
    >>> [named_as(c) for c in ("ViewLayer.Depth.Z", "Z", "V", "ViewLayer.Normal.X")]
    ['depth', None, None, 'surface normals']
    >>> named_as("ViewLayer.Combined.R"), named_as("Image.V"), named_as("disparity")
    ('render', None, 'disparity')
    """
    if "." not in channel and normalised(channel) in PLAIN:
        return None
    what = meaning(channel)
    if what is not None:
        return what
    key = normalised(pass_name(channel))
    if key in RENDER_PASSES:
        return "render"
    return next((word for word, names in OTHER_PASSES.items() if key in names), None)


def _what(what: str) -> str:
    return WORDS.get(what, what)


def foreign_channel(channel: str, role: str, path) -> None:
    """Refuse the one channel of a file read as ``role`` when its name says it holds
    something else (:func:`named_as`), e.g. a one-channel ``ViewLayer.Depth.Z`` file given
    as disparity.

    Parameters
    ----------
    channel : str
        The file's only channel.
    role : {"render", "depth", "segmentation", "disparity", "glass_mask"}
        What the file was given as.
    path : path-like
        The file, for the error line.

    Raises
    ------
    ImageError
        One line naming the channel, what its name says and the fix.

    Examples
    --------
    >>> foreign_channel("Z", "disparity", "d.exr")  # plain Z says nothing: read
    >>> foreign_channel("ViewLayer.Depth.Z", "disparity", "d.exr")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    stereovar.errors.ImageError: d.exr: its one channel 'ViewLayer.Depth.Z' holds depth ...
    """
    check_role(role)
    what = named_as(channel)
    if what is None or what == role:
        return
    if role == "disparity" and what == "depth":
        fix = (
            "give it as audit.depth (with audit.focal_px and audit.baseline_m: d = f B / z) "
            "and leave audit.disparity out, or give the disparity in px"
        )
    elif role == "render":
        fix = "give the renders' files in audit.renders"
    else:
        fix = (
            f"give a file that holds {_what(role)}, or set audit.channels: "
            f"{{{role}: {channel}}} if it does hold {_what(role)}"
        )
    raise ImageError(
        f"{path}: its one channel {channel!r} holds {_what(what)} by its name, not "
        f"{_what(role)}; {fix}"
    )


def listing(names) -> str:
    """The channel names, sorted and comma-separated, at most :data:`LISTED` of them."""
    names = sorted(names)
    shown = ", ".join(names[:LISTED])
    return shown + (f" and {len(names) - LISTED} more" if len(names) > LISTED else "")


def check_role(role: str) -> None:
    """Refuse a role that is not one of :data:`ROLES` (one line)."""
    if role not in ROLES:
        raise ValueError(f"unknown channel role {role!r}; use one of {', '.join(ROLES)}")


def _fix(role: str) -> str:
    if role not in ROLES:
        return "write the field as one channel"
    return f"set audit.channels: {{{role}: <one of them>}}"


def _holds(channel: str, role: str | None) -> bool:
    """Whether the name of ``channel`` says it holds ``role`` (None: any field but ray
    distance)."""
    what = meaning(channel)
    return what == role if role is not None else what in FIELD_ROLES


def _distance_error(path, channel: str) -> ImageError:
    return ImageError(
        f"{path}: channel {channel!r} is ray distance (BlenderProc's distance output), not "
        "planar depth, and d = f B / z needs planar depth; export depth "
        "(bproc.renderer.enable_depth_output) or give audit.disparity"
    )


def _missing_error(path, role: str, channel: str, names) -> ImageError:
    return ImageError(
        f"{path}: audit.channels.{role} is {channel!r} but the file has no such channel (it "
        f"has {listing(names)}); set audit.channels.{role} to one of them"
    )


def field_channel(names, role: str | None, path, channel: str | None = None) -> str:
    """The one channel of an EXR that holds the field ``role``.

    Parameters
    ----------
    names : iterable of str
        The file's channel names (across all its parts).
    role : {"depth", "segmentation", "disparity", "glass_mask"} or None
        What the channel holds; None: any field (one channel, or the one channel whose name
        means a field).
    path : path-like
        The file, for the error line.
    channel : str, optional
        ``audit.channels``' name for it: taken as given when the file has it.

    Returns
    -------
    str
        The channel's name.

    Raises
    ------
    ImageError
        The named channel is missing; ray distance as depth; the file's one channel is named
        as something else (:func:`foreign_channel`); several channels hold the role; or none
        does and the file has more than one channel (one line listing the channels and
        naming the fix).

    Examples
    --------
    >>> blender = ["ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Depth.Z"]
    >>> field_channel(blender, "depth", "a.exr")
    'ViewLayer.Depth.Z'
    >>> field_channel(["V"], "disparity", "b.exr")
    'V'
    """
    names = list(names)
    if role is not None and role not in FIELD_ROLES:
        raise ValueError(f"unknown field role {role!r}; use one of {', '.join(FIELD_ROLES)}")
    label = role or "field"
    if channel is not None:
        if channel not in names:
            raise _missing_error(path, label, channel, names)
        picked = [channel]
    elif len(names) == 1:
        picked = names
    else:
        picked = [n for n in names if _holds(n, role)]
    if role == "depth" and len(picked) == 1 and meaning(picked[0]) == "distance":
        raise _distance_error(path, picked[0])
    if channel is None and len(names) == 1 and role is not None:
        foreign_channel(names[0], role, path)
    if len(picked) == 1:
        return picked[0]
    if picked:
        raise ImageError(f"{path}: several {label} channels ({listing(picked)}); {_fix(label)}")
    distance = [n for n in names if meaning(n) == "distance"]
    if role == "depth" and distance:
        raise _distance_error(path, distance[0])
    raise ImageError(
        f"{path}: no {label} channel among its {len(names)} channels ({listing(names)}); "
        f"{_fix(label)}"
    )


def rgb_layers(names) -> dict:
    """Layers with an ``R``, a ``G`` and a ``B`` channel: layer name (``""``: the plain
    ``R, G, B``) to the three channel names.

    Examples
    --------
    >>> rgb_layers(["Image.R", "Image.G", "Image.B", "Image.A", "Depth.V", "R", "G"])
    {'Image': ('Image.R', 'Image.G', 'Image.B')}
    """
    names = set(names)
    layers = {}
    for name in sorted(names):
        layer, _, last = name.rpartition(".")
        triple = tuple(f"{layer}.{c}" if layer else c for c in "RGB")
        if last == "R" and all(c in names for c in triple):
            layers[layer] = triple
    return layers


def _layer_channels(layer: str, names) -> tuple:
    """The ``R, G, B`` of ``layer`` (the plain ones for ``""``), or the one channel named
    ``layer``, or ``()``."""
    layer = layer.rstrip(".")
    triple = rgb_layers(names).get(layer)
    if triple:
        return triple
    return (layer,) if layer in set(names) else ()


def render_channels(names, path, channel: str | None = None) -> tuple:
    """The channels of an EXR holding the render: its ``R, G, B`` names, or one grey
    channel's name.

    Parameters
    ----------
    names : iterable of str
        The file's channel names (across all its parts).
    path : path-like
        The file, for the error line.
    channel : str, optional
        ``audit.channels.render``: the layer whose ``R, G, B`` are read (``ViewLayer.Combined``),
        or one grey channel.

    Returns
    -------
    tuple of str
        Three names (R, G, B) or one (grey).

    Raises
    ------
    ImageError
        The named layer is missing; several RGB layers and not exactly one render layer
        among them; no RGB layer and more than one channel; or one channel whose name says
        it holds a field (:func:`foreign_channel`) (one line).

    Examples
    --------
    >>> names = [f"ViewLayer.{p}.{c}" for p in ("Combined", "Noisy Image") for c in "RGBA"]
    >>> render_channels(names + ["ViewLayer.Depth.Z"], "a.exr")
    ('ViewLayer.Combined.R', 'ViewLayer.Combined.G', 'ViewLayer.Combined.B')
    >>> render_channels(["R", "G", "B", "A"], "b.exr")
    ('R', 'G', 'B')
    """
    names = list(names)
    if channel is not None:
        picked = _layer_channels(channel, names)
        if not picked:
            raise _missing_error(path, "render", channel, names)
        return picked
    layers = rgb_layers(names)
    if len(layers) > 1:
        renders = [k for k in layers if normalised(k.rpartition(".")[2]) in RENDER_LAYERS]
        if len(renders) != 1:
            raise ImageError(
                f"{path}: several RGB layers ({listing(layers)}) and "
                f"{'none' if not renders else 'more than one'} is the render (Combined); "
                f"{_fix('render')}"
            )
        return layers[renders[0]]
    if layers:
        return next(iter(layers.values()))
    if len(names) == 1:
        foreign_channel(names[0], "render", path)
        return tuple(names)
    raise ImageError(
        f"{path}: no R, G, B channels (has {listing(names)}); write an RGB image, or "
        f"{_fix('render')}"
    )


def unique_channels(parts, path) -> None:
    """Refuse a multi-part file in which one channel name is in several parts: a multi-view
    file (Blender's stereo ``Views Format: Multi-View``) holds each view's passes under the
    same names.

    Parameters
    ----------
    parts : iterable of (str or None, iterable of str)
        Each part's view (its ``view`` attribute, or None) and channel names.
    path : path-like
        The file, for the error line.

    Raises
    ------
    ImageError
        A channel name in more than one part (one line naming the views and the fix).
    """
    seen: dict = {}
    for view, names in parts:
        for name in names:
            seen.setdefault(name, []).append(view)
    repeated = {name: views for name, views in seen.items() if len(views) > 1}
    if not repeated:
        return
    name, views = min(repeated.items())
    which = ", ".join(str(v) for v in views if v) or "several parts"
    raise ImageError(
        f"{path}: channel {name!r} is in {len(views)} parts ({which}): a multi-view file; "
        "export one file per view (Blender: Output Properties > Views > Views Format: "
        "Individual)"
    )
