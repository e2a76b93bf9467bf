"""The registered :class:`~stereovar.transforms.base.Transform` objects.

Importing this module imports the camera model (numpy) but not pyoidn, which
:mod:`stereovar.transforms.denoise` imports on first use.
"""

from __future__ import annotations

from functools import partial

from .base import Transform
from .denoise import apply_denoise
from .output import apply_view_png, output_encoding
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
PNG8_FILMIC = Transform(
    name="png8_filmic",
    description="Blender's Filmic view transform and 8-bit PNG, as Kubric and BlenderProc write",
    apply=partial(apply_view_png, view_transform="Filmic", bits=8),
    encoding=output_encoding(8),
)
PNG16_FILMIC = Transform(
    name="png16_filmic",
    description="Blender's Filmic view transform and 16-bit PNG (BlenderProc's color_depth 16)",
    apply=partial(apply_view_png, view_transform="Filmic", bits=16),
    encoding=output_encoding(16),
)
PNG8_AGX = Transform(
    name="png8_agx",
    description="Blender's AgX view transform and 8-bit PNG, as Infinigen writes its PNG",
    apply=partial(apply_view_png, view_transform="AgX", bits=8),
    encoding=output_encoding(8),
)
