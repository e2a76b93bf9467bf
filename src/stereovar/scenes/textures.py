"""Procedural diffuse textures baked to bitmaps.

A scene spec names its textures by a small dictionary (see ``scene.schema.yaml``,
``$defs/texture``)::

    {"pattern": "planks", "colors": [[0.4, 0.25, 0.12], [0.2, 0.1, 0.05]],
     "seed": 3, "resolution": 512, "repeat": [4, 4]}

:func:`bake_texture` turns that into an ``(resolution, resolution, 3)`` float32 array of linear
RGB albedos in ``[0, 1]``. The result is a pure, deterministic function of ``pattern``,
``colors``, ``seed`` and ``resolution``; ``repeat`` is not baked in (the renderer applies it
as a UV scale).

Stereo matching needs texture, so every pattern carries fine, high-contrast, non-repetitive
detail: multi-octave value noise at scales down to two texels sits on top of the pattern's
structure. Every pattern is tileable: all lattices, stripe widths, board and tile counts are
periodic over the unit square, so the left and right (top and bottom) borders continue each
other seamlessly when the renderer repeats the bitmap.

Image convention: row ``i`` is ``v`` (top row first), column ``j`` is ``u``; texel centres are
at ``((j + 0.5) / n, (i + 0.5) / n)``.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import os
from pathlib import Path

import numpy as np

log = logging.getLogger("stereovar")

PATTERNS = ("planks", "tiles", "noise", "stripes", "checker", "grain")


# --------------------------------------------------------------------------------------------
# periodic value noise
# --------------------------------------------------------------------------------------------


def _axis_weights(n: int, freq: int):
    """Lattice indices and weights that interpolate a periodic lattice of ``freq`` cells.

    Returns ``(k0, k1, w)`` with ``value = (1 - w) * lattice[k0] + w * lattice[k1]`` at each
    of the ``n`` texel centres. The smoothstep weight makes the interpolant C1.
    """
    x = (np.arange(n, dtype=np.float64) + 0.5) * (freq / n)
    base = np.floor(x)
    t = x - base
    k0 = base.astype(np.int64) % freq
    k1 = (k0 + 1) % freq
    w = t * t * (3.0 - 2.0 * t)
    return k0, k1, w


def _value_noise(rng: np.random.Generator, n: int, fy: int, fx: int) -> np.ndarray:
    """One octave of periodic value noise in ``[0, 1]`` on an ``n x n`` grid.

    The ``fy x fx`` random lattice wraps around, so the result tiles seamlessly. The
    interpolation is separable: rows of the lattice are interpolated first (``fy x n``),
    then columns, which costs ``O(n * (fx + n))``.
    """
    fy = int(max(1, min(fy, n)))
    fx = int(max(1, min(fx, n)))
    lattice = rng.random((fy, fx))
    k0, k1, w = _axis_weights(n, fx)
    rows = lattice[:, k0] * (1.0 - w) + lattice[:, k1] * w  # (fy, n)
    k0, k1, w = _axis_weights(n, fy)
    return rows[k0, :] * (1.0 - w)[:, None] + rows[k1, :] * w[:, None]  # (n, n)


def _fbm(
    rng: np.random.Generator,
    n: int,
    *,
    base: int = 4,
    aspect: float = 1.0,
    gain: float = 0.55,
    octaves: int | None = None,
) -> np.ndarray:
    """Multi-octave (fractal) periodic value noise normalised to zero mean, unit std.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the lattices.
    n : int
        Grid size.
    base : int
        Lattice cells of the first octave along x.
    aspect : float
        Lattice cells along y per cell along x (``> 1`` stretches features along x, as in
        wood grain). Rounded per octave to an integer, so the field stays tileable.
    gain : float
        Amplitude ratio of successive octaves.
    octaves : int, optional
        Number of octaves; by default enough to reach a two-texel lattice.
    """
    if octaves is None:
        octaves = max(1, int(np.floor(np.log2(max(n / 2.0, 1.0) / base))) + 1)
    total = np.zeros((n, n))
    amp = 1.0
    for o in range(octaves):
        fx = base * 2**o
        fy = max(1, int(round(fx * aspect)))
        total += amp * _value_noise(rng, n, fy, fx)
        amp *= gain
    total -= total.mean()
    std = total.std()
    return total / std if std > 0 else total


def _detail(rng: np.random.Generator, n: int) -> np.ndarray:
    """Zero-mean, unit-std fine detail: the top octaves of value noise (scales 2 to ~16 texels)."""
    total = np.zeros((n, n))
    amp = 1.0
    freq = max(1, n // 2)
    for _ in range(4):
        total += amp * _value_noise(rng, n, freq, freq)
        amp *= 0.8
        freq = max(1, freq // 2)
    total -= total.mean()
    std = total.std()
    return total / std if std > 0 else total


def _ramp(colors: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Piecewise-linear colour ramp through ``colors`` evaluated at ``t`` in ``[0, 1]``."""
    k = len(colors)
    x = np.clip(t, 0.0, 1.0) * (k - 1)
    i0 = np.minimum(np.floor(x).astype(np.int64), k - 2)
    w = (x - i0)[..., None]
    return colors[i0] * (1.0 - w) + colors[i0 + 1] * w


