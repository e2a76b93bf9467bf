"""Figures: pure functions from arrays or table rows to a matplotlib figure (Agg backend).

The caller saves the figure; nothing here reads or writes results.

``teaser``
    The paper's teaser (Fig. 1): both variance fields, the warped right field and their joint
    histogram.
``rho_vs_spp``
    :math:`\\rho` versus SPP per region with its intervals (Fig. 2).
``material_scatter``
    The material scatter, glass against non-glass (Fig. 3).
``margins``
    The intervention's margin distributions, normal against decorrelated.
``plotting``
    What the figure modules share: pyplot on the Agg backend, the regions' labels and
    colours, the statistics' legend names.
``fields``
    Variance fields on a logarithmic colour scale, and the Pearson :math:`\\rho` the figures
    print.
``error_bars``
    The 95% interval of a correlation row as an error bar, and the legend note naming it.
``uncertainty``
    :math:`\\rho` against the number of seeds, and every statistic and control per scene
    with its bootstrap interval.
``estimators``
    The estimator validation: the moments estimator against N seeds.
``cross_renderer``
    One scene's variance fields from every renderer, side by side.
``mitigations``
    The cue each mitigation leaves against its image-quality cost.
``calibration``
    Each rule's power on a planted cue and its false-positive rate on the matched nulls.
``probe``
    The learned probe's accuracy on each test input, per training condition.
``generators``
    Each generator profile's Monte Carlo-specific cue beside its matched null, its residual
    coupling and its image quality.
``preview``
    Both renders of a scene, its disparity and material map; the audit's thumbnails.
``layout``
    The check that no text of a figure is cut off at its edge or drawn over another
    (:func:`~stereovar.figures.layout.layout_problems`), and the helpers that keep it so:
    titles wrapped to a width, point labels placed apart.
``strongest``
    The verdict page's frames and tiles where the cue is strongest, with the top tile's two
    residual fields.

Importing this package imports none of its modules (nor matplotlib).
"""
