"""The learned probe: does a stereo network trained on these renders use the Monte Carlo cue,
and could the probe tell if it did?

Two architectures (:mod:`~stereovar.probe.architectures`, the registry): MC-CNN "fast"
(:mod:`~stereovar.probe.network`, trained in :mod:`~stereovar.probe.training`) and a small
end-to-end cost-volume network (:mod:`~stereovar.probe.costvolume`). Each is trained on
single renders of each training condition (:mod:`~stereovar.probe.conditions`: the
mitigations, the control ``sensor_only`` and the planted positive control of
:mod:`~stereovar.probe.planted`), beside a cue-blind twin, to a plateau of validation
accuracy (:mod:`~stereovar.probe.convergence`), cross-validated over scenes
(:mod:`~stereovar.probe.experiment`, the folds' scenes in :mod:`~stereovar.probe.folds`),
and tested on counterfactual inputs that change only the right view's Monte Carlo residual
(:mod:`~stereovar.probe.inputs`). Its predictions are scored per tile
(:mod:`~stereovar.probe.scoring`) and summarised with intervals over training seeds and test
tiles (:mod:`~stereovar.probe.metrics`); :mod:`~stereovar.probe.verdict` states whether each
network uses the cue, against its twin, and the smallest reliance the probe detects.
:mod:`~stereovar.probe.user_model` runs the user's own trained network through the same
counterfactual inputs, loaded by :mod:`~stereovar.probe.user_loading`, checked for a
response to its input and against the best constant disparity by
:mod:`~stereovar.probe.user_checks`, and summarised in a table and a reading by
:mod:`~stereovar.probe.user_summary`.

The modules that train or run a network import PyTorch (the ``probe`` extra); ``inputs``,
``scoring``, ``metrics``, ``verdict``, ``conditions``, ``architectures``, ``convergence`` and
``user_checks`` need only numpy, scipy and pandas, and ``folds`` only the standard library.
"""
