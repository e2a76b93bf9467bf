"""The learned probe: does a stereo matcher trained on these renders use the Monte Carlo cue?

A small matcher (MC-CNN "fast", :mod:`~stereovar.probe.network`) is trained on single renders
of each training condition (:mod:`~stereovar.probe.conditions`,
:mod:`~stereovar.probe.training`), cross-validated over scenes
(:mod:`~stereovar.probe.experiment`), and tested on counterfactual inputs that change only the
right view's Monte Carlo residual (:mod:`~stereovar.probe.inputs`): the block shuffle
:math:`\\Pi`, camera noise, no noise, and a cue conflict that moves the residual's variance
structure to :math:`d + k`. Its predictions are scored per tile
(:mod:`~stereovar.probe.scoring`) and summarised with intervals over test tiles and training
seeds (:mod:`~stereovar.probe.metrics`); :mod:`~stereovar.probe.verdict` states whether the
matcher uses the cue, against the ``sensor_only`` control.

The modules that train or run a network import PyTorch (the ``probe`` extra); ``inputs``,
``scoring``, ``metrics`` and ``verdict`` need only numpy and pandas.
"""
