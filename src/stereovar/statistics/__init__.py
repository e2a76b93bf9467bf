"""Statistics of the aligned variance fields: Eq. 2 and 3, their intervals, controls and tables.

The measurement of paper Sec. 2.2-3.3: the right view's variance field warped into the left
view (Eq. 2), Pearson's :math:`\\rho` over the valid set :math:`\\Omega` and its regions
(Eq. 3), every registered statistic and control with a Fisher-z and a spatial block-bootstrap
interval, and the tables built from the per-scene rows.

``warp``
    Eq. 2: :func:`~stereovar.statistics.warp.warp_right_to_left` and
    :func:`~stereovar.statistics.warp.align_variance`.
``regions``
    The valid set :math:`\\Omega` and the material regions (glass, non-glass).
``correlation``
    Eq. 3: :func:`~stereovar.statistics.correlation.pearson_over_mask` with its Fisher-z
    interval and test.
``bootstrap``
    The spatial block bootstrap of a correlation over a pixel set.
``fields``
    The fields every statistic sees in left-view coordinates (:math:`\\sigma_L^2`,
    :math:`\\hat\\sigma_{R\\to L}^2`, intensities, null warps, sensor baselines).
``pixels``
    One region's pixels and the work its statistics share.
``registry``
    The registered statistics and controls (:data:`~stereovar.statistics.registry.METHODS`)
    and their evaluation over a region.
``robust``
    Spearman, logarithms, trimming and the firefly diagnostics of the tail.
``reliability``
    Split-half reliability of Eq. 1 and the attenuation of :math:`\\rho` by finite N.
``residuals``
    The cross-view correlation of the per-seed residuals (shared random streams).
``chance``
    How far two independent fields with spatial structure correlate by chance (Bartlett).
``agreement``
    Agreement of two estimates of one variance field (the estimator validation).
``rows``
    One scene's correlation rows and seed-subset curve.
``summary``
    Cross-scene and SPP-sweep summaries (Tables 1 and 2) and the intervention table.
``across``
    Every statistic and control across scenes, with combined intervals.
``cross_renderer``
    Each scene's statistics from every renderer, side by side.
``matched_null``
    A statistic minus its matched null (camera-law noise on the same frames), over scenes.
``lift``
    The :math:`C_\\sigma` winner-take-all lift over chance across frames.
``mitigations``
    The mitigation table: cue, controls and image-quality cost per mitigation.
``utility``
    Image-quality cost of a mitigation against a converged reference.
``dose_response``
    What a seed-mean mitigation ships over its budget and the camera, and what removes it.
``generators``
    The generator table: each generator profile's cue against its own matched null.
``values``
    Table cells read as numbers (NaN where missing or unreadable).
``t_intervals``
    Student-t intervals of a mean over scenes, and of a geometric mean of ratios.
``claim_rules``
    The verdict rules of a claim: holds, does not hold, explained by a control, not testable.
``claim_statistics``
    The statistics a claim can be tested on, each with its interval over scenes.
``claims``
    The claims table: which of the paper's quantitative claims hold.

Importing this package imports none of its modules (nor numpy); import the one you need,
e.g. ``from stereovar.statistics.correlation import pearson_over_mask``.
"""