def _squash(x: np.ndarray) -> np.ndarray:
    """Map a zero-mean, unit-std field to ``(0, 1)`` smoothly."""
    return 0.5 + 0.5 * np.tanh(0.8 * x)


def _coords(n: int):
    """Texel-centre coordinates ``(u, v)`` in ``[0, 1)`` as broadcastable 1-D arrays."""
    c = (np.arange(n, dtype=np.float64) + 0.5) / n
    return c[None, :], c[:, None]


# --------------------------------------------------------------------------------------------
# patterns; each returns float64 (n, n, 3), unclipped
# --------------------------------------------------------------------------------------------


def _noise(rng, n, colors):
    """Plaster: fractal noise through the colour ramp plus fine speckle."""
    t = _squash(_fbm(rng, n, base=4, gain=0.6))
    img = _ramp(colors, t)
    fine = _detail(rng, n)
    return img * (1.0 + 0.22 * fine)[..., None]


def _planks(rng, n, colors):
    """Floor boards running along u, staggered joints, per-board tint, grain and gaps."""
    rows = int(rng.integers(4, 9))
    per_row = int(rng.integers(1, 4))
    u, v = _coords(n)
    row = np.floor(v * rows).astype(np.int64) % rows  # (n, 1)
    v_in = v * rows - np.floor(v * rows)  # (n, 1), position across the board
    offsets = rng.random(rows)
    shifted = u + offsets[row]  # (n, n)
    board_col = np.floor(shifted * per_row).astype(np.int64) % per_row
    u_in = shifted * per_row - np.floor(shifted * per_row)
    board_id = row * per_row + board_col
    tint = rng.random(rows * per_row)
    shade = 1.0 + 0.25 * (rng.random(rows * per_row) - 0.5)
    # grain: noise stretched along u (many cells across v, few along u)
    grain = _fbm(rng, n, base=2, aspect=8.0, gain=0.65)
    streaks = np.sin(2.0 * np.pi * (v * rows * 6.0 + 0.6 * grain))
    t = np.clip(tint[board_id] + 0.2 * grain + 0.15 * streaks, 0.0, 1.0)
    img = _ramp(colors, t) * shade[board_id][..., None]
    # dark gaps along the long edges and at the joints
    edge_v = np.minimum(v_in, 1.0 - v_in) * (n / rows)  # distance in texels
    edge_u = np.minimum(u_in, 1.0 - u_in) * (n / per_row)
    gap = np.clip(np.minimum(edge_v, edge_u) / 1.5, 0.0, 1.0)
    img *= (0.35 + 0.65 * gap)[..., None]
    fine = _detail(rng, n)
    return img * (1.0 + 0.18 * fine)[..., None]


