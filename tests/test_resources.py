"""Cluster requests sized from each job (stereovar.resources), against hand calculations."""

import math

import pytest

from stereovar import resources as sizing


def test_render_runtime_is_startup_plus_samples_over_rate_with_safety():
    # 1280x720 at SPP 512, 16 renders, 1e6 samples/s: 7.55e9 samples -> 7549.7 s + 120 s.
    expected = math.ceil(2.0 * (120 + 1280 * 720 * 512 * 16 / 1e6) / 60)
    assert sizing.render_runtime(1280, 720, 512, 16, samples_per_second=1e6) == expected
    # Retries ask for proportionally more, and a faster backend for less.
    assert sizing.render_runtime(1280, 720, 512, 16, samples_per_second=1e6, attempt=2) == (
        math.ceil(4.0 * (120 + 1280 * 720 * 512 * 16 / 1e6) / 60)
    )
    assert sizing.render_runtime(1280, 720, 512, 16, samples_per_second=1e8) < expected / 10


def test_small_jobs_still_get_a_minute_and_bad_rates_are_refused():
    assert 4 <= sizing.render_runtime(1, 1, 1, 1, samples_per_second=1e9) <= 5  # 2 x 120 s
    with pytest.raises(ValueError, match="samples_per_second"):
        sizing.render_runtime(8, 8, 1, 1, samples_per_second=0)


def test_memory_grows_with_pixels_and_attempt():
    small = sizing.render_mem_mb(320, 180)
    large = sizing.render_mem_mb(1280, 720)
    assert small == sizing.RENDER_BASE_MB + math.ceil(64 * 320 * 180 / 2**20)
    assert large - sizing.RENDER_BASE_MB == math.ceil(64 * 1280 * 720 / 2**20) == 57
    assert sizing.render_mem_mb(1280, 720, attempt=3) == 3 * large
    assert sizing.analysis_mem_mb(1280, 720, 10) == 1024 + math.ceil(240 * 921600 / 2**20)


def test_intervention_runtime_covers_the_measured_paper_scale_scene():
    # Measured: 23.7 s for one 1280x720 scene with N = 30 and 31 disparities on 2 cores.
    minutes = sizing.intervention_runtime(1280, 720, 30, 31)
    assert minutes * 60 >= 2 * 23.7
    assert minutes <= 5
