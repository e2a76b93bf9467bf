"""The analysis settings and the simulated sensor of the ``analysis`` and ``controls`` config
sections, read by every job that computes a statistic (correlation, estimators, mitigations,
calibration, dose response, audit)."""

from __future__ import annotations


def analysis_settings(analysis: dict | None = None, controls: dict | None = None):
    """:class:`~stereovar.statistics.fields.AnalysisSettings` and the sensor model from the
    ``analysis`` and ``controls`` config sections (defaults for missing keys)."""
    from ..controls.sensor import SensorModel
    from ..statistics.bootstrap import BootstrapSettings
    from ..statistics.fields import AnalysisSettings

    analysis, controls = dict(analysis or {}), dict(controls or {})
    boot = dict(analysis.get("bootstrap") or {})
    settings = AnalysisSettings(
        min_pixels=int(analysis.get("min_pixels", 30)),
        bootstrap=BootstrapSettings(
            tile=int(boot.get("tile", 16)),
            reps=int(boot.get("reps", 1000)),
            seed=int(boot.get("seed", 0)),
        ),
        trim_fraction=float(analysis.get("trim_fraction", 0.001)),
        firefly_factor=float(analysis.get("firefly_factor", 100.0)),
        null_shift=float(controls.get("null_shift", 8)),
    )
    sensor = dict(controls.get("sensor") or {})
    model = SensorModel(
        gain=float(sensor.get("gain", 1000.0)),
        read_noise=float(sensor.get("read_noise", 2.0)),
        seed=int(sensor.get("seed", 0)),
    )
    return settings, model
