"""Generator profiles: the Cycles settings that synthetic-data generators ship by default.

A team's question is rarely whether renders made the paper's way carry the cue, but whether
the data *its generator* makes does. Each profile is a preset,
``workflow/presets/generators/{name}.yaml``, that copies one generator's render defaults
(its samples per pixel and ``render.cycles``: adaptive sampling, the denoiser, multiview
stereo and the seed rule), citing the generator's source line by line. A preset is a config
file of its own (``--configfile workflow/presets/generators/kubric.yaml`` runs the whole
experiment under it), and the ``generators`` target renders ``generators.scenes`` under every
profile in ``generators.profiles`` at a common budget, beside the paper's own settings
(:data:`PAPER`), and measures each like a mitigation (:mod:`stereovar.mitigations`).

A profile whose SPP exceeds the budget is scaled down (:func:`budget_profile`). Adaptive
sampling stops a pixel once its estimated error falls below the threshold; the error of a
pixel falls as :math:`1/\\sqrt{\\mathrm{spp}}`, so at :math:`k` times fewer samples the
threshold is raised :math:`\\sqrt{k}` times and the minimum sample count lowered :math:`k`
times, which keeps the share of the budget at which each pixel stops.

Importing this module pulls in no third-party package but ``yaml``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from .errors import ConfigError

__all__ = [
    "OUTPUTS",
    "PAPER",
    "PROFILES",
    "GeneratorProfile",
    "budget_profile",
    "load_profile",
    "profile_path",
]

PROFILES = ("kubric", "blenderproc", "infinigen")
"""The generator presets the workflow ships (``workflow/presets/generators/{name}.yaml``)."""

PAPER = "paper"
"""The row of the paper's own settings: Cycles with ``render.cycles`` at its defaults
(independent seeds per view, no adaptive sampling, no denoiser), the renders of source
``cycles`` itself."""

OUTPUTS = {
    "kubric": "png8_filmic",
    "blenderproc": "png8_filmic",
    "infinigen": "png8_agx",
}
"""What each generator ships its images as: the store transform
(:mod:`stereovar.transforms.output`) from its float render to the PNG a team trains on.

``kubric`` (google-research/kubric @ 0ee21e2): ``kubric/renderer/blender.py`` L292-294 renders
each frame with ``write_still`` to ``frame_%04d.png``, and L354 keeps that PNG as ``rgba``
("the contrast-normalized PNG instead of the EXR"); L368 starts from Blender's factory
settings and no line sets ``view_transform`` or ``color_depth``, so Blender's defaults
apply: PNG at 8 bits through the Filmic view transform of the Blender it builds
(``docker/Blender.Dockerfile`` L48, Blender 2.93).

``blenderproc`` (DLR-RM/BlenderProc @ a80f75d): ``blenderproc/python/utility/DefaultConfig.py``
L26-27 ``file_format = "PNG"``, ``color_depth = 8`` and L44 ``view_transform = "Filmic"``,
set by ``Initializer.py`` L167 (``set_output_format``) at ``bproc.init()``
(``RendererUtility.py`` L732-766); ``color_depth=16`` is its option (``png16_filmic``).