def _tiles(rng, n, colors):
    """Square tiles with grout lines, per-tile colour variation and surface noise."""
    count = int(rng.integers(3, 7))
    u, v = _coords(n)
    ti = np.floor(v * count).astype(np.int64) % count
    tj = np.floor(u * count).astype(np.int64) % count
    tile_id = ti * count + tj
    body = colors[:-1] if len(colors) > 2 else colors[:1]
    grout = colors[-1]
    tint = rng.random(count * count)
    t = np.clip(tint[tile_id] + 0.15 * _fbm(rng, n, base=4, gain=0.6), 0.0, 1.0)
    img = _ramp(body, t) if len(body) > 1 else np.broadcast_to(body[0], (n, n, 3)).copy()
    shade = 1.0 + 0.3 * (rng.random(count * count) - 0.5)
    img = img * shade[tile_id][..., None]
    fu = u * count - np.floor(u * count)
    fv = v * count - np.floor(v * count)
    dist = np.minimum(np.minimum(fu, 1.0 - fu), np.minimum(fv, 1.0 - fv)) * (n / count)
    half_width = max(1.0, n / count * 0.03)
    mortar = np.clip((dist - half_width) / 1.0, 0.0, 1.0)[..., None]
    img = img * mortar + grout * (1.0 - mortar)
    fine = _detail(rng, n)
    return img * (1.0 + 0.2 * fine)[..., None]


def _stripes(rng, n, colors):
    """Wallpaper: vertical stripes of random widths with pin stripes and paper texture."""
    count = int(rng.integers(6, 16))
    widths = rng.random(count) + 0.4
    edges = np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])
    edges[-1] = 1.0
    u, v = _coords(n)
    idx = np.clip(np.searchsorted(edges, u[0], side="right") - 1, 0, count - 1)  # (n,)
    choice = rng.integers(0, len(colors), size=count)
    # neighbouring stripes get different colours
    for k in range(1, count):
        if choice[k] == choice[k - 1]:
            choice[k] = (choice[k] + 1) % len(colors)
    img = np.broadcast_to(colors[choice[idx]][None, :, :], (n, n, 3)).copy()
    # thin darker pin stripes at the boundaries
    dist = np.min(np.abs(u[0][:, None] - edges[None, :]), axis=1)
    dist = dist * n
    pin = np.clip(dist / 1.5, 0.0, 1.0)
    img *= (0.55 + 0.45 * pin)[None, :, None]
    # a faint print along v and paper fibres
    motif = 0.5 + 0.5 * np.sin(2.0 * np.pi * (int(rng.integers(8, 24)) * v))
    img *= (0.92 + 0.08 * motif)[..., None]
    cloud = _fbm(rng, n, base=4, gain=0.55)
    fine = _detail(rng, n)
    return img * (1.0 + 0.1 * cloud + 0.2 * fine)[..., None]


def _checker(rng, n, colors):
    """Checkerboard of ``colors[0]`` / ``colors[1]`` (even / odd cells) with surface noise.

    Cell ``(i, j)`` covers ``floor(v * c) == i`` and ``floor(u * c) == j`` for an even cell
    count ``c`` (so it tiles); colours beyond the second tint the cells.
    """
    count = 2 * int(rng.integers(2, 6))
    u, v = _coords(n)
    parity = (np.floor(v * count).astype(np.int64) + np.floor(u * count).astype(np.int64)) % 2
    img = np.where(parity[..., None] == 0, colors[0], colors[1])
    if len(colors) > 2:
        extra = colors[2:]
        mix = _squash(_fbm(rng, n, base=4, gain=0.6))
        pick = extra[rng.integers(0, len(extra))]
        img = img * (1.0 - 0.25 * mix[..., None]) + pick * 0.25 * mix[..., None]
    # bounded modulation (at most +-26 %), so every texel stays nearer its own cell colour
    fine = np.tanh(_detail(rng, n))
    cloud = np.tanh(_fbm(rng, n, base=4, gain=0.5))
    return img * (1.0 + 0.06 * cloud + 0.2 * fine)[..., None]


def _grain(rng, n, colors):
    """Furniture wood: warped growth rings running along u, fibres and pores."""
    rings = int(rng.integers(6, 16))
    u, v = _coords(n)
    warp = _fbm(rng, n, base=2, aspect=3.0, gain=0.5)
    phase = v * rings + 0.45 * warp + 0.15 * np.sin(2.0 * np.pi * (u + rng.random()))
    ring = phase - np.floor(phase)
    # late wood: a sharp dark band at the end of each ring
    band = ring**3
    fibres = _fbm(rng, n, base=2, aspect=16.0, gain=0.7)
    t = np.clip(0.1 + 0.7 * band + 0.12 * fibres, 0.0, 1.0)
    img = _ramp(colors, t)
    fine = _detail(rng, n)
    return img * (1.0 + 0.18 * fine)[..., None]


