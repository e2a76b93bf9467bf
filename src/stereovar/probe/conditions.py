"""The probe's training conditions: which renders each network family trains and is tested on.

A condition is either a mitigation (:mod:`stereovar.mitigations`), read from its source key at
its SPP on every probe scene: ``none`` (the renders as they are, independent seeds), the
control ``sensor_only`` (seed mean plus camera noise, no Monte Carlo structure) and any other
mitigation (``spp_xK`` renders every probe scene at K x SPP); or the **planted** positive
control ``planted_x{f}``: the renders' seed mean with camera-law noise whose variance carries a
cross-view pattern of ``f`` times the strength the renders show (the calibration's planted
design, :mod:`stereovar.probe.planted`), so its answer is known.

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
    "probe_runs",
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
    mitigation) and whether it trains a cue-blind ``twin``."""

    name: str
    run: MitigationRun
    factor: float | None = None

    @property
    def twin(self) -> bool:
        return self.name != CONTROL

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
    names = probe.get("conditions") or default_conditions(config)
    names = list(dict.fromkeys([NONE, CONTROL, *names]))
    render = config["render"]
    source = render["renderer"]
    runs = []
    for name in names:
        try:
            m = resolve_mitigation(name)
        except ConfigError as err:
            raise ConfigError(
                str(err).replace("'mitigations.names'", "'probe.conditions'")
            ) from None
        if is_audit(source) and m.kind not in ("baseline", "transform"):
            raise ConfigError(
                f"config key 'probe.conditions': {name!r} renders the scenes anew, and an "
                "audit's renders are given; use store transforms only"
            )
        spp = int(render["spp"]) * m.spp_factor
        runs.append(MitigationRun(m, source, spp, tuple(config["scenes"])))
    return runs


def probe_conditions(config: dict) -> list[ProbeCondition]:
    """Every training condition of the probe: the mitigation conditions of :func:`probe_runs`,
    then one planted cue per factor of ``probe.planted`` (read from ``none``'s renders).

    Raises
    ------
    ConfigError
        As :func:`probe_runs`; a planted factor that is not positive.

    Examples
    --------
    >>> cfg = {"render": {"renderer": "mitsuba", "spp": 8}, "scenes": ["a", "b"],
    ...        "mitigations": {"names": []}, "probe": {"planted": [1, 4]}}
    >>> [(c.name, c.run.name, c.factor, c.variants) for c in probe_conditions(cfg)]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('none', 'none', None, ('main', 'twin')), ('sensor_only', 'sensor_only', None, ('main',)),
     ('planted_x1', 'none', 1.0, ('main', 'twin')), ('planted_x4', 'none', 4.0, ('main', 'twin'))]
    """
    runs = probe_runs(config)
    out = [ProbeCondition(run.name, run) for run in runs]
    none = runs[0]
    for factor in config.get("probe", {}).get("planted") or []:
        if not float(factor) > 0:
            raise ConfigError(
                f"config key 'probe.planted': {factor!r} is not a positive multiple of the "
                "renders' strength; list factors above 0 (strength 0 is the 'none' condition)"
            )
        out.append(ProbeCondition(planted_name(factor), none, float(factor)))
    return list({c.name: c for c in out}.values())


def check_probe(config: dict, n_seeds: int) -> None:
    """The probe's settings that fail before any work, in one line: too few renders per view
    (:func:`stereovar.probe.experiment.check_renders`) and ``probe.device: cuda`` where
    PyTorch sees no GPU (imports PyTorch only then)."""
    from .experiment import MIN_RENDERS

    if int(n_seeds) < MIN_RENDERS:
        from .experiment import check_renders

        check_renders(n_seeds, "render.n_seeds (renders per view)")
    device = str(config.get("probe", {}).get("device", "cpu"))
    if device.startswith("cuda"):
        import torch

        if not torch.cuda.is_available():
            raise ConfigError(
                f"config key 'probe.device' is {device!r}, but PyTorch sees no CUDA GPU here "
                f"(torch {torch.__version__}); set probe.device: cpu, or run on a machine "
                "with a GPU and a CUDA build of PyTorch"
            )


def planted_factor(name: str) -> float | None:
    """The factor of a planted condition's name, None for any other name.

    Examples
    --------
    >>> planted_factor("planted_x0.5"), planted_factor("none")
    (0.5, None)
    """
    match = _PLANTED.match(str(name))
    return float(match["factor"]) if match else None
