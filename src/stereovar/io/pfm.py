"""PFM files, read and written by hand.

A PFM is a plain header (``PF`` colour or ``Pf`` grey, width, height, scale) and raw float32
rows stored bottom to top, little-endian when the scale is negative.
"""

from __future__ import annotations

import numpy as np


def _pfm_header(f):
    tokens = []
    while len(tokens) < 4:
        line = f.readline()
        if not line:
            raise ValueError("header ends early")
        tokens += line.split()
    kind, width, height, scale = tokens[0], int(tokens[1]), int(tokens[2]), float(tokens[3])
    if kind not in (b"PF", b"Pf"):
        raise ValueError(f"magic {kind!r} is neither PF nor Pf")
    return kind == b"PF", width, height, scale, f.tell()


def read_pfm(path) -> np.ndarray:
    """A PFM file as float32, top row first: ``(H, W)`` (``Pf``) or ``(H, W, 3)`` (``PF``).

    PFM stores rows bottom to top; a negative scale means little-endian floats.
    """
    with open(path, "rb") as f:
        color, width, height, scale, _ = _pfm_header(f)
        data = f.read()
    dtype = np.dtype("<f4" if scale < 0 else ">f4")
    shape = (height, width, 3) if color else (height, width)
    count = int(np.prod(shape))
    if len(data) < count * 4:
        raise ValueError(f"{len(data)} bytes of pixel data, {count * 4} expected")
    a = np.frombuffer(data, dtype=dtype, count=count).reshape(shape)
    return np.ascontiguousarray(a[::-1]).astype(np.float32)


def write_pfm(path, array) -> None:
    """Write ``(H, W)`` or ``(H, W, 3)`` values as little-endian PFM (rows bottom to top)."""
    a = np.asarray(array, dtype="<f4")
    if a.ndim == 3 and a.shape[-1] == 3:
        kind = b"PF"
    elif a.ndim == 2:
        kind = b"Pf"
    else:
        raise ValueError(f"PFM holds (H, W) or (H, W, 3) arrays, got {a.shape}")
    with open(path, "wb") as f:
        f.write(kind + b"\n%d %d\n-1.0\n" % (a.shape[1], a.shape[0]))
        f.write(np.ascontiguousarray(a[::-1]).tobytes())
