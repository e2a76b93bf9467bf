"""The probe's training conditions: which renders each network family trains and is tested on.

A condition is either a mitigation (:mod:`stereovar.mitigations`), read from its source key at
its SPP on every probe scene: ``none`` (the renders as they are, independent seeds), the
control ``sensor_only`` (seed mean plus camera noise, no Monte Carlo structure) and any other
mitigation (``spp_xK`` renders every probe scene at K x SPP); or the **planted** positive
control ``planted_x{f}``: the renders' seed mean with camera-law noise whose variance carries a
cross-view pattern of ``f`` times the strength the renders show (the calibration's planted
design, :mod:`stereovar.probe.planted`), so its answer is known. A judged mitigation that
builds its images from the seed mean (``sensor_only``, ``equalise``) is trained as **shipped**
(``{name}_shipped``): from ``none``'s renders, one image per disjoint group of
:data:`SHIPPED_GROUP` seeds, each with its own group's seed mean
(:func:`stereovar.calibration.stacks.shipped_stack`), so the images are independent and the
shuffle reaches the Monte Carlo noise their seed means keep.

Every condition but the control trains a **cue-blind twin** beside its network: the same
renders, seeds, crops and offsets, with the right view's residual shuffled within intensity
strata at every step (:func:`stereovar.probe.inputs.stratified_shuffle`): the noise law is the
same, only the cross-view alignment is missing.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..errors import ConfigError
from ..layout import NONE, is_audit
from ..mitigations import MitigationRun, resolve_mitigation

__all__ = [
    "ARCHITECTURES",
    "CONTROL",
    "MAIN",
    "TWIN",
    "ProbeCondition",
    "check_probe",
    "default_conditions",
    "planted_factor",
    "planted_name",
    "probe_conditions",
    "probe_mitigations",
    "probe_runs",
    "shippable",
    "shipped_mitigation",
    "shipped_name",
    "ships_one_seed_mean",
]

CONTROL = "sensor_only"
"""The second control training condition: clean images plus camera noise."""
MAIN = "main"
"""The network of a condition."""
TWIN = "twin"
"""Its cue-blind twin."""
ARCHITECTURES = ("mccnn", "costvolume")
"""The probe's networks: MC-CNN fast (:mod:`~stereovar.probe.network`) and a small end-to-end
cost-volume network (:mod:`~stereovar.probe.costvolume`)."""

DEFAULT_MITIGATIONS = ("denoise",)
"""The mitigation the default probe judges: the denoiser, which teams ship and which leaves
a Monte Carlo-specific cue in the data (docs/mitigations.md). ``sensor_only``, which the
dose-response names as the remedy, builds its images from a seed mean: judged, it trains as
shipped (:func:`shipped_name`), which needs :data:`SHIPPED_GROUP` times the probe's
renders per view."""

SHIPPED_SUFFIX = "_shipped"
"""Suffix of the condition that trains a seed-mean mitigation on what it ships."""

SHIPPED_GROUP = 2
"""Seeds per shipped image: each group's seed mean carries :math:`\\sigma^2/2` of Monte
Carlo noise, :math:`N/2` times what an image built from all :math:`N` seeds ships."""

_PLANTED = re.compile(r"^planted_x(?P<factor>[0-9]+(?:\.[0-9]+)?)$")


def planted_name(factor: float) -> str:
    """The condition name of a planted cue at ``factor`` times the renders' strength.

    Examples
    --------
    >>> planted_name(1.0), planted_name(0.5)
    ('planted_x1', 'planted_x0.5')
    """
    return f"planted_x{float(factor):g}"


@dataclass(frozen=True)
class ProbeCondition:
    """One training condition: its ``name``, the :class:`~stereovar.mitigations.MitigationRun`
    whose renders it reads (``none``'s for a planted cue), the planted ``factor`` (None for a
    mitigation), whether it trains a cue-blind ``twin`` (every condition but the control: a
    judged ``sensor_only`` trains as shipped instead), the ``architectures`` that
    train it (None: every one of ``probe.architectures``) and, for a seed-mean mitigation
    trained on what it ships (reading ``none``'s renders), its transform ``shipped``."""

    name: str
    run: MitigationRun
    factor: float | None = None
    twinned: bool | None = None
    architectures: tuple[str, ...] | None = None
    shipped: str | None = None

    @property
    def twin(self) -> bool:
        return self.name != CONTROL if self.twinned is None else bool(self.twinned)

    def trains(self, arch: str) -> bool:
        """Whether networks of architecture ``arch`` train on this condition."""
        return self.architectures is None or arch in self.architectures

    @property
    def variants(self) -> tuple[str, ...]:
        return (MAIN, TWIN) if self.twin else (MAIN,)

    @property
    def planted(self) -> bool:
        return self.factor is not None


def default_conditions(config: dict) -> list[str]:
    """``probe.conditions`` when it is null: ``none``, the control and every mitigation of
    ``mitigations.names`` (an audit: ``audit.mitigations``) but ``spp_xK``, which would render
    every scene again at K x SPP.

    Examples
    --------
    >>> default_conditions({"mitigations": {"names": ["spp_x4", "denoise"]}})
    ['none', 'sensor_only', 'denoise']
    """
    audit = config.get("audit")
    names = audit.get("mitigations", []) if audit else config["mitigations"]["names"]
    names = [n for n in names if resolve_mitigation(n).kind != "spp"]
    return list(dict.fromkeys([NONE, CONTROL, *names]))


def probe_runs(config: dict) -> list[MitigationRun]:
    """One :class:`~stereovar.mitigations.MitigationRun` per mitigation condition, the control
    included, on every scene of the run (or frame of the audit) at the condition's SPP.

    Raises
    ------
    ConfigError
        An unknown condition; an audit asked for one that renders (``shared_seed``,
        ``spp_xK``): an audit's renders are given.
    """
    probe = config.get("probe", {})
    listed = probe.get("conditions") or default_conditions(config)
    judged = [m for m in probe_mitigations(config) if not shippable(m)]  # else: shipped
    names = list(dict.fromkeys([NONE, CONTROL, *listed, *judged]))
    render = config["render"]
    source = render["renderer"]
    runs = []
    for name in names:
        try:
            m = resolve_mitigation(name)
        except ConfigError as err:
            raise ConfigError(
                str(err).replace("'mitigations.names'", f"'{_key_of(name, listed)}'")
            ) from None
        if is_audit(source) and m.kind not in ("baseline", "transform"):
            raise ConfigError(
                f"config key '{_key_of(name, listed)}': {name!r} renders the scenes anew, and an "
                "audit's renders are given; use store transforms only"
            )
        spp = int(render["spp"]) * m.spp_factor
        runs.append(MitigationRun(m, source, spp, tuple(config["scenes"])))
    return runs


def _key_of(name: str, listed) -> str:
    """The config key that asked for condition ``name``."""
    return "probe.conditions" if name in listed else "probe.mitigations"


def probe_conditions(config: dict) -> list[ProbeCondition]:
    """Every training condition of the probe: the mitigation conditions of :func:`probe_runs`,
    then one planted cue per factor of ``probe.planted`` (read from ``none``'s renders, for
    every architecture) and of ``probe.planted_series`` (an architecture's own dose-response:
    trained by that architecture only).

    Raises
    ------
    ConfigError
        As :func:`probe_runs`; a planted factor that is not positive.

    Examples
    --------
    >>> cfg = {"render": {"renderer": "mitsuba", "spp": 8}, "scenes": ["a", "b"],
    ...        "mitigations": {"names": []},
    ...        "probe": {"planted": [1], "planted_series": {"costvolume": [1, 4]},
    ...                  "mitigations": ["sensor_only"]}}
    >>> [(c.name, c.factor, c.variants, c.architectures) for c in probe_conditions(cfg)]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('none', None, ('main', 'twin'), None), ('sensor_only', None, ('main',), None),
     ('sensor_only_shipped', None, ('main', 'twin'), None),
     ('planted_x1', 1.0, ('main', 'twin'), None),
     ('planted_x4', 4.0, ('main', 'twin'), ('costvolume',))]

    ``sensor_only`` builds its images from the seed mean: judged, it trains as shipped
    (``sensor_only_shipped``, from ``none``'s renders), and the control stays as it is.

    A mitigation that does not read the seed mean trains as the workflow makes it, with its
    twin; the control then trains without one:

    >>> cfg["probe"]["mitigations"] = ["denoise"]
    >>> [(c.name, c.variants) for c in probe_conditions(cfg)][:3]
    [('none', ('main', 'twin')), ('sensor_only', ('main',)), ('denoise', ('main', 'twin'))]
    """
    runs = probe_runs(config)
    judged = probe_mitigations(config)
    twinned = {m for m in judged if not shippable(m)}
    out = [ProbeCondition(run.name, run, twinned=run.name != CONTROL or run.name in twinned)
           for run in runs]
    none = runs[0]
    out += [ProbeCondition(shipped_name(m), none, shipped=m) for m in judged if shippable(m)]
    probe = config.get("probe", {})
    everyone = [float(f) for f in probe.get("planted") or []]
    series = {str(a): [float(f) for f in fs] for a, fs in
              (probe.get("planted_series") or {}).items()}
    archs = tuple(probe.get("architectures") or ARCHITECTURES)
    for arch in series:
        if arch not in ARCHITECTURES:
            raise ConfigError(
                f"config key 'probe.planted_series': {arch!r} is no probe architecture; use "
                + " or ".join(ARCHITECTURES)
            )
    for factor in dict.fromkeys([*everyone, *(f for fs in series.values() for f in fs)]):
        if not factor > 0:
            key = "probe.planted" if factor in everyone else "probe.planted_series"
            raise ConfigError(
                f"config key {key!r}: {factor!r} is not a positive multiple of the "
                "renders' strength; list factors above 0 (strength 0 is the 'none' condition)"
            )
        trained = None if factor in everyone else tuple(
            a for a in archs if factor in series.get(a, ()))
        if trained == ():
            continue  # a series of an architecture the probe does not train
        out.append(ProbeCondition(planted_name(factor), none, factor, architectures=trained))
    return list({c.name: c for c in out}.values())


def probe_mitigations(config: dict) -> list[str]:
    """``probe.mitigations``: the mitigations whose networks the verdict judges against
    ``none`` (each trains with its own cue-blind twin; one built from the seed mean, the
    control ``sensor_only`` too, as shipped: :func:`shipped_name`), :data:`DEFAULT_MITIGATIONS`
    when the key is absent.

    Examples
    --------
    >>> probe_mitigations({"probe": {}}), probe_mitigations({"probe": {"mitigations": []}})
    (['denoise'], [])
    """
    names = config.get("probe", {}).get("mitigations")
    names = list(DEFAULT_MITIGATIONS) if names is None else list(names)
    for name in names:
        if name == NONE:
            raise ConfigError(
                "config key 'probe.mitigations': 'none' is the baseline every mitigation is "
                "judged against; list mitigations only (sensor_only, denoise, ...)"
            )
    return list(dict.fromkeys(names))


def check_probe(config: dict, n_seeds: int) -> None:
    """The probe's settings that fail before any work, in one line: too few renders per view
    (:func:`stereovar.probe.experiment.check_renders`) and ``probe.device: cuda`` where
    PyTorch sees no GPU (imports PyTorch only then)."""
    from .experiment import MIN_RENDERS

    if int(n_seeds) < MIN_RENDERS:
        from .experiment import check_renders

        check_renders(n_seeds, "render.n_seeds (renders per view)")
    shipped = [m for m in probe_mitigations(config) if shippable(m)]
    if shipped and int(n_seeds) // SHIPPED_GROUP < MIN_RENDERS:
        raise ConfigError(
            f"config key 'probe.mitigations': judging {', '.join(shipped)} (built from the "
            f"seed mean) needs {SHIPPED_GROUP * MIN_RENDERS} renders per view, "
            f"{MIN_RENDERS} shipped images of {SHIPPED_GROUP} seeds each, and there are "
            f"{int(n_seeds)}; raise render.n_seeds (audit: give more seeds) or remove "
            f"{', '.join(shipped)} from probe.mitigations"
        )
    device = str(config.get("probe", {}).get("device", "cpu"))
    if device.startswith("cuda"):
        import torch

        if not torch.cuda.is_available():
            raise ConfigError(
                f"config key 'probe.device' is {device!r}, but PyTorch sees no CUDA GPU here "
                f"(torch {torch.__version__}); set probe.device: cpu, or run on a machine "
                "with a GPU and a CUDA build of PyTorch"
            )


def ships_one_seed_mean(name: str) -> bool:
    """Whether mitigation ``name`` builds every image of a scene from the one seed mean of its
    renders (``sensor_only``, ``equalise``): the Monte Carlo noise left in that mean is in
    every image and in the reference mean of the probe's counterfactuals, so the residual
    shuffle reaches only the per-image noise added to it, and the probe cannot measure a
    reliance on what remains of the cue.

    Examples
    --------
    >>> ships_one_seed_mean("sensor_only"), ships_one_seed_mean("denoise")
    (True, False)
    >>> ships_one_seed_mean("none"), ships_one_seed_mean("planted_x2")
    (False, False)
    """
    from ..transforms import TRANSFORMS, transform_chain

    parts = str(name).split("+")
    if not all(p in TRANSFORMS.names() for p in parts):
        return False  # none, a seed policy, spp_xK, a planted cue
    return any({"seed_mean", "seed_var"} & set(t.reads) for t in transform_chain(name))


def shippable(name: str) -> bool:
    """Whether mitigation ``name`` builds its images from the seed mean and reads nothing
    but the renders (no albedo or normal pass), so the probe can build what it ships from
    ``none``'s renders in its own jobs (:func:`shipped_name`).

    Examples
    --------
    >>> shippable("sensor_only"), shippable("equalise"), shippable("denoise")
    (True, True, False)
    """
    from ..transforms import transform_chain

    return ships_one_seed_mean(name) and not any(
        t.optional_reads for t in transform_chain(name))


def shipped_name(name: str) -> str:
    """The condition that trains mitigation ``name`` on what it ships.

    Examples
    --------
    >>> shipped_name("sensor_only")
    'sensor_only_shipped'
    """
    return f"{name}{SHIPPED_SUFFIX}"


def shipped_mitigation(name: str) -> str | None:
    """The mitigation a shipped condition trains on, None for any other condition.

    Examples
    --------
    >>> shipped_mitigation("sensor_only_shipped"), shipped_mitigation("sensor_only")
    ('sensor_only', None)
    """
    name = str(name)
    return name[: -len(SHIPPED_SUFFIX)] if name.endswith(SHIPPED_SUFFIX) else None


def planted_factor(name: str) -> float | None:
    """The factor of a planted condition's name, None for any other name.

    Examples
    --------
    >>> planted_factor("planted_x0.5"), planted_factor("none")
    (0.5, None)
    """
    match = _PLANTED.match(str(name))
    return float(match["factor"]) if match else None