_PATTERN_FUNCS = {
    "planks": _planks,
    "tiles": _tiles,
    "noise": _noise,
    "stripes": _stripes,
    "checker": _checker,
    "grain": _grain,
}

# salts keep the random streams of different patterns with the same seed unrelated
_SALT = {name: i + 1 for i, name in enumerate(PATTERNS)}


def bake_texture(spec: dict) -> np.ndarray:
    """Bake a procedural texture spec to a linear-RGB bitmap.

    Parameters
    ----------
    spec : dict
        A texture entry of a scene spec: ``pattern`` (one of ``planks``, ``tiles``,
        ``noise``, ``stripes``, ``checker``, ``grain``), ``colors`` (2 to 4 linear RGB
        albedos in ``[0, 1]``), optional ``seed`` (int >= 0, default 0) and ``resolution``
        (int, default 256). ``repeat`` and any other key are ignored here: the renderer
        applies ``repeat`` as a UV scale.

    Returns
    -------
    numpy.ndarray, shape (resolution, resolution, 3), dtype float32
        Linear RGB albedo in ``[0, 1]``; row 0 is the top of the image (``v = 0``).
        Tileable: the pattern continues across opposite borders.

    Raises
    ------
    ValueError
        If the pattern is unknown, fewer than two colours are given, or the resolution is
        below 16.

    Notes
    -----
    The same spec always gives the same array: all randomness comes from
    ``numpy.random.default_rng([seed, pattern_salt])``. Patterns:

    * ``planks`` -- floor boards along ``u`` with staggered joints, dark gaps, per-board tint
      and stretched grain.
    * ``tiles`` -- square tiles with grout (the last colour) and per-tile variation.
    * ``noise`` -- multi-octave value noise through the colour ramp (plaster).
    * ``stripes`` -- wallpaper stripes of random widths along ``u`` with pin stripes.
    * ``checker`` -- an even number of cells per side; cell ``(i, j)`` is ``colors[0]`` when
      ``i + j`` is even, else ``colors[1]``, modulated by noise.
    * ``grain`` -- warped growth rings and fibres (furniture wood).

    Each pattern is multiplied by fine value-noise detail (scales of 2 to ~16 texels).

    Examples
    --------
    >>> img = bake_texture({"pattern": "noise", "colors": [[0.8, 0.8, 0.8], [0.5, 0.5, 0.5]],
    ...                     "resolution": 64})
    >>> img.shape, img.dtype
    ((64, 64, 3), dtype('float32'))
    """
    pattern = spec.get("pattern")
    if pattern not in _PATTERN_FUNCS:
        raise ValueError(f"unknown texture pattern {pattern!r}; use one of {', '.join(PATTERNS)}")
    colors = np.asarray(spec.get("colors", ()), dtype=np.float64)
    if colors.ndim != 2 or colors.shape[0] < 2 or colors.shape[1] != 3:
        raise ValueError("texture 'colors' must be a list of 2 to 4 RGB triples")
    colors = np.clip(colors, 0.0, 1.0)
    n = int(spec.get("resolution", 256))
    if n < 16:
        raise ValueError(f"texture resolution {n} is below 16; use at least 16")
    seed = int(spec.get("seed", 0))
    rng = np.random.default_rng([seed, _SALT[pattern]])
    img = _PATTERN_FUNCS[pattern](rng, n, colors)
    return np.clip(img, 0.0, 1.0).astype(np.float32)


TEXTURE_VERSION = 1
"""Bumped whenever :func:`bake_texture` would give a different image for the same spec, so
cached bakes of the old version are never reused."""


def texture_cache_dir() -> Path:
    """Directory of baked textures: ``$STEREOVAR_CACHE_DIR/textures`` or
    ``~/.cache/stereovar/textures``."""
    root = os.environ.get("STEREOVAR_CACHE_DIR") or Path.home() / ".cache" / "stereovar"
    return Path(root) / "textures"


def texture_shape(spec: dict) -> tuple[int, int, int]:
    """Shape of the bitmap :func:`bake_texture` gives for ``spec``: ``(n, n, 3)`` with ``n``
    its ``resolution`` (default 256)."""
    n = int(spec.get("resolution", 256))
    return (n, n, 3)


