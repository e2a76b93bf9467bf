"""The variance-estimator interface: render stores in, the variance contract out.

An estimator turns the render stores of one scene at one SPP (both views) into the dataset
stored at ``results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr``
(:func:`stereovar.io.contracts.variance_store`): ``mean`` (view, y, x, channel),
``variance`` (view, y, x), ``finite`` and ``n_nonfinite`` (view, y, x), with the attrs
``n_seeds`` and ``estimator``. Everything downstream (Eq. 2, Eq. 3, the tables, the figures)
reads only that contract.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence


class VarianceEstimator(ABC):
    """Per-pixel Monte Carlo variance of both views from their render stores.

    Subclasses set :attr:`name` (the ``render.estimator`` value) and :attr:`description`
    (stored as the dataset's ``estimator`` attribute) and implement :meth:`estimate`.
    """

    name: str = ""
    description: str = ""
    reads: str = "renders"
    """What the estimator reads per view: ``"renders"`` (every seed batch's render store,
    :mod:`stereovar.io.renders`) or ``"moments"`` (one moment store,
    :mod:`stereovar.io.moments`)."""
    takes_transforms: bool = True
    """Whether it can read the stores of a store transform (:mod:`stereovar.transforms`),
    which map render stores to render stores."""

    @classmethod
    def renders_per_view(cls, n_seeds: int) -> int:
        """Stores read per view for a run of ``n_seeds`` seeds (for job sizing)."""
        return int(n_seeds) if cls.reads == "renders" else 1

    @abstractmethod
    def estimate(self, left: Sequence, right: Sequence):
        """The variance contract of one scene at one SPP.

        Parameters
        ----------
        left, right : sequence of path-like
            Render stores of each view (the renders this estimator needs).

        Returns
        -------
        xarray.Dataset
            ``mean``, ``variance``, ``finite``, ``n_nonfinite`` on ``view`` (``left``,
            ``right``), ``y``, ``x`` (and ``channel`` for ``mean``); attrs ``n_seeds``.
        """
