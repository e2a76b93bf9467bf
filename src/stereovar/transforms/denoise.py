"""``denoise``: Intel Open Image Denoise (OIDN) on each render, as BlenderProc runs it.

OIDN is reached through its Python binding ``pyoidn`` (the ``mitigations`` extra), imported on
first use so that importing :mod:`stereovar.transforms` needs no pyoidn.
"""

from __future__ import annotations

import atexit
import hashlib
import threading
from collections import OrderedDict

import numpy as np

from .base import TransformInputs

QUALITIES = ("high", "balanced", "fast", "default")
"""OIDN's filter qualities (``OIDN_QUALITY_*``); ``"high"`` is OIDN's and pyoidn's default."""

_LOCK = threading.Lock()
_DEVICES: dict[int, tuple] = {}  # threads -> (pyoidn.Device, {aux key: pyoidn.Filter})

MEMO_BYTES = 64 * 2**20
"""Most bytes of denoised images kept for a repeated call (:func:`denoise_image`): the
calibration passes each replicate's frames through ``denoise`` and ``denoise_sensor``, whose
first step is the same OIDN call on the same image."""

_MEMO: OrderedDict[bytes, np.ndarray] = OrderedDict()


def _memo_key(images: dict, **options) -> bytes:
    """A digest of the prepared inputs and the filter's options."""
    digest = hashlib.blake2b(repr(sorted(options.items())).encode(), digest_size=20)
    for name in sorted(images):
        image = images[name]
        digest.update(f"{name}{image.shape}{image.dtype}".encode())
        digest.update(memoryview(np.ascontiguousarray(image)).cast("B"))
    return digest.digest()


def _remember(key: bytes, output: np.ndarray) -> None:
    _MEMO[key] = output
    while sum(v.nbytes for v in _MEMO.values()) > MEMO_BYTES and len(_MEMO) > 1:
        _MEMO.popitem(last=False)


def _pyoidn():
    try:
        import pyoidn
    except ImportError as err:  # pragma: no cover - the extra is installed by make setup
        raise ImportError(
            "the denoise transform needs pyoidn; install the mitigations extra: "
            "pip install 'stereovar[mitigations]' (in a checkout, make setup does)"
        ) from err
    return pyoidn


def _check(device, operation: str) -> None:
    message = device.get_error()
    if message is not None:
        raise RuntimeError(f"OIDN {operation} failed: {message}")


def _filter(threads: int, key: tuple):
    """The cached OIDN CPU device with ``threads`` threads and its RT filter for ``key``."""
    pyoidn = _pyoidn()
    if threads not in _DEVICES:
        device = pyoidn.Device(pyoidn.OIDN_DEVICE_TYPE_CPU)
        device.set_int("numThreads", threads)
        device.commit()
        _check(device, "device commit")
        _DEVICES[threads] = (device, {})
    device, filters = _DEVICES[threads]
    if key not in filters:
        filters[key] = pyoidn.Filter(device, pyoidn.OIDN_FILTER_TYPE_RT)
        _check(device, "filter creation")
    return device, filters[key]


@atexit.register
def _release() -> None:
    with _LOCK:
        for device, filters in _DEVICES.values():
            for flt in filters.values():
                flt.release()
            device.release()
        _DEVICES.clear()


def prepare_inputs(color, albedo=None, normal=None) -> tuple[dict, np.ndarray]:
    """The contiguous float32 images OIDN's RT filter is given, and the non-finite colour
    entries.

    OIDN needs finite input. Colour: non-finite entries become 0 and negative ones 0 (HDR
    colour is non-negative radiance); albedo: non-finite to 0, clipped to [0, 1]; normal:
    non-finite to 0, clipped to [-1, 1].

    Returns
    -------
    images : dict
        ``color`` and, when given, ``albedo`` and ``normal`` (H, W, 3) float32.
    nonfinite : numpy.ndarray of bool (H, W, 3)
        Colour entries that were NaN or Inf.
    """
    color = np.asarray(color, dtype=np.float32)
    if color.ndim != 3 or color.shape[2] != 3:
        raise ValueError(f"denoise needs an (H, W, 3) colour image, got shape {color.shape}")
    if normal is not None and albedo is None:
        raise ValueError(
            "OIDN's RT filter takes a normal pass only together with an albedo pass; give both "
            "or neither"
        )
    nonfinite = ~np.isfinite(color)
    images = {"color": np.ascontiguousarray(np.where(nonfinite, 0.0, np.maximum(color, 0.0)))}
    for name, image, low in (("albedo", albedo, 0.0), ("normal", normal, -1.0)):
        if image is None:
            continue
        image = np.asarray(image, dtype=np.float32)
        if image.shape != color.shape:
            raise ValueError(f"{name} has shape {image.shape}, the colour {color.shape}")
        clean = np.clip(np.nan_to_num(image, nan=0.0, posinf=0.0, neginf=0.0), low, 1.0)
        images[name] = np.ascontiguousarray(clean, dtype=np.float32)
    images = {k: v.astype(np.float32, copy=False) for k, v in images.items()}
    return images, nonfinite


