"""The registered :class:`~stereovar.transforms.base.Transform` objects.

Importing this module imports the camera model (numpy) but not pyoidn, which
:mod:`stereovar.transforms.denoise` imports on first use.
"""

from __future__ import annotations

from .base import Transform
from .denoise import apply_denoise
from .sensor import apply_denoise_sensor, apply_equalise, apply_sensor_only

DENOISE = Transform(
    name="denoise",
    description="OIDN denoiser on each render (albedo and normal when given), as BlenderProc",
    apply=apply_denoise,
    optional_reads=("albedo", "normal"),
    expensive=True,
)
DENOISE_SENSOR = Transform(
    name="denoise_sensor",
    description="OIDN denoiser, then Poisson-Gaussian camera noise",
    apply=apply_denoise_sensor,
    optional_reads=("albedo", "normal"),
    random=True,
    expensive=True,
)
EQUALISE = Transform(
    name="equalise",
    description="residual from the seed mean rescaled to the camera variance a*mu + b",
    apply=apply_equalise,
    reads=("seed_mean", "seed_var"),
)
SENSOR_ONLY = Transform(
    name="sensor_only",
    description="seed mean plus Poisson-Gaussian camera noise (what a camera would give)",
    apply=apply_sensor_only,
    reads=("seed_mean",),
    random=True,
)
