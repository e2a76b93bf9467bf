"""One function per workflow job, one module per ``workflow/rules/*.smk`` file.

``common`` (logging, scene preparation), ``scenes``, ``ground_truth``, ``preview``,
``render``, ``variance``, ``correlation`` (Eq. 2 and Eq. 3), ``tables``, ``figures`` and
``intervention``. Import the module you need, e.g. ``from stereovar.jobs.render import
render_job``.
"""