def denoise_image(
    color,
    *,
    albedo=None,
    normal=None,
    clean_aux: bool = False,
    quality: str = "high",
    threads: int = 1,
) -> tuple[np.ndarray, int]:
    """OIDN's RT filter on an HDR image, with the auxiliary passes when given.

    .. math::

        \\hat I = D_{\\text{OIDN}}\\bigl(I;\\ A, N\\bigr)

    with :math:`D_{\\text{OIDN}}` OIDN's pretrained ``RT`` network, ``hdr=True`` (linear
    radiance, not tone-mapped), the albedo :math:`A` and normal :math:`N` passes when given,
    else the colour-only network. Inputs are first made finite (:func:`prepare_inputs`). A
    call with the same inputs and options as a recent one returns a copy of that one's
    output (OIDN on the CPU is deterministic; at most :data:`MEMO_BYTES` are kept).

    Parameters
    ----------
    color : numpy.ndarray, shape (H, W, 3)
        Linear radiance.
    albedo, normal : numpy.ndarray, shape (H, W, 3), keyword-only, optional
        Auxiliary passes; a normal needs an albedo (OIDN's rule).
    clean_aux : bool, keyword-only
        OIDN's ``cleanAux``: True tells OIDN the auxiliary passes are noise-free. False (the
        default) because ours come from a cheap low-SPP AOV pass and carry sampling noise at
        edges; OIDN then uses its networks trained on noisy auxiliary passes.
    quality : {"high", "balanced", "fast", "default"}, keyword-only
    threads : int, keyword-only
        OIDN's ``numThreads`` (1: one core per job, as the workflow schedules them).

    Returns
    -------
    denoised : numpy.ndarray, float32 (H, W, 3)
    n_nonfinite : int
        Non-finite colour entries that were replaced by 0 before OIDN.
    """
    if quality not in QUALITIES:
        raise ValueError(f"quality must be one of {QUALITIES}, got {quality!r}")
    threads = int(threads)
    if threads < 1:
        raise ValueError(f"threads must be at least 1, got {threads}")
    pyoidn = _pyoidn()
    levels = {
        "high": pyoidn.OIDN_QUALITY_HIGH,
        "balanced": pyoidn.OIDN_QUALITY_BALANCED,
        "fast": pyoidn.OIDN_QUALITY_FAST,
        "default": pyoidn.OIDN_QUALITY_DEFAULT,
    }
    images, nonfinite = prepare_inputs(color, albedo, normal)
    key = _memo_key(images, clean_aux=bool(clean_aux), quality=quality, threads=threads)
    with _LOCK:
        if key in _MEMO:  # OIDN on the CPU is deterministic: the same call, the same image
            _MEMO.move_to_end(key)
            return _MEMO[key].copy(), int(nonfinite.sum())
    output = np.empty_like(images["color"])
    with _LOCK:
        device, flt = _filter(threads, tuple(sorted(images)))
        for name, image in images.items():
            flt.set_image(name, image, pyoidn.OIDN_FORMAT_FLOAT3)
        flt.set_image(pyoidn.OIDN_IMAGE_OUTPUT, output, pyoidn.OIDN_FORMAT_FLOAT3)
        flt.set_bool("hdr", True)
        flt.set_bool("cleanAux", bool(clean_aux))
        flt.set_quality(levels[quality])
        flt.commit()
        _check(device, "filter commit")
        flt.execute()
        _check(device, "filter execution")
        _remember(key, output.copy())
    return output, int(nonfinite.sum())


def apply_denoise(
    inputs: TransformInputs,
    *,
    clean_aux: bool = False,
    quality: str = "high",
    threads: int = 1,
) -> np.ndarray:
    """``denoise``: OIDN on one render, with albedo and normal passes when the source has them.

    .. math::

        I'^{(n)} = D_{\\text{OIDN}}\\bigl(I^{(n)};\\ A, N\\bigr)

    (:func:`denoise_image`). BlenderProc's default: its renderer enables Blender's OIDN
    denoiser fed with the normal and diffuse-colour passes (and renders 1024 SPP with
    adaptive threshold 0.01); Kubric uses Blender's default denoiser. A denoiser mixes each
    pixel with its neighbours, so it changes the variance field the paper's Eq. 1 measures
    (Sec. 2.1) without promising to remove its cross-view alignment (Sec. 2.3).

    Without albedo and normal it runs the colour-only network: lower quality on texture and
    edges, stated in the mitigation table by the source's inputs. A normal pass without an
    albedo pass is not used (OIDN takes a normal only together with an albedo). A non-finite
    colour entry is denoised as 0 and is NaN in the output, so the stores' finite flags drop
    it as they would without the transform.

    Parameters
    ----------
    inputs : TransformInputs
        Uses ``albedo`` and ``normal`` when given.
    clean_aux, quality, threads : keyword-only
        As :func:`denoise_image`.

    Returns
    -------
    numpy.ndarray, float32 (H, W, 3)
    """
    out, n_nonfinite = denoise_image(
        inputs.render,
        albedo=inputs.albedo,
        normal=inputs.normal if inputs.albedo is not None else None,
        clean_aux=clean_aux,
        quality=quality,
        threads=threads,
    )
    if n_nonfinite:
        out[~np.isfinite(np.asarray(inputs.render))] = np.nan
    return out
