"""The mitigations: what a data team can do to its renders, each a row of the mitigation table.

A mitigation is one of

``none``
    the baseline: the source's own renders, independent seeds;
a **seed policy** (``shared_seed``)
    a render-time policy: the scenes rendered anew with the policy's sampler seeds
    (:data:`stereovar.seeding.SEED_POLICIES`), under ``results/{source}/{name}/renders/``;
``spp_xK``
    K times the main SPP: every scene rendered at K x SPP (the SPP sweep's renders of its
    scene are reused), the equal-budget row;
a **store transform** (:data:`stereovar.transforms.TRANSFORMS`)
    a pure function of each render (``denoise``, ``denoise_sensor``, ``equalise``,
    ``sensor_only``) applied to the source's renders, under
    ``results/{source}/{name}/renders/``.

:func:`mitigation_runs` turns ``mitigations.names`` into what each row reads: its source key
(:func:`stereovar.layout.source_key`), SPP and scenes. Every row is measured by the ``seeds``
estimator (a store transform maps single renders), the same statistics and controls, the
intervention, the cross-view residual correlation and the image-quality cost.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import ConfigError
from .layout import NONE

__all__ = [
    "KINDS",
    "MITIGATION_ESTIMATOR",
    "Mitigation",
    "MitigationRun",
    "SEED_POLICY_MITIGATIONS",
    "audit_mitigation_runs",
    "keyed_transforms",
    "mitigation_runs",
    "resolve_mitigation",
]

KINDS = ("baseline", "seed_policy", "spp", "transform")
"""What a mitigation changes."""

MITIGATION_ESTIMATOR = "seeds"
"""The estimator of every mitigation row: store transforms map single renders, so the rows
are compared on Eq. 1 over the N seeds."""

SEED_POLICY_MITIGATIONS = {"shared_seed": "shared"}
"""Mitigation name to the seed policy it renders with (:data:`stereovar.seeding.SEED_POLICIES`).

``shared_seed`` is what Kubric and Infinigen do by default: they never set Cycles' seed
(default 0, not animated) and render each view as its own job, so both views of a frame get
the same sampler seed. BlenderProc never sets it either, but its multiview render gives every
eye after the first a seed derived from it, so its eyes' noise is independent
(:mod:`stereovar.generators`). Mitsuba also defaults to ``seed=0``."""

SPP_PATTERN = re.compile(r"spp_x(\d+)")


@dataclass(frozen=True)
class Mitigation:
    """One mitigation: its ``name``, ``kind`` (:data:`KINDS`), a one-line ``description``,
    the path segment ``transform`` its renders sit under (:data:`stereovar.layout.NONE` for
    none), the ``seed_policy`` it renders with and the SPP factor."""

    name: str
    kind: str
    description: str
    transform: str = NONE
    seed_policy: str = "independent"
    spp_factor: int = 1


@dataclass(frozen=True)
class MitigationRun:
    """What one mitigation row reads: ``source`` and ``transform`` (the source key), ``spp``
    and ``scenes``."""

    mitigation: Mitigation
    source: str
    spp: int
    scenes: tuple[str, ...]

    @property
    def name(self) -> str:
        return self.mitigation.name

    @property
    def transform(self) -> str:
        return self.mitigation.transform


def _store_transforms() -> tuple[str, ...]:
    from .transforms import TRANSFORMS

    return TRANSFORMS.names()


def resolve_mitigation(name: str) -> Mitigation:
    """The :class:`Mitigation` named ``name``.

    Raises
    ------
    ConfigError
        ``name`` is none of ``none``, ``spp_xK`` (K >= 2), a seed-policy mitigation or a
        registered store transform; the one-line message lists them.

    Examples
    --------
    >>> resolve_mitigation("spp_x4").spp_factor
    4
    >>> resolve_mitigation("shared_seed").seed_policy
    'shared'
    """
    name = str(name)
    if name == NONE:
        return Mitigation(NONE, "baseline", "the source's renders, independent seeds")
    match = SPP_PATTERN.fullmatch(name)
    if match and int(match.group(1)) >= 2:
        k = int(match.group(1))
        return Mitigation(name, "spp", f"{k}x the samples per pixel", spp_factor=k)
    if name in SEED_POLICY_MITIGATIONS:
        return Mitigation(
            name,
            "seed_policy",
            "the same sampler seed in both views (Kubric's and Infinigen's default)",
            transform=name,
            seed_policy=SEED_POLICY_MITIGATIONS[name],
        )
    if name in _store_transforms():
        from .transforms import get_transform

        return Mitigation(name, "transform", get_transform(name).description, transform=name)
    known = [NONE, "spp_xK (K >= 2)", *SEED_POLICY_MITIGATIONS, *_store_transforms()]
    raise ConfigError(
        f"config key 'mitigations.names': unknown mitigation {name!r}; use any of: "
        + ", ".join(known)
    )


def keyed_transforms() -> tuple[str, ...]:
    """Every name that can follow a source in a source key: the seed-policy mitigations,
    the store transforms and the generator profiles (:data:`stereovar.generators.PROFILES`,
    rendered by Cycles under a generator's settings)."""
    from .generators import PROFILES

    return (*SEED_POLICY_MITIGATIONS, *_store_transforms(), *PROFILES)


def audit_mitigation_runs(config: dict) -> list[MitigationRun]:
    """The mitigation rows of an audit (``audit.mitigations``): ``none`` first, then each
    store transform, on every frame at the audit's SPP.

    Raises
    ------
    ConfigError
        A name is no mitigation, or a mitigation renders (``shared_seed``, ``spp_xK``): an
        audit's renders are given. The message names ``audit.mitigations``.
    """
    names = list(dict.fromkeys([NONE, *config["audit"].get("mitigations", [])]))
    transforms = ", ".join(_store_transforms())
    runs = []
    for name in names:
        try:
            m = resolve_mitigation(name)
        except ConfigError:
            raise ConfigError(
                f"config key 'audit.mitigations': unknown mitigation {name!r}; use store "
                f"transforms ({transforms})"
            ) from None
        if m.kind not in ("baseline", "transform"):
            raise ConfigError(
                f"config key 'audit.mitigations': {name!r} renders the scenes anew, and an "
                f"audit's renders are given; use store transforms only ({transforms}), or "
                "render with that setting and audit those renders"
            )
        render = config["render"]
        scenes = tuple(config["scenes"])
        runs.append(MitigationRun(m, render["renderer"], int(render["spp"]), scenes))
    return runs


def mitigation_runs(config: dict) -> list[MitigationRun]:
    """The rows of the mitigation table: ``none`` first, then ``mitigations.names`` in order.

    Parameters
    ----------
    config : dict
        A validated workflow config; ``render.renderer`` is the source.

    Returns
    -------
    list of MitigationRun
        Every row on every scene, at the main SPP, except ``spp_xK`` at K x SPP: the
        equal-budget row that every mitigation is compared with (the SPP sweep's renders of
        its scene are reused when the sweep renders that SPP).
    """
    names = list(dict.fromkeys([NONE, *config.get("mitigations", {}).get("names", [])]))
    render = config["render"]
    spp = int(render["spp"])
    scenes = tuple(config["scenes"])
    return [
        MitigationRun(m, render["renderer"], spp * m.spp_factor, scenes)
        for m in map(resolve_mitigation, names)
    ]
