"""Variance estimators behind one interface (:mod:`stereovar.estimators.base`), selected by
``render.estimator``.

:data:`ESTIMATORS` maps each name to its :class:`~stereovar.estimators.base.VarianceEstimator`
class, imported on first use; :func:`get_estimator` builds one. A new estimator is one module
plus one :meth:`~stereovar.registry.Registry.register` call below and the name in the config
schema's ``render.estimator`` enum.

``base``
    The interface: render stores in, the variance contract out.
``seeds``
    Eq. 1 over N independent seeds (``seeds``), in memory or streamed from the stores.
``moments``
    Eq. 1's target from one render's per-pixel sample moments (``moments``).
``subsets``
    Eq. 1 on split halves and disjoint subsets of the seeds (the reliability and the
    seed-subset curve).
``single``
    One render per view: the single-render noise estimates that were measured and refused,
    not registered (``docs/single_render.md``).
"""

from __future__ import annotations

from ..registry import Registry, factory

ESTIMATORS = Registry("estimator", config_key="render.estimator")
ESTIMATORS.register("seeds", "stereovar.estimators.seeds:SeedEstimator")
ESTIMATORS.register("moments", "stereovar.estimators.moments:MomentEstimator")

get_estimator = factory(ESTIMATORS)
"""``get_estimator(name, **options)``: a
:class:`~stereovar.estimators.base.VarianceEstimator`."""



def reads_moments(name) -> bool:
    """Whether the estimator ``name`` reads one render's sample moments per view instead of
    N renders (its declared :attr:`~stereovar.estimators.base.VarianceEstimator.reads`);
    False for a name that is not registered (e.g. a table without an ``estimator``)."""
    return name in ESTIMATORS and ESTIMATORS.get(name).reads == "moments"


__all__ = ["ESTIMATORS", "get_estimator", "reads_moments"]
