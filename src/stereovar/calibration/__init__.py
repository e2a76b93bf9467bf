"""The calibration: every statistic, control and verdict rule checked on data whose answer is
known (``DESIGN.md``, Calibration).

:mod:`~stereovar.calibration.synthesis` draws matched nulls and planted cues from a run's own
frames, :mod:`~stereovar.calibration.pipelines` camera pipelines without a Monte Carlo cue
(lens shading, gain maps, 8-bit sRGB, white balance, colour matrices) and the integer
encodings a null passes through, :mod:`~stereovar.calibration.replicates` passes them through
the run's transforms and statistics, and :mod:`~stereovar.calibration.summary` turns the
replicates into false-positive rates, power curves and interval coverage;
:mod:`~stereovar.calibration.claims` decides the claims table's level rule on them too;
:mod:`~stereovar.calibration.dose_response` predicts what a seed-mean mitigation ships over
its budget and the camera, and measures it on renders.
"""