``infinigen`` (princeton-vl/infinigen @ 01c39c7): ``infinigen/core/rendering/render.py``
L160-177 writes the image through a PNG file output (RGB, Blender's default 8 bits) and an
OpenEXR one; no line sets ``view_transform``, so Blender 4.2's default (``pyproject.toml`` L27
``bpy==4.2.0``), AgX, makes the PNG. Its EXR is the float render, the profile's float row.
"""

PRESET_FOLDER = ("workflow", "presets", "generators")
"""Where the profiles sit, under the workflow's root
(:func:`stereovar.workflow_home.workflow_root`)."""


@dataclass(frozen=True)
class GeneratorProfile:
    """One generator's render defaults.

    Attributes
    ----------
    name : str
        The profile (a name in :data:`PROFILES`, or :data:`PAPER`).
    spp : int
        The samples per pixel it renders with.
    cycles : dict
        Its ``render.cycles`` options (the keys the preset sets; the rest take the
        defaults of :data:`stereovar.renderers.cycles.settings.CYCLES_DEFAULTS`).
    scale : float
        The budget SPP over the generator's own (1 when not scaled).
    """

    name: str
    spp: int
    cycles: dict = field(default_factory=dict)
    scale: float = 1.0

    @property
    def seed_rule(self) -> str:
        """How the views' seeds relate: ``multiview`` (both eyes in one render, one seed),
        else ``render.cycles.seed`` (``per_view``, ``unset`` or ``animated``)."""
        if self.cycles.get("multiview"):
            return "multiview"
        return str(self.cycles.get("seed", "per_view"))

    @property
    def seed_policy(self) -> str:
        """The seed policy its renders take (:data:`stereovar.seeding.SEED_POLICIES`): one
        seed for both views of a render unless every view gets its own."""
        return "independent" if self.seed_rule == "per_view" else "shared"

    @property
    def denoiser(self) -> str:
        """``off``, or where the denoiser runs (``render``, ``compositor``)."""
        if not self.cycles.get("denoise"):
            return "off"
        return str(self.cycles.get("denoiser", "render"))

    @property
    def adaptive(self) -> str:
        """``off``, or the threshold and minimum samples of adaptive sampling."""
        if not self.cycles.get("adaptive_sampling"):
            return "off"
        threshold = float(self.cycles.get("adaptive_threshold", 0.01))
        minimum = int(self.cycles.get("adaptive_min_samples", 0))
        return f"threshold {threshold:.3g}, min {minimum or 'auto'}"


def profile_path(name: str, root: Path | None = None) -> Path:
    """The preset of profile ``name``: ``workflow/presets/generators/{name}.yaml``."""
    from .workflow_home import workflow_root

    return Path(root or workflow_root()).joinpath(*PRESET_FOLDER, f"{name}.yaml")


def load_profile(name: str, root: Path | None = None) -> GeneratorProfile:
    """The profile ``name`` read from its preset (``render.spp`` and ``render.cycles``).

    Raises
    ------
    ConfigError
        ``name`` has no preset, or the preset is no Cycles profile; one line naming the
        choices or the key.
    """
    import yaml

    name = str(name)
    path = profile_path(name, root)
    if not path.is_file():
        raise ConfigError(
            f"config key 'generators.profiles': no generator profile {name!r}; use any of: "
            + ", ".join(PROFILES)
        )
    data = yaml.safe_load(path.read_text()) or {}
    render = data.get("render") or {}
    if render.get("renderer") != "cycles" or "spp" not in render:
        raise ConfigError(
            f"{path}: a generator profile sets render.renderer: cycles and render.spp"
        )
    return GeneratorProfile(name, int(render["spp"]), dict(render.get("cycles") or {}))


def automatic_min_samples(threshold: float) -> int:
    """Cycles' minimum samples of adaptive sampling when ``adaptive_min_samples`` is 0.

    .. math:: n_\\min = \\max\\!\\left(4,\\ \\left\\lceil 16 / \\tau^{0.3} \\right\\rceil\\right)

    (Cycles' ``Integrator::get_adaptive_sampling``, ``intern/cycles/scene/integrator.cpp``:
    "Threshold 0.1 -> 32, 0.01 -> 64, 0.001 -> 128").

    Examples
    --------
    >>> automatic_min_samples(0.01), automatic_min_samples(0.005)
    (64, 79)
    """
    threshold = float(threshold)
    if threshold <= 0:
        raise ValueError(f"an adaptive threshold is above 0, got {threshold}")
    return max(4, math.ceil(16.0 / threshold**0.3))


def budget_profile(profile: GeneratorProfile, budget_spp: int) -> GeneratorProfile:
    """``profile`` at no more than ``budget_spp`` samples per pixel.

    A profile within the budget is returned unchanged. Above it, the SPP becomes
    ``budget_spp`` (:math:`k = \\mathrm{spp} / \\mathrm{budget}`) and adaptive sampling
    keeps the share of the budget at which each pixel stops: the error estimate falls as
    :math:`1/\\sqrt{n}`, so

    .. math:: \\tau' = \\tau \\sqrt{k}, \\qquad n_\\min' = \\max(1, \\lfloor n_\\min / k \\rceil)

    with :math:`n_\\min` Cycles' automatic minimum where the preset leaves it at 0
    (:func:`automatic_min_samples`).

    Examples
    --------
    >>> p = GeneratorProfile("x", 1024, {"adaptive_sampling": True, "adaptive_threshold": 0.01,
    ...                                  "adaptive_min_samples": 256})
    >>> q = budget_profile(p, 64)
    >>> q.spp, q.scale, q.cycles["adaptive_threshold"], q.cycles["adaptive_min_samples"]
    (64, 0.0625, 0.04, 16)
    """
    budget = int(budget_spp)
    if budget < 1:
        raise ConfigError(f"config key 'generators.spp': {budget} is below 1; use 1 or more")
    if profile.spp <= budget:
        return profile
    k = profile.spp / budget
    cycles = dict(profile.cycles)
    if cycles.get("adaptive_sampling"):
        threshold = float(cycles.get("adaptive_threshold", 0.01))
        minimum = int(cycles.get("adaptive_min_samples", 0)) or automatic_min_samples(threshold)
        cycles["adaptive_threshold"] = round(threshold * math.sqrt(k), 6)
        cycles["adaptive_min_samples"] = max(1, round(minimum / k))
    return GeneratorProfile(profile.name, budget, cycles, scale=budget / profile.spp)


def generator_profiles(config: dict, root: Path | None = None) -> list[GeneratorProfile]:
    """The rows of the generator table: :data:`PAPER` first (the renders of ``cycles`` at
    the budget), then each of ``generators.profiles`` at the budget
    (:func:`budget_profile`)."""
    gen = config["generators"]
    budget = int(gen["spp"])
    rows = [GeneratorProfile(PAPER, budget, {})]
    for name in dict.fromkeys(gen["profiles"]):
        if name == PAPER:
            continue
        rows.append(budget_profile(load_profile(name, root), budget))
    return rows
