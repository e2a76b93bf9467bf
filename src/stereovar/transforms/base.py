"""The transform seam: what a mitigation reads and the function that applies it.

A run is source -> transform -> estimator -> analysis (``DESIGN.md``). A transform maps one
render of one view and seed to a new render of the same shape; it may read the view's seed
statistics (mean and unbiased variance over its :math:`N` renders) and auxiliary passes
(albedo, normal), and it declares which, so that a source that cannot give them (an audit
without auxiliary files, say) is refused in one line before any job
(:func:`check_reads`).

Importing this module pulls in only numpy.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields

import numpy as np

from ..errors import ConfigError

BASE_FIELDS = ("render", "view", "seed_index", "rng_seed")
"""The :class:`TransformInputs` fields every source gives."""


@dataclass(frozen=True)
class TransformInputs:
    """One render and what a transform may read beside it.

    Attributes
    ----------
    render : numpy.ndarray, shape (H, W, 3), float32
        Linear radiance of one render (one seed) of one view.
    view : str
        ``"left"`` or ``"right"``.
    seed_index : int
        Index :math:`i` of the render among the view's :math:`N` seeds.
    rng_seed : int
        Seed of any random draw of the transform; the caller records it.
    seed_mean : numpy.ndarray, shape (H, W, 3), float64, optional
        Per-channel mean of the view's :math:`N` renders, :math:`\\bar I_c`.
    seed_var : numpy.ndarray, shape (H, W, 3), float64, optional
        Per-channel unbiased variance over the :math:`N` renders (``ddof=1``),
        :math:`\\hat\\sigma_c^2`.
    n_seeds : int, optional
        :math:`N`.
    albedo : numpy.ndarray, shape (H, W, 3), float32, optional
        Auxiliary albedo (diffuse colour) pass, in [0, 1].
    normal : numpy.ndarray, shape (H, W, 3), float32, optional
        Auxiliary normal pass, in [-1, 1].
    """

    render: np.ndarray
    view: str
    seed_index: int
    rng_seed: int
    seed_mean: np.ndarray | None = None
    seed_var: np.ndarray | None = None
    n_seeds: int | None = None
    albedo: np.ndarray | None = None
    normal: np.ndarray | None = None

    def __post_init__(self):
        shape = np.shape(self.render)
        if len(shape) != 3 or shape[2] != 3:
            raise ValueError(f"render must have shape (H, W, 3), got {shape}")
        if self.view not in ("left", "right"):
            raise ValueError(f"view must be 'left' or 'right', got {self.view!r}")
        for name in ("seed_mean", "seed_var", "albedo", "normal"):
            value = getattr(self, name)
            if value is not None and np.shape(value) != shape:
                raise ValueError(
                    f"{name} has shape {np.shape(value)}, the render {shape}; give the same view"
                )

    def available(self) -> set[str]:
        """Names of the fields that are given (not None)."""
        return {f.name for f in fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class Transform:
    """A registered mitigation that acts on stored renders.

    Attributes
    ----------
    name : str
        Registry name (``mitigations.transforms`` in the config).
    description : str
        One line, for tables.
    apply : callable
        ``apply(inputs: TransformInputs, **options) -> numpy.ndarray`` (H, W, 3) float32;
        options are keyword-only.
    reads : tuple of str
        :class:`TransformInputs` fields it requires beyond :data:`BASE_FIELDS`.
    optional_reads : tuple of str
        Fields it uses when present (and works without).
    random : bool
        Whether it draws random numbers from ``rng_seed``.
    expensive : bool
        Whether one image costs far more than the statistics on it (the denoisers): the
        calibration passes fewer replicates through it
        (:mod:`stereovar.calibration.replicates`).
    encoding : dict, optional
        The integer encoding its output is read back from (``bits``, ``transfer``, ``scale``:
        :func:`stereovar.transforms.output.output_encoding`), for the intensity control's
        quantisation term; None for a float output.
    """

    name: str
    description: str
    apply: Callable[..., np.ndarray]
    reads: tuple[str, ...] = ()
    optional_reads: tuple[str, ...] = ()
    random: bool = False
    expensive: bool = False
    encoding: dict | None = None

    def __post_init__(self):
        known = {f.name for f in fields(TransformInputs)}
        unknown = sorted((set(self.reads) | set(self.optional_reads)) - known)
        if unknown:
            raise ValueError(
                f"transform {self.name!r} reads unknown inputs {unknown}; use some of "
                f"{sorted(known)}"
            )

    def missing(self, available: Iterable[str]) -> list[str]:
        """The required reads not in ``available``, in declaration order."""
        have = set(available) | set(BASE_FIELDS)
        return [name for name in self.reads if name not in have]

    def __call__(self, inputs: TransformInputs, **options) -> np.ndarray:
        """Apply to one render after checking its reads (:func:`check_reads`)."""
        check_reads(self, inputs.available(), source="these inputs")
        return self.apply(inputs, **options)


def check_reads(transform: Transform, available: Iterable[str], *, source: str) -> None:
    """Refuse a transform whose required inputs the source cannot give.

    Parameters
    ----------
    transform : Transform
    available : iterable of str
        The :class:`TransformInputs` fields the source gives (e.g. ``{"seed_mean",
        "seed_var", "n_seeds"}`` for a source with :math:`N \\ge 2` seeds, plus ``"albedo"``
        and ``"normal"`` where it has auxiliary passes).
    source : str
        The source, as the user names it (``"renderer mitsuba"``, ``"audit 'team_a'"``).

    Raises
    ------
    ConfigError
        One line: the transform, what it needs, what the source gives and the fix.
    """
    missing = transform.missing(available)
    if not missing:
        return
    gives = sorted(set(available) - set(BASE_FIELDS))
    fixes = []
    if {"seed_mean", "seed_var", "n_seeds"} & set(missing):
        fixes.append("give the source at least 2 seeds per view (the seed statistics)")
    if {"albedo", "normal"} & set(missing):
        fixes.append("give the source albedo and normal passes")
    fixes.append(f"or remove {transform.name!r} from mitigations.transforms")
    raise ConfigError(
        f"transform {transform.name!r} needs {', '.join(missing)}, which {source} does not "
        f"give (it gives: {', '.join(gives) or 'the renders only'}); {'; '.join(fixes)}"
    )
