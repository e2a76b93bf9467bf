"""Sampler seeds: one deterministic derivation, selected by a seed policy.

Mitsuba (like most path tracers) gives two sensors rendered with the same seed identical
random streams, so whether the two views share seeds is an experimental condition, never an
accident. :func:`render_seed` derives the seed of every render from its labels under a named
policy; :data:`SEED_POLICIES` lists the policies: ``independent`` (the experiment) and
``shared`` (both views of a render get one seed, as several Blender-based generators do by
default; the ``shared_seed`` mitigation, :mod:`stereovar.mitigations`).

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import hashlib

from .registry import Registry

SEED_POLICIES = Registry("seed policy", config_key="render.seed_policy")
"""Policy name to ``labels(scene, view, spp, index) -> tuple`` of the parts hashed by
:func:`derive_seed`."""


def derive_seed(*parts) -> int:
    """Deterministic 32-bit sampler seed from labelled parts (scene, view, spp, index, ...).

    .. math:: \\mathrm{seed} = \\mathrm{SHA256}(p_1 \\,|\\, p_2 \\,|\\, \\dots)\\ \\bmod\\ 2^{32}

    (the first four digest bytes, little-endian).
    """
    text = "|".join(str(p) for p in parts).encode()
    return int.from_bytes(hashlib.sha256(text).digest()[:4], "little")


@SEED_POLICIES.register("independent")
def independent_labels(scene: str, view: str, spp, index) -> tuple:
    """Every (scene, view, spp, index) gets its own seed; the views never share one."""
    return (scene, view, spp, index)


@SEED_POLICIES.register("shared")
def shared_labels(scene: str, view: str, spp, index) -> tuple:
    """Both views of render ``index`` get one seed: what Kubric and Infinigen do, since
    neither sets Cycles' seed (default 0) and each renders a view as its own job. Mitsuba
    then gives both sensors the same random stream at the same pixel coordinates
    (``sample_tea_32(seed, pixel index)``). The label ``"shared"`` keeps these seeds apart
    from any ``independent`` one."""
    return ("shared", scene, spp, index)


def render_seed(scene: str, view: str, spp, index, *, policy: str = "independent") -> int:
    """The sampler seed of one render under seed policy ``policy``.

    .. math:: \\mathrm{seed} = \\mathrm{SHA256}\\bigl(\\ell_\\pi(\\text{scene}, \\text{view},
        \\text{spp}, n)\\bigr)\\ \\bmod\\ 2^{32}

    with :math:`\\ell_\\pi` the labels of policy :math:`\\pi` (paper Sec. 2.1: the views' seeds
    are independent under ``independent``).

    Parameters
    ----------
    scene, view : str
    spp : int
    index : int or str
        Seed index (or a label such as ``"preview"``).
    policy : str, keyword-only
        A name in :data:`SEED_POLICIES`.

    Raises
    ------
    stereovar.errors.ConfigError
        ``policy`` is not registered.
    """
    return derive_seed(*SEED_POLICIES.get(policy)(scene, view, spp, index))