def texture_cache_paths(spec: dict, cache_dir=None) -> tuple[Path, Path]:
    """Where the cached bake of ``spec`` lives: the ``.npy`` bitmap and its ``.json`` record.

    Both are named by the SHA-256 of the canonical JSON of ``spec`` and
    :data:`TEXTURE_VERSION`, so a cached image is only reused for the identical recipe.
    """
    key = json.dumps({"spec": spec, "version": TEXTURE_VERSION}, sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()
    root = Path(cache_dir or texture_cache_dir())
    return root / f"{digest}.npy", root / f"{digest}.json"


def read_cached_texture(spec: dict, cache_dir=None) -> tuple[np.ndarray | None, str | None]:
    """The cached bake of ``spec``, verified against what was recorded when it was baked.

    The bytes of the ``.npy`` file are read once; their SHA-256 must equal the one in the
    record beside it, and the array decoded from those same bytes must be float32 of
    :func:`texture_shape`.

    Parameters
    ----------
    spec : dict
        A texture spec (:func:`bake_texture`).
    cache_dir : path-like, optional
        The cache (default :func:`texture_cache_dir`).

    Returns
    -------
    image : numpy.ndarray or None
        The verified bitmap; None when there is none to use.
    problem : str or None
        Why the cached file was refused (one phrase), or None when it was used or there is
        no cached file.
    """
    path, record_path = texture_cache_paths(spec, cache_dir)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None, None
    except OSError as err:
        return None, f"it cannot be read ({err.strerror or err})"
    try:
        recorded = json.loads(record_path.read_text())["sha256"]
    except FileNotFoundError:
        return None, f"its record {record_path.name} of the SHA-256 it was baked with is missing"
    except (OSError, ValueError, KeyError, TypeError):
        return None, f"its record {record_path.name} is unreadable"
    actual = hashlib.sha256(data).hexdigest()
    if actual != recorded:
        return None, f"its SHA-256 is {actual}, not the {recorded} it was baked with"
    try:
        image = np.load(io.BytesIO(data), allow_pickle=False)
    except (OSError, ValueError, EOFError) as err:
        return None, f"it is not a NumPy array ({err})"
    shape = texture_shape(spec)
    if not isinstance(image, np.ndarray) or image.dtype != np.float32 or image.shape != shape:
        found = f"{image.dtype} {image.shape}" if isinstance(image, np.ndarray) else "no array"
        return None, f"it holds {found}, not float32 {shape}"
    return image, None


def bake_texture_cached(spec: dict, cache_dir=None) -> np.ndarray:
    """:func:`bake_texture` with a verified, content-addressed on-disk cache.

    Every render job compiles its scene afresh; the cache spares each one the baking (about a
    second for a scene with several 1024² textures). A bake is stored as a ``.npy`` file and a
    ``.json`` record of its SHA-256, shape and dtype (:func:`texture_cache_paths`), each
    written atomically. A cached file is used only when it verifies
    (:func:`read_cached_texture`); a damaged one is baked again and replaced, with one warning
    naming it, so a render never uses damaged pixels. An unwritable cache falls back to
    baking.

    Returns
    -------
    numpy.ndarray, shape (resolution, resolution, 3), dtype float32
        Equal to ``bake_texture(spec)``; read-only, as it may be shared by the callers.
    """
    from ..errors import StereovarError
    from ..io.store import write_file

    image, problem = read_cached_texture(spec, cache_dir)
    if image is None:
        path, record_path = texture_cache_paths(spec, cache_dir)
        if problem:
            log.warning("baked texture %s is damaged: %s; baking it again", path, problem)
        image = bake_texture(spec)
        buffer = io.BytesIO()
        np.save(buffer, image, allow_pickle=False)
        data = buffer.getvalue()
        record = {
            "sha256": hashlib.sha256(data).hexdigest(),
            "shape": list(image.shape),
            "dtype": str(image.dtype),
            "spec": spec,
            "version": TEXTURE_VERSION,
        }
        try:
            write_file(path, lambda tmp: Path(tmp).write_bytes(data))
            write_file(record_path, lambda tmp: Path(tmp).write_text(json.dumps(record)))
        except (OSError, StereovarError) as err:
            log.info("baked texture %s not cached (%s)", path, err)
    image.flags.writeable = False
    return image
