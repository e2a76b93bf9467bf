"""One function per workflow job, one module per ``workflow/rules/*.smk`` file.

``common`` (logging, scene preparation), ``scenes``, ``ground_truth``, ``preview``,
``render``, ``variance``, ``correlation`` (Eq. 2 and Eq. 3), ``tables``, ``figures``,
``intervention``, ``estimators`` (the moments estimator against N seeds), ``claims`` (the
claims table), ``mitigations``, ``calibration`` (synthetic nulls and planted cues through
every transform, statistic and verdict rule), ``probe`` (the learned probe),
``probe_model`` (the user's own network on the counterfactual inputs), ``generators`` (the
generator table and figure), ``dose_response`` (what a seed-mean mitigation ships over its
budget and the camera) and ``audit``
(an audit's import, verdict page and export). Import the module you need, e.g.
``from stereovar.jobs.render import render_job``.
"""
