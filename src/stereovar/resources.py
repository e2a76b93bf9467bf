"""Memory and runtime requests of the workflow's jobs, from the size of each job.

A cluster scheduler needs every job's memory (``mem_mb``) and wall time (``runtime``, in
minutes) up front. These functions derive them from what the job does: the resolution, the
samples per pixel and the number of renders, seeds or disparities. Each request grows with
the retry ``attempt`` (1, 2, ...), so a job killed for exceeding it is resubmitted with more.
The constants are measured on the default and paper configurations (see the README).
"""

from __future__ import annotations

import math

MIB = 2**20

RENDER_BASE_MB = 1536
"""Resident memory of a render process before its images: Python, Mitsuba, the compiled
scene and Dr.Jit's buffers (measured 0.66-0.70 GB on llvm_ad_rgb at 320x180 to 1280x720)."""

ANALYSIS_BASE_MB = 1024
"""Resident memory of an analysis process (Python, numpy, xarray, zarr)."""

STARTUP_S = 120.0
"""Process start-up and scene compilation, charged once per job."""

SAFETY = 2.0
"""Factor between the expected and the requested wall time on the first attempt."""


def _minutes(seconds: float, attempt: int) -> int:
    return max(1, math.ceil(SAFETY * attempt * seconds / 60.0))


def render_samples(width: int, height: int, spp: int, n_renders: int) -> int:
    """Path samples of ``n_renders`` images: :math:`W H \\cdot \\mathrm{SPP} \\cdot n`."""
    return int(width) * int(height) * int(spp) * int(n_renders)


def render_runtime(
    width: int, height: int, spp: int, n_renders: int, *, samples_per_second: float, attempt=1
) -> int:
    """Wall-time request (minutes) of a render job.

    .. math::

        t = \\lceil s \\cdot a \\cdot (t_0 + W H \\cdot \\mathrm{SPP} \\cdot n / r) / 60 \\rceil

    with :math:`r` the expected path samples per second of one job, :math:`t_0` the start-up
    (:data:`STARTUP_S`), :math:`s` the safety factor (:data:`SAFETY`) and :math:`a` the attempt.
    """
    if samples_per_second <= 0:
        raise ValueError(f"samples_per_second must be > 0, got {samples_per_second}")
    samples = render_samples(width, height, spp, n_renders)
    return _minutes(STARTUP_S + samples / samples_per_second, attempt)


def render_mem_mb(width: int, height: int, *, batch: int = 1, attempt=1) -> int:
    """Memory request (MB) of a render job: the base process plus 64 bytes per pixel (film,
    the float32 RGB image, its float64 statistics and the store being written) plus, for a
    batch of ``batch`` seeds of one view held until its store is written, 24 bytes per pixel
    and seed (the float32 RGB renders and their stacked copy), times the attempt."""
    per_pixel = 64 + 24 * max(int(batch) - 1, 0)
    return int(attempt) * (RENDER_BASE_MB + math.ceil(per_pixel * width * height / MIB))


def moments_mem_mb(width: int, height: int, *, attempt=1) -> int:
    """Memory request (MB) of a ``moments`` render job (one view): the base process plus
    200 bytes per pixel (the film's 11 float32 channels and its developed copy, the two
    half renders' float32 moments and the store being written), times the attempt."""
    return int(attempt) * (RENDER_BASE_MB + math.ceil(200 * width * height / MIB))


def analysis_mem_mb(width: int, height: int, images: int, *, attempt=1) -> int:
    """Memory request (MB) of an analysis job that holds ``images`` float64 RGB images."""
    return int(attempt) * (ANALYSIS_BASE_MB + math.ceil(24 * images * width * height / MIB))


def analysis_runtime(width: int, height: int, n_reads: int, *, attempt=1) -> int:
    """Wall-time request (minutes) of a job that reads ``n_reads`` renders and does a few
    passes over each (variance, warp, correlation): 0.1 s per megapixel read, plus start-up."""
    return _minutes(30.0 + 0.1 * n_reads * width * height / 1e6, attempt)


def intervention_runtime(
    width: int, height: int, n_seeds: int, n_disparities: int, *, attempt=1
) -> int:
    """Wall-time request (minutes) of the intervention of one scene: :math:`2N + 4` scans of
    ``n_disparities`` slices at about 20 ns per pixel and slice (measured 23.7 s for
    1280x720, N = 30, 31 disparities on 2 cores), plus reading the renders twice."""
    scans = 2 * n_seeds + 4
    seconds = 30.0 + 20e-9 * scans * n_disparities * width * height
    return _minutes(seconds + 0.2 * n_seeds * width * height / 1e6, attempt)
