"""The calibration: every statistic, control and verdict rule checked on data whose answer is
known (``DESIGN.md``, Calibration).

One scene's calibration runs in one order, law -> designs -> draws -> transforms ->
statistics -> rows -> table: the **law** (a camera law fitted to the renders' own variance,
and the planted strength they show beyond it, :mod:`~stereovar.calibration.law`), the
**designs** (the matched nulls and the planted cue at multiples of that strength,
:func:`~stereovar.calibration.replicates.designs`), the **draws** (:math:`N` frames per view
of each design, :mod:`~stereovar.calibration.synthesis`, through the data's integer encoding
when it has one, :mod:`~stereovar.calibration.pipelines`), the **transforms** (each of the
run's transforms on the frames as on the renders, :mod:`~stereovar.calibration.stacks`), the
**statistics** (Eq. 1, Eq. 2 and every calibrated statistic on the view pair,
:mod:`~stereovar.calibration.view_statistics`), the **rows** (every replicate of every design,
then the pipeline nulls, :mod:`~stereovar.calibration.replicates`, and the renders' own,
:mod:`~stereovar.calibration.renders`) and, over every scene's rows, the **table** (rates,
matched nulls and rules, :mod:`~stereovar.calibration.summary`, then in words).
:func:`~stereovar.calibration.replicates.scene_calibration` calls the steps in that order,
and no module below imports one listed after it.

:mod:`~stereovar.calibration.scene_frames`
    what the calibration takes from one scene (seed means, Eq. 1 field, ground truth, N);
:mod:`~stereovar.calibration.synthesis`
    the camera law and the synthetic frames of the matched nulls and the planted cue;
:mod:`~stereovar.calibration.pipelines`
    camera pipelines without a Monte Carlo cue and the integer encodings a null passes through;
:mod:`~stereovar.calibration.law`
    the law every design is drawn at and the planted strength the renders show;
:mod:`~stereovar.calibration.stacks`
    frame stacks through the run's transforms, as applied and as shipped;
:mod:`~stereovar.calibration.view_statistics`
    the statistics on one view pair of stacks, as replicate rows;
:mod:`~stereovar.calibration.replicates`
    one scene's replicates: the designs drawn, transformed and measured, and the pipeline nulls;
:mod:`~stereovar.calibration.renders`
    the run's own renders measured as the designs are (what ships);
:mod:`~stereovar.calibration.dose_response`
    what a seed-mean mitigation ships over its budget and the camera, predicted and measured;
:mod:`~stereovar.calibration.rates`
    rates with their Wilson interval and the level, coverage and power they are held to;
:mod:`~stereovar.calibration.nulls`
    the matched nulls and each statistic's difference from its null;
:mod:`~stereovar.calibration.rules`
    the rules a replicate fires (above 0, above its null, removed, shared, matching);
:mod:`~stereovar.calibration.summary`
    the calibration table: false-positive rates, power and coverage of every rule;
:mod:`~stereovar.calibration.claims`
    the claims table's level rule decided on the designs;
:mod:`~stereovar.calibration.sentences`
    the calibration in words, for the results and verdict pages;
:mod:`~stereovar.calibration.compact`
    the compact table, one row per transform and statistic.
"""
