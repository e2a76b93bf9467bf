"""The residual-shuffle intervention of paper Sec. 3.4 (Table 3): is alignment a matching cue?

The right view's Monte Carlo residuals are block-shuffled by one fixed permutation, which
decorrelates the two views' noise structure and keeps everything else; cost-volume scans
then score stereo matching on the normal and the decorrelated pair against the ground-truth
disparity.

``shuffle``
    The block permutation :math:`\\Pi` and its application to the residuals.
``scan``
    Streamed windowed-SAD cost-volume scans, winner-take-all disparity and hit rates.
``metrics``
    One scene's intervention metrics (residual, variance and image costs).
``lift``
    The variance-matching cost's lift over chance with its tile-bootstrap interval (the
    audit's matching-cue rule).

Importing this package imports none of its modules (nor numpy).
"""
