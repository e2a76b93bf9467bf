"""What a mitigated or calibrated image reads and costs: the converged reference of a source,
the auxiliary passes (albedo, normal) a transform reads when its source renders them, the
options a transform takes from the config, and the samples behind one mitigated image.
"""

from __future__ import annotations

import inspect

from ..config import moments_settings_error
from ..renderers import RENDERERS
from ..transforms import get_transform

#: The auxiliary passes a transform may read.
AUX = frozenset({"albedo", "normal"})


def reference_from_moments(source: str, render: dict) -> bool:
    """Whether a source's converged reference is a moments render of each view at
    ``mitigations.reference_spp``: a renderer with sample moments, rendering with the
    independent sampler and the box filter (``render``: the ``render:`` config section).
    Otherwise the reference is a split-half one of its own renders
    (:func:`stereovar.statistics.utility.split_half_quality`: audits, Cycles)."""
    return bool(
        source in RENDERERS
        and RENDERERS.get(source).sample_moments
        and moments_settings_error(render["sampler"], render["rfilter"]) is None
    )


def source_aux_passes(source: str) -> tuple:
    """The auxiliary passes a source gives (a renderer's ``aux_passes``; an audit none)."""
    if source in RENDERERS:
        return RENDERERS.get(source).aux_passes
    return ()


def reads_aux(transforms, source: str) -> bool:
    """Whether any of ``transforms`` (names) reads albedo or normal, required or optional,
    and ``source`` renders every auxiliary pass they read: then their jobs get the passes as
    inputs."""
    wants = set()
    for name in transforms:
        t = get_transform(name)
        wants |= AUX & {*t.reads, *t.optional_reads}
    return bool(wants) and wants <= set(source_aux_passes(source))


def transform_options(transform: str, sensor: dict) -> dict:
    """The options of ``transform`` that the config sets: the camera model of
    ``controls.sensor`` (``gain``, ``read_noise``), for the transforms whose ``apply`` takes
    them (those that add or model camera noise)."""
    accepted = inspect.signature(get_transform(transform).apply).parameters
    offered = {"gain": sensor["gain"], "read_noise": sensor["read_noise"]}
    return {k: v for k, v in offered.items() if k in accepted}


def image_cost(run, n_seeds: int, aux_spp: int) -> dict:
    """Samples per pixel behind one mitigated image of mitigation row ``run``
    (:func:`stereovar.mitigations.mitigation_runs`): ``render_spp``, N x SPP when the
    transform reads the seed mean or variance (which average the N = ``n_seeds`` renders),
    else the SPP; and ``aux_spp``, the SPP of the auxiliary pass it reads once per view
    (``mitigations.aux_spp``; 0 without one)."""
    render_spp, aux = run.spp, 0
    if run.mitigation.kind == "transform":
        t = get_transform(run.transform)
        if {"seed_mean", "seed_var"} & set(t.reads):
            render_spp *= n_seeds
        if reads_aux([run.transform], run.source):
            aux = aux_spp
    return {"render_spp": render_spp, "aux_spp": aux}


DOSE_DEFAULT = "sensor_only"
"""The transform the dose-response measures by default, where it is a mitigation row."""


def dose_response_plan(config: dict, runs) -> dict:
    """What the dose-response measures (``mitigations.dose_response``): its ``transforms``
    (null: :data:`DOSE_DEFAULT` where it is a row),
    the ``cameras`` (the run's ``controls.sensor`` first, then one per extra gain at the same
    read noise), the budget ``multiples`` and the ``rendered`` ones (1: the run's renders;
    K: a ``spp_xK`` row's renders), for the mitigation rows ``runs``
    (:func:`stereovar.mitigations.mitigation_runs`).

    Raises
    ------
    stereovar.errors.ConfigError
        A transform is not among the mitigation rows, or does not read the seed mean (one
        line naming ``mitigations.dose_response.transforms``).
    """
    from ..errors import ConfigError

    dose = dict(config["mitigations"].get("dose_response") or {})
    names = {r.transform for r in runs if r.mitigation.kind == "transform"}
    transforms = dose.get("transforms")
    if transforms is None:  # the default: sensor_only where it is a mitigation row
        transforms = [DOSE_DEFAULT] if DOSE_DEFAULT in names else []
    for name in transforms:
        reads = set(get_transform(name).reads) if name in names else set()
        if not {"seed_mean", "seed_var"} & reads:
            raise ConfigError(
                f"config key 'mitigations.dose_response.transforms': {name!r} is not a "
                "mitigation row that ships the seed mean; use some of "
                + ", ".join(sorted(n for n in names
                                   if {"seed_mean", "seed_var"} & set(get_transform(n).reads)))
                + " (each also in mitigations.names)"
            )
    sensor = config["controls"]["sensor"]
    cameras = [{"gain": float(sensor["gain"]), "read_noise": float(sensor["read_noise"])}]
    for gain in dose.get("gains", []):
        if float(gain) != cameras[0]["gain"]:
            cameras.append({"gain": float(gain), "read_noise": float(sensor["read_noise"])})
    multiples = sorted({int(m) for m in dose.get("multiples", [1])})
    factors = {1} | {r.mitigation.spp_factor for r in runs if r.mitigation.kind == "spp"}
    return {
        "transforms": transforms if runs else [],
        "cameras": cameras,
        "multiples": multiples,
        "rendered": sorted(factors & set(multiples)),
        "replicates": int(dose.get("replicates", 2)),
    }
