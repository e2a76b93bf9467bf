"""Image and field files written in the format of a path's extension.

OpenEXR, PFM, PNG (16 bit), NPY and NPZ; the export (:mod:`stereovar.audit.export`) writes ours
through :func:`write_image` and :func:`write_field`.
"""

from __future__ import annotations

import numpy as np

from .formats import image_format
from .pfm import write_pfm
from .transfer import linear_to_srgb


def write_image(
    path, image, *, transfer: str = "linear", scale: float = 1.0, half: bool = False
) -> None:
    """Write one ``(H, W, 3)`` linear RGB image in the format of ``path``'s extension.

    EXR is float (``half``: 16-bit float) with ZIP compression; PNG is 16 bit, ``image /
    scale`` encoded with ``transfer`` and clipped to [0, 1]; PFM, NPY and NPZ are float32.
    """
    fmt = image_format(path)
    a = np.asarray(image, dtype=np.float32)
    if a.ndim != 3 or a.shape[-1] != 3:
        raise ValueError(f"an image is (H, W, 3), got {a.shape}")
    if fmt == "exr":
        _write_exr(path, {c: a[..., k] for k, c in enumerate("RGB")}, half=half)
    elif fmt == "png":
        import cv2

        v = np.clip(a.astype(np.float64) / scale, 0.0, 1.0)
        if transfer == "srgb":
            v = linear_to_srgb(v)
        q = np.round(v * 65535.0).astype(np.uint16)
        if not cv2.imwrite(str(path), np.ascontiguousarray(q[..., ::-1])):
            raise OSError(f"{path}: OpenCV could not write it")
    else:
        _write_plain(path, a, fmt)


def write_field(path, field, *, png_scale: float = 256.0) -> None:
    """Write one ``(H, W)`` field: EXR (one float channel ``Z``), PFM (``Pf``), NPY, NPZ, or
    PNG as uint16 ``round(field * png_scale)`` (the KITTI disparity encoding, 0 = invalid)."""
    fmt = image_format(path)
    a = np.asarray(field, dtype=np.float32)
    if a.ndim != 2:
        raise ValueError(f"a field is (H, W), got {a.shape}")
    if fmt == "exr":
        _write_exr(path, {"Z": a})
    elif fmt == "png":
        import cv2

        with np.errstate(invalid="ignore"):
            q = np.where(np.isfinite(a) & (a > 0), np.round(a * png_scale), 0)
        if not cv2.imwrite(str(path), np.clip(q, 0, 65535).astype(np.uint16)):
            raise OSError(f"{path}: OpenCV could not write it")
    else:
        _write_plain(path, a, fmt)


def _write_exr(path, channels: dict, *, half: bool = False) -> None:
    import OpenEXR

    dtype = np.float16 if half else np.float32
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    pixels = {k: np.ascontiguousarray(v, dtype=dtype) for k, v in channels.items()}
    with OpenEXR.File(header, pixels) as f:
        f.write(str(path))


def _write_plain(path, a, fmt) -> None:
    if fmt == "pfm":
        write_pfm(path, a)
    elif fmt == "npy":
        with open(path, "wb") as f:
            np.save(f, a)
    else:
        with open(path, "wb") as f:
            np.savez_compressed(f, a)
