"""The pixel type of each channel of an OpenEXR file, from its header alone.

The ASWF ``OpenEXR`` bindings give a channel's type only with its pixels (a header-only read
leaves it out), so the header is read here, by the file layout of the OpenEXR specification
("OpenEXR File Layout"): the magic number ``76 2f 31 01``, a four-byte version field (bit 12
set: a multi-part file), then each part's header as attributes (a null-terminated name, a
null-terminated type name, a little-endian ``int32`` size and the value), each header ended by
a null byte and a multi-part file's list of headers by one more. The ``channels`` attribute
(type ``chlist``) holds, for each channel, its null-terminated name, its pixel type (``int32``:
0 ``UINT``, 1 ``HALF``, 2 ``FLOAT``), one ``pLinear`` byte, three reserved bytes and the x and
y sampling (``int32`` each), and ends with a null byte.
"""

from __future__ import annotations

import struct

MAGIC = b"\x76\x2f\x31\x01"
"""The first four bytes of every OpenEXR file (20000630, little-endian)."""

MULTIPART = 0x1000
"""The version field's bit of a multi-part file."""

PIXEL_TYPES = {0: "uint", 1: "half", 2: "float"}
"""A ``chlist`` pixel type to its name."""

_NAME_MAX = 256
"""Attribute names and type names hold at most 255 bytes (the long-names flag's limit)."""


def channel_types(f) -> dict[str, str]:
    """Each channel's pixel type, across all parts of an OpenEXR file.

    Parameters
    ----------
    f : binary file object
        Positioned at the start of the file; it is read up to the end of the headers, and
        attribute values other than ``channels`` are skipped (``f.seek``).

    Returns
    -------
    dict
        Channel name to ``"uint"``, ``"half"`` or ``"float"`` (``"unknown"`` for a type the
        specification does not define).

    Raises
    ------
    ValueError
        No OpenEXR magic number, or a header that ends early or is malformed.

    Examples
    --------
    >>> import io, struct
    >>> chlist = b"R\\0" + struct.pack("<iB3xii", 1, 0, 1, 1) + b"\\0"
    >>> header = b"channels\\0chlist\\0" + struct.pack("<i", len(chlist)) + chlist + b"\\0"
    >>> channel_types(io.BytesIO(MAGIC + struct.pack("<i", 2) + header))
    {'R': 'half'}
    """
    head = f.read(8)
    if len(head) < 8 or head[:4] != MAGIC:
        raise ValueError("no OpenEXR magic number")
    (version,) = struct.unpack("<i", head[4:])
    types: dict[str, str] = {}
    while True:
        found, chlist = _header(f)
        if not found:  # the empty header that ends a multi-part file's list
            break
        types.update(_channels(chlist))
        if not version & MULTIPART:
            break
    return types


def _header(f) -> tuple[bool, bytes]:
    """One header: whether it has any attribute, and its ``channels`` value (``b""``)."""
    found, chlist = False, b""
    while True:
        name = _cstring(f)
        if not name:
            return found, chlist
        found = True
        kind = _cstring(f)
        (size,) = struct.unpack("<i", _exactly(f, 4))
        if size < 0:
            raise ValueError(f"attribute {name!r} has a negative size")
        if name == b"channels" and kind == b"chlist":
            chlist = _exactly(f, size)
        else:
            f.seek(size, 1)


def _channels(chlist: bytes) -> dict[str, str]:
    """Channel name to pixel type from a ``chlist`` value."""
    out, pos = {}, 0
    try:
        while chlist[pos] != 0:
            end = chlist.index(b"\0", pos)
            (kind,) = struct.unpack_from("<i", chlist, end + 1)
            out[chlist[pos:end].decode("utf-8", "replace")] = PIXEL_TYPES.get(kind, "unknown")
            pos = end + 1 + 16  # pixel type, pLinear, 3 reserved bytes, x and y sampling
    except (IndexError, ValueError, struct.error):
        raise ValueError("its channel list ends early") from None
    return out


def _cstring(f) -> bytes:
    """A null-terminated string (without its null byte)."""
    out = bytearray()
    while len(out) < _NAME_MAX:
        byte = f.read(1)
        if not byte:
            raise ValueError("its header ends early")
        if byte == b"\0":
            return bytes(out)
        out += byte
    raise ValueError("a header name longer than 255 bytes")


def _exactly(f, n: int) -> bytes:
    data = f.read(n)
    if len(data) != n:
        raise ValueError("its header ends early")
    return data
