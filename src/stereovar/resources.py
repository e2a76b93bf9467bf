"""Memory and runtime requests of the workflow's jobs, from the size of each job.

A cluster scheduler needs every job's memory (``mem_mb``) and wall time (``runtime``, in
minutes) up front. These functions derive them from what the job does: the resolution, the
samples per pixel and the number of renders, seeds or disparities. Each request grows with
the retry ``attempt`` (1, 2, ...), so a job killed for exceeding it is resubmitted with more.
The constants are measured on the default and paper configurations (docs/performance.md).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import NamedTuple

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


CALIBRATION_SECONDS_PER_PIXEL = 0.5e-6
"""Seconds per pixel of one synthetic image through a cheap transform and the statistics
(measured about 0.2 us at 320x180, N = 8, on one core; twice that for a loaded node)."""

DENOISE_SECONDS_PER_PIXEL = 5e-6
"""Seconds per pixel of one OIDN image on one thread (measured 0.17-0.37 s at 320x180)."""


def calibration_runtime(
    width: int,
    height: int,
    n_seeds: int,
    *,
    replicates: int,
    designs: int,
    transforms: int,
    denoised_replicates: int = 0,
    denoisers: int = 0,
    pipeline_replicates: int = 0,
    pipeline_designs: int = 0,
    attempt=1,
) -> int:
    """Wall-time request (minutes) of one scene's calibration: every replicate draws
    :math:`2N` images per design and transform (plus :math:`N/2` for what a seed-mean
    transform ships) and measures them; each denoiser sees 3 designs in
    ``denoised_replicates`` replicates at OIDN's cost per image; the pipeline nulls
    (``pipeline_designs``, with the 8-bit ones' encoded nulls) are measured untransformed
    ``pipeline_replicates`` times each.

    .. math::

        t = 30 + WH\\,\\bigl(c\\, (R\\, D\\, T + R_p D_p) \\cdot 2.5 N
            + c_{\\text{OIDN}}\\, R_d \\cdot 3 \\cdot T_d \\cdot 2N\\bigr)
    """
    pixels = int(width) * int(height)
    cheap = CALIBRATION_SECONDS_PER_PIXEL * (
        replicates * designs * transforms + pipeline_replicates * pipeline_designs
    ) * 2.5 * n_seeds
    denoise = DENOISE_SECONDS_PER_PIXEL * denoised_replicates * 3 * denoisers * 2 * n_seeds
    return _minutes(30.0 + pixels * (cheap + denoise), attempt)


def intervention_runtime(
    width: int, height: int, n_seeds: int, n_disparities: int, *, attempt=1
) -> int:
    """Wall-time request (minutes) of the intervention of one scene: :math:`2N + 4` scans of
    ``n_disparities`` slices at about 20 ns per pixel and slice (measured 23.7 s for
    1280x720, N = 30, 31 disparities on 2 cores), plus reading the renders twice."""
    scans = 2 * n_seeds + 4
    seconds = 30.0 + 20e-9 * scans * n_disparities * width * height
    return _minutes(seconds + 0.2 * n_seeds * width * height / 1e6, attempt)


ANALYSIS_IMAGES_MAX = 24
"""Most images one analysis job holds at once: the intervention and the estimator check
(:func:`stereovar.workflow_inputs.resources.intervention_resources`, ``estimators.smk``)."""


def job_mem_requests(config) -> dict[str, int]:
    """First-attempt memory request (MB) of each kind of job a validated config runs.

    ``render``: a render job of the largest seed batch (``render.seeds_per_job`` seeds,
    at most the most seeds any run renders); ``moments``: a moments render job;
    ``analysis``: an analysis job holding :data:`ANALYSIS_IMAGES_MAX` images. An audit
    renders nothing, so it has only ``analysis``.
    """
    width, height = int(config["resolution"]["width"]), int(config["resolution"]["height"])
    requests = {"analysis": analysis_mem_mb(width, height, ANALYSIS_IMAGES_MAX)}
    if config.get("audit"):
        return requests
    render = config["render"]
    seeds = max(render["n_seeds"], (config.get("intervention") or {}).get("n_seeds") or 0)
    batch = min(render["seeds_per_job"], seeds)
    requests["render"] = render_mem_mb(width, height, batch=batch)
    requests["moments"] = moments_mem_mb(width, height)
    return requests


def machine_mem_mb() -> int:
    """Memory of this machine in MB (10^6 bytes, Snakemake's ``mem_mb`` unit): the physical
    memory, or the container's cgroup limit when that is lower."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
    except OSError:
        limit = "max"
    if limit.isdigit():
        total = min(total, int(limit))
    return total // 10**6


MACHINE = "this machine's memory"


def memory_limit(config, *, global_mem_mb=None, machine_mb=None) -> tuple[int, str]:
    """The most memory (MB) one job of this run may request, and where that bound comes
    from, in words.

    ``cluster.max_mem_mb`` when set (a cluster node's memory), else this machine's memory
    (``machine_mb``, :func:`machine_mem_mb` by default); lowered to ``global_mem_mb``, the
    run's ``--resources mem_mb`` (also from a profile's ``resources:``), which caps the
    memory of the jobs running at once and so of any one job.
    """
    cap = (config.get("cluster") or {}).get("max_mem_mb")
    if cap is not None:
        limit, source = int(cap), "cluster.max_mem_mb"
    else:
        limit = machine_mem_mb() if machine_mb is None else int(machine_mb)
        source = MACHINE
    if global_mem_mb is not None and int(global_mem_mb) < limit:
        limit, source = int(global_mem_mb), "--resources mem_mb"
    return limit, source


def largest_fitting_size(config, limit_mb: int) -> tuple[int, int] | None:
    """The largest image size with the config's aspect ratio whose jobs all request at most
    ``limit_mb`` (:func:`job_mem_requests`), or None when not even 1x1 fits."""
    width, height = int(config["resolution"]["width"]), int(config["resolution"]["height"])

    def fits(scale: float) -> bool:
        size = {"width": max(1, int(width * scale)), "height": max(1, int(height * scale))}
        return max(job_mem_requests({**config, "resolution": size}).values()) <= limit_mb

    lo, hi = 0.0, 1.0
    if not fits(lo):
        return None
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return max(1, int(width * lo)), max(1, int(height * lo))


class MemoryExcess(NamedTuple):
    """The job of a config that requests more memory than one job may use
    (:func:`memory_excess`)."""

    job: str
    """Its kind (:func:`job_mem_requests`)."""
    request: int
    """Its first-attempt request, MB."""
    fitting: tuple[int, int] | None
    """The largest image size (width, height) of the config's aspect ratio whose jobs all
    fit (:func:`largest_fitting_size`); None when none does."""
    smallest: int
    """The most memory (MB) a job requests at 1x1: the least the bound must be."""


def memory_excess(config, limit_mb: int) -> MemoryExcess | None:
    """The job of ``config`` that requests the most memory, when that is more than
    ``limit_mb``.

    Parameters
    ----------
    config : dict
        A validated config (``resolution``, ``render``, ...).
    limit_mb : int
        The most memory (MB) one job may request (:func:`memory_limit`).

    Returns
    -------
    MemoryExcess or None
        None when every job fits; else the largest job, its request, the largest size that
        fits and the least bound any size needs.
    """
    requests = job_mem_requests(config)
    job, request = max(requests.items(), key=lambda item: item[1])
    if request <= limit_mb:
        return None
    tiny = {**config, "resolution": {"width": 1, "height": 1}}
    smallest = max(job_mem_requests(tiny).values())
    return MemoryExcess(job, request, largest_fitting_size(config, limit_mb), smallest)


def raise_bound(source: str, at_least_mb: int) -> str:
    """How to lift the bound ``source`` (:func:`memory_limit`) to ``at_least_mb`` MB: a
    machine with that much memory, or the setting raised.

    Parameters
    ----------
    source : str
        Where the bound comes from: :data:`MACHINE`, ``cluster.max_mem_mb`` or
        ``--resources mem_mb``.
    at_least_mb : int
        The bound needed, MB.

    Returns
    -------
    str
        The fix, in words.
    """
    if source == MACHINE:
        return (
            f"run on a machine with at least {at_least_mb:,} MB of memory (on a cluster, set "
            "cluster.max_mem_mb to the memory of its largest node)"
        )
    return f"raise {source} to at least {at_least_mb:,} MB"


def check_job_memory(config, limit_mb: int, source: str) -> None:
    """Refuse a config whose largest job would request more memory than ``limit_mb``.

    Raises
    ------
    ConfigError
        One line with the job, its request, the bound and where it comes from, and the
        largest resolution of the same aspect ratio that fits, or, when none does, how to
        raise the bound (:func:`raise_bound`).
    """
    from .errors import ConfigError

    excess = memory_excess(config, limit_mb)
    if excess is None:
        return
    width, height = config["resolution"]["width"], config["resolution"]["height"]
    if excess.fitting is None:
        fix = f"no resolution fits; {raise_bound(source, excess.smallest)}"
    else:
        fix = f"use at most {excess.fitting[0]}x{excess.fitting[1]}"
        if source == MACHINE:
            fix += " (on a cluster, set cluster.max_mem_mb to the memory of its largest node)"
    raise ConfigError(
        f"config key 'resolution': {width}x{height} makes each {excess.job} job request "
        f"{excess.request:,} MB of memory, more than the {limit_mb:,} MB of {source}; {fix}"
    )
