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

A workflow job runs without dask: the workflow sets ``STEREOVAR_DASK=0`` for its jobs
(``Snakefile``), and importing this package then marks dask absent, so
xarray, which reads every store numpy-backed here, does not import it (about 0.4 CPU-s a
job; ``bench/job_overhead.py``). Set ``STEREOVAR_DASK=1`` to keep it.
"""

import os as _os
import sys as _sys

if _os.environ.get("STEREOVAR_DASK") == "0" and "dask" not in _sys.modules:
    _sys.modules["dask"] = None  # importlib.util.find_spec("dask") is then None
