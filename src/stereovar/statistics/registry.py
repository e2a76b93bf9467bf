"""The statistics registry: every per-region statistic of the aligned variance fields.

A statistic is a function ``f(fields, mask, *, min_pixels) -> dict`` of the
:class:`AlignedFields` of one scene and a region's pixel set, returning ``rho``,
``n_pixels``, ``ci_low``, ``ci_high``, ``p_value``, ``log10_p_value``, ``n_nonfinite`` and
``reason`` (the columns of :data:`stereovar.statistics.correlation.RESULT_KEYS`). The
correlation rows (``results/.../correlation/{scene}/spp{spp}.csv``), Table 1 and Fig. 2
iterate over :data:`METHODS`, so a new statistic is one function plus one
:func:`register_method` call; its name becomes the rows' ``method`` value.

Registered here (paper Sec. 2.3, 3.2):

``warp``
    Eq. 3: Pearson of :math:`\\sigma_L^2` and the warped :math:`\\hat\\sigma_{R\\to L}^2`
    over :math:`\\Omega_r`. The primary statistic (:data:`PRIMARY_METHOD`): Table 1's
    ``mean_rho`` and Table 2's ``rho_{region}``.
``no_warp``
    The same pixels without the alignment: Pearson of :math:`\\sigma_L^2(x, y)` and
    :math:`\\sigma_R^2(x, y)`; Table 1's ``mean_rho_no_warp``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..registry import Registry
from .correlation import pearson_over_mask


@dataclass(frozen=True)
class AlignedFields:
    """The fields every statistic sees, all (H, W) float64 in left-view coordinates.

    Attributes
    ----------
    left : numpy.ndarray
        :math:`\\sigma_L^2` (Eq. 1).
    warped : numpy.ndarray
        :math:`\\hat\\sigma_{R\\to L}^2` (Eq. 2); 0 outside the warp's valid set.
    right : numpy.ndarray
        :math:`\\sigma_R^2` at the same pixel positions, unaligned; NaN where a render was
        non-finite.
    """

    left: Any
    warped: Any
    right: Any


@dataclass(frozen=True)
class Method:
    """A registered statistic: its function and a one-line description."""

    function: Callable[..., dict]
    description: str


METHODS = Registry("statistic")
"""Name to :class:`Method`, in the order rows and table columns appear."""

PRIMARY_METHOD = "warp"
"""The statistic Table 1's ``mean_rho`` and Table 2's ``rho_{region}`` report."""


def register_method(name: str, description: str, *, replace: bool = False):
    """Decorator registering ``f(fields, mask, *, min_pixels) -> dict`` as statistic ``name``."""

    def decorator(function):
        METHODS.register(name, Method(function, description), replace=replace)
        return function

    return decorator


@register_method("warp", "Pearson of sigma_L^2 and the warped sigma_R^2 over the region (Eq. 3)")
def warped_pearson(fields: AlignedFields, mask, *, min_pixels: int = 30) -> dict:
    """Eq. 3: :math:`\\rho = \\mathrm{corr}(\\sigma_L^2, \\hat\\sigma_{R\\to L}^2)|_{\\Omega_r}`.

    .. math::

        \\rho = \\frac{\\sum_{i \\in \\Omega_r} (a_i - \\bar a)(b_i - \\bar b)}
            {\\sqrt{\\sum_i (a_i - \\bar a)^2 \\sum_i (b_i - \\bar b)^2}}, \\quad
        a = \\sigma_L^2,\\ b = \\hat\\sigma_{R\\to L}^2

    (paper Sec. 2.3), with the Fisher-z interval of
    :func:`~stereovar.statistics.correlation.pearson_over_mask`.
    """
    return pearson_over_mask(fields.left, fields.warped, mask, min_pixels=min_pixels)


@register_method("no_warp", "Pearson of sigma_L^2 and the unaligned sigma_R^2 on the same pixels")
def unaligned_pearson(fields: AlignedFields, mask, *, min_pixels: int = 30) -> dict:
    """The no-warp baseline of paper Sec. 3.2: Eq. 3 without Eq. 2.

    .. math::

        \\rho_{\\text{no-warp}} = \\mathrm{corr}\\bigl(\\sigma_L^2(x, y),\\,
            \\sigma_R^2(x, y)\\bigr)\\big|_{\\Omega_r}
    """
    return pearson_over_mask(fields.left, fields.right, mask, min_pixels=min_pixels)


def secondary_methods() -> tuple[str, ...]:
    """Every registered statistic but :data:`PRIMARY_METHOD`."""
    return tuple(m for m in METHODS.names() if m != PRIMARY_METHOD)
