"""Controls: what could explain a cross-view variance correlation away.

``sensor``
    A Poisson-Gaussian camera on the clean seed mean (the level a real sensor reaches).
``intensity``
    The variance-intensity relation removed (partial correlation, relative variance).
``partial``
    Both views' residuals of the control, which the ``partial`` statistic correlates.
``covariates``
    The intensity control's colour and sensor-position terms (white balance, colour
    matrices, lens-shading correction).
``quantisation``
    The variance an integer encoding implies at each pixel's seed mean (8-bit PNG), the
    control's third term.
``null_warps``
    Deliberately wrong alignments (the level an unrelated alignment reaches).

Each enters the correlation rows as a registered statistic
(:mod:`stereovar.statistics.registry`).
"""
