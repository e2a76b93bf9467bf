"""What a generator writes: Blender's view transform and an integer PNG, read back as an
audit reads it.

Kubric and BlenderProc ship 8-bit PNG through Blender's view transform (Filmic), Infinigen an
8-bit PNG through Blender 4.2's default view transform (AgX) beside its EXR
(:data:`stereovar.generators.OUTPUTS` cites each). The statistics then see the code values,
not the renderer's float radiance: a smooth tone curve, rounding to :math:`2^B - 1` levels and
clipping at full scale.

The view transform is Blender's own (its OpenColorIO configuration, through ``bpy``: an image
saved with the scene's colour management, ``Image.save_render``), so a curve is never
re-derived here. The PNG is read back as :func:`stereovar.io.images.read_image` reads one
whose transfer is sRGB (the PNG default): the code value over full scale, decoded by the sRGB
curve,

.. math::

    I' = \\mathrm{sRGB}^{-1}\\Bigl(\\frac{\\operatorname{round}\\bigl((2^B - 1)\\,
        V(I)\\bigr)}{2^B - 1}\\Bigr)

with :math:`V` the view transform to display values in [0, 1]. An audit of the generator's
PNGs states the same encoding (``bit_depth``, ``transfer: srgb``, full scale 1), and the
intensity control's quantisation term (:mod:`stereovar.controls.quantisation`) reads it from
:func:`output_encoding`.

``bpy`` is imported on first use.
"""

from __future__ import annotations

import tempfile
from functools import cache, lru_cache
from pathlib import Path

import numpy as np

from .base import TransformInputs

VIEW_TRANSFORMS = ("Filmic", "AgX", "Standard")
"""Blender view transforms a generator writes its PNG through (``Standard`` is the sRGB
curve alone)."""

BIT_DEPTHS = (8, 16)
"""PNG bit depths Blender writes."""


def output_encoding(bits: int) -> dict:
    """The integer encoding an audit reads the PNG with
    (:func:`~stereovar.calibration.pipelines.integer_roundtrip`'s ``bits``, ``transfer`` and
    ``scale``).

    Examples
    --------
    >>> output_encoding(8)
    {'bits': 8, 'transfer': 'srgb', 'scale': 1.0}
    """
    if int(bits) not in BIT_DEPTHS:
        raise ValueError(f"a PNG has bit depth 8 or 16, got {bits}")
    return {"bits": int(bits), "transfer": "srgb", "scale": 1.0}


@cache
def _blender_image(height: int, width: int):
    """One float image of this size in Blender's data, reused for every frame."""
    import bpy

    return bpy.data.images.new(
        f"stereovar_output_{height}x{width}", width, height, alpha=True, float_buffer=True
    )


@lru_cache(maxsize=1)
def _scene():
    """A scene of its own whose colour management and image settings write the PNG, so that
    what other code set on Blender's current scene (a multilayer EXR output, say) changes
    nothing here."""
    import bpy

    return bpy.data.scenes.new("stereovar_output")


@lru_cache(maxsize=1)
def _folder() -> tempfile.TemporaryDirectory:
    """Where Blender writes each PNG before it is read back; removed when the process ends."""
    return tempfile.TemporaryDirectory(prefix="stereovar-png-")


def view_png_codes(image, *, view_transform: str, bits: int = 8) -> np.ndarray:
    """The code values of ``image`` written by Blender as a PNG of ``bits`` bits through
    ``view_transform`` (exposure 0, gamma 1, no look: Blender's defaults).

    Parameters
    ----------
    image : numpy.ndarray (H, W, 3)
        Linear scene radiance, top row first.
    view_transform : str
        One of :data:`VIEW_TRANSFORMS`.
    bits : int
        8 or 16.

    Returns
    -------
    numpy.ndarray (H, W, 3), uint8 or uint16
        The PNG's RGB codes, top row first.
    """
    import cv2

    if view_transform not in VIEW_TRANSFORMS:
        raise ValueError(
            f"view transform {view_transform!r} is not one of {', '.join(VIEW_TRANSFORMS)}"
        )
    output_encoding(bits)
    image = np.asarray(image, dtype=np.float32)
    h, w = image.shape[:2]
    scene = _scene()
    view = scene.view_settings
    view.view_transform = view_transform
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    scene.display_settings.display_device = "sRGB"
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # Blender 5: a still image, not a multilayer one
        settings.media_type = "IMAGE"
    settings.file_format = "PNG"
    settings.color_mode = "RGB"
    settings.color_depth = str(int(bits))
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = np.nan_to_num(image, nan=0.0, posinf=0.0, neginf=0.0)
    target = _blender_image(h, w)
    target.pixels.foreach_set(rgba[::-1].ravel())  # Blender's rows run bottom-up
    path = Path(_folder().name) / "frame.png"
    target.save_render(str(path), scene=scene)
    codes = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if codes is None or codes.shape[:2] != (h, w):
        raise RuntimeError(f"Blender wrote no readable {bits}-bit PNG at {path}")
    return np.ascontiguousarray(codes[..., 2::-1])  # OpenCV reads BGR


def apply_view_png(inputs: TransformInputs, *, view_transform: str, bits: int = 8) -> np.ndarray:
    """One render as the generator ships it, read back as an audit reads the PNG (the
    module's equation).

    Non-finite render values are NaN in the output, as every transform leaves them.
    """
    from ..io.transfer import srgb_to_linear

    render = np.asarray(inputs.render, dtype=np.float32)
    codes = view_png_codes(render, view_transform=view_transform, bits=bits)
    full = float(2 ** int(bits) - 1)
    out = srgb_to_linear(codes.astype(np.float64) / full).astype(np.float32)
    out[~np.isfinite(render)] = np.nan
    return out
