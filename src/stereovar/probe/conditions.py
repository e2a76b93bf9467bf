"""The probe's training conditions: which renders each network family trains and is tested on.

A condition is a mitigation (:mod:`stereovar.mitigations`): ``none`` (the renders as they
are, independent seeds), the control ``sensor_only`` (seed mean plus camera noise, no Monte
Carlo structure) and any other mitigation, each read from its source key at its SPP on every
probe scene. ``spp_xK`` renders every probe scene at K x SPP.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

from ..errors import ConfigError
from ..layout import NONE, is_audit
from ..mitigations import MitigationRun, resolve_mitigation
from .metrics import CONTROL

__all__ = ["default_conditions", "probe_runs"]


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
    """One :class:`~stereovar.mitigations.MitigationRun` per training condition, the control
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
