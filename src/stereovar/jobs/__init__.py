"""One function per workflow job, in modules by ``workflow/rules/*.smk`` file (a large one's
jobs over several).

``common`` (logging, scene preparation), ``settings`` (the analysis settings and sensor
model of the config), ``scenes``, ``ground_truth``, ``preview``, ``render``, ``variance``,
``correlation`` (Eq. 2 and Eq. 3), ``tables``, ``figures``, ``intervention``,
``estimators`` (the moments estimator against N seeds), ``claims`` (the claims table),
``transform`` (a mitigation's auxiliary passes and store transforms), ``reference`` (the
converged reference a mitigation's images are graded against), ``mitigation_scene`` (one
scene's mitigation measurements), ``mitigations`` (the mitigation table and figure),
``calibration`` (synthetic nulls and planted cues through every transform, statistic and
verdict rule), ``probe`` (the learned probe), ``probe_model`` (the user's own network on the
counterfactual inputs), ``generators`` (the generator table and figure), ``dose_response``
(what a seed-mean mitigation ships over its budget and the camera) and ``audit`` (an audit's
import, verdict page and export). Import the module you need, e.g.
``from stereovar.jobs.render import render_job``.
"""
