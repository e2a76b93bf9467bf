"""The verdict rules of the claims table: when a claim of the paper holds on the scenes run.

:func:`verdict` decides one claim from our value with its 95% interval, the paper's value, the
claim's kind and rule settings, and the bearing control with its interval; the claims table
(:mod:`stereovar.statistics.claims`) gives one row per claim with it. The rules:

* **level** claims (a value, e.g. :math:`\\rho = 0.754`): *not testable at this scale* when
  ours or its interval is undefined; *does not hold* when the paper's value is outside our
  interval; *not testable at this scale* when the interval contains the null too (no effect,
  :math:`\\rho = 0`: the data cannot tell the claim from no effect); *explained by a
  control* when the control accounts for ours (:func:`explained_by_control`: the interval of
  ours minus the control reaches 0, or the control is at least the claim's ``control_share``
  of ours); *holds* otherwise;
* **level claims with an equivalence margin** :math:`m` (required when the paper's value is
  the null, e.g. real sensors' :math:`\\rho = 0`, which an interval that must exclude the
  null could never confirm): decided by equivalence, :func:`equivalence_verdict` around the
  paper's value;
* **ratio** claims (e.g. glass variance :math:`7\\times` non-glass): the level rule with the
  null 1, on the geometric mean over scenes and the exponentiated Student-t interval of the
  per-scene log ratios (:func:`~stereovar.statistics.t_intervals.geometric_t_interval`); a
  scene with a ratio that is not positive has no logarithm, and the claim is *not testable*
  with that scene named;
* **direction** claims (a sign, e.g. Table 3's normal minus decorrelated): *not testable at
  this scale* when our interval spans 0; *does not hold* when it lies on the other side;
  *explained by a control* when the control accounts for ours, as for a level; *holds*
  otherwise (beyond its control);
* **tolerance** claims (a relative change within the paper's :math:`\\pm t`): equivalence
  with the margin :math:`t` around 0 (:func:`equivalence_verdict`): a statistic without an
  interval cannot show it.

Equivalence is two one-sided tests (TOST) at 5%: *holds* when the 90% interval lies inside
:math:`(c - m,\\ c + m)`; *does not hold* when the 95% interval lies wholly outside
:math:`[c - m,\\ c + m]`; *not testable at this scale* otherwise (too wide to show either).
The 90% interval is the claim's statistic computed again at level 0.90 (Student-t
quantile :math:`t_{0.95,\\,S-1}` in place of :math:`t_{0.975,\\,S-1}`), and the row's note
gives it.
"""

from __future__ import annotations

import math

HOLDS = "holds"
FAILS = "does not hold"
EXPLAINED = "explained by a control"
UNTESTABLE = "not testable at this scale"

KINDS = ("level", "ratio", "direction", "tolerance")
"""The kinds of claim, in the order the caption states their rules."""

NULLS = {"level": 0.0, "ratio": 1.0}
"""The no-effect value of a level claim (:math:`\\rho = 0`) and of a ratio claim (1), used by
:func:`verdict` when the claim does not state its own."""

_NAN3 = (math.nan,) * 3


def _ok(*values) -> bool:
    return all(v is not None and math.isfinite(float(v)) for v in values)


def difference_interval(ours, control) -> tuple[float, float, float]:
    """Ours minus the control with its interval, the two taken as independent.

    .. math::

        d = \\hat\\theta - \\hat\\theta_c, \\qquad
        \\left[\\, d - \\sqrt{(\\hat\\theta - \\ell)^2 + (h_c - \\hat\\theta_c)^2},\\ \\
        d + \\sqrt{(h - \\hat\\theta)^2 + (\\hat\\theta_c - \\ell_c)^2} \\,\\right]

    (each side's half-widths in quadrature: the interval of a difference of independent
    estimates; for symmetric intervals the half-width is :math:`\\sqrt{w^2 + w_c^2}`). Ours
    and the control are computed on the same scenes, so they are usually positively
    correlated and the difference is then better known than this: the interval errs wide,
    toward "explained by a control".

    Parameters
    ----------
    ours, control : tuple (value, low, high)

    Examples
    --------
    >>> d, low, high = difference_interval((0.088, 0.065, 0.111), (0.003, 0.0026, 0.0034))
    >>> round(d, 3), round(low, 4), round(high, 4)
    (0.085, 0.062, 0.108)
    """
    a, a_low, a_high = (float(v) for v in ours)
    b, b_low, b_high = (float(v) for v in control)
    d = a - b
    return d, d - math.hypot(a - a_low, b_high - b), d + math.hypot(a_high - a, b - b_low)


def explained_by_control(
    ours, control, *, side: float, null: float = 0.0, share: float | None = None
) -> bool:
    """Whether the control accounts for ours: the interval of ours minus the control
    (:func:`difference_interval`) reaches 0 or lies on the control's side, or, with a
    ``share`` :math:`q`, the control's effect is at least :math:`q` of ours,

    .. math::

        \\sigma\\,(\\hat\\theta_c - \\theta_0) \\ge q\\,\\sigma\\,(\\hat\\theta - \\theta_0),

    :math:`\\sigma` the side of the claim (+1 or -1) and :math:`\\theta_0` its null. A control
    on the claim's side but far smaller than ours explains nothing.

    Parameters
    ----------
    ours, control : tuple (value, low, high)
    side : float, keyword-only
        The claim's side: the sign of the paper's value (a direction) or of the paper's
        value minus the null (a level or ratio).
    null : float, keyword-only
        The no-effect value the shares are measured from.
    share : float, keyword-only, optional
        The claim's ``control_share``; None: the interval alone decides.

    Examples
    --------
    >>> explained_by_control((0.088, 0.065, 0.111), (0.003, 0.0026, 0.0034), side=1)
    False
    >>> explained_by_control((0.088, 0.065, 0.111), (0.08, 0.07, 0.09), side=1)
    True
    >>> explained_by_control((0.088, 0.065, 0.111), (0.05, 0.049, 0.051), side=1, share=0.5)
    True
    """
    sign = math.copysign(1.0, side)
    if _ok(*ours, *control):
        _, low, high = difference_interval(ours, control)
        if (low if sign > 0 else -high) <= 0:
            return True
    if share is not None and _ok(ours[0], control[0]):
        theirs, mine = sign * (float(control[0]) - null), sign * (float(ours[0]) - null)
        if theirs >= share * mine:
            return True
    return False


def equivalence_verdict(ours, low, high, *, centre: float, margin: float, interval90=None) -> str:
    """The verdict of equivalence to ``centre`` within ``margin``: two one-sided tests
    (TOST) at 5%.

    .. math::

        \\text{holds} \\iff c - m < \\ell_{90} \\ \\text{and}\\ h_{90} < c + m, \\qquad
        \\text{does not hold} \\iff \\ell_{95} > c + m \\ \\text{or}\\ h_{95} < c - m

    *Holds* rejects both :math:`\\theta \\le c - m` and :math:`\\theta \\ge c + m`, each at
    5% one-sided, which is the 90% interval inside the margin; *does not hold* when the 95%
    interval (the one the table shows) lies wholly outside it; *not testable at this scale*
    otherwise, and when ours or its interval is undefined: a point value without an interval
    cannot show equivalence.

    Parameters
    ----------
    ours, low, high : float
        Our value and its 95% interval.
    centre, margin : float, keyword-only
        The claimed value :math:`c` and the margin :math:`m > 0`.
    interval90 : tuple (low, high), keyword-only, optional
        The 90% interval. None: the 95% interval is used for "holds" too, a conservative
        TOST at 2.5% each side.

    Examples
    --------
    >>> equivalence_verdict(0.0, -0.05, 0.05, centre=0.0, margin=0.002)
    'not testable at this scale'
    >>> equivalence_verdict(0.03, 0.01, 0.05, centre=0.0, margin=0.1)
    'holds'
    >>> equivalence_verdict(0.3, 0.2, 0.4, centre=0.0, margin=0.1)
    'does not hold'
    """
    if not _ok(ours, low, high, centre, margin):
        return UNTESTABLE
    low90, high90 = (low, high) if interval90 is None else interval90
    if _ok(low90, high90) and centre - margin < low90 and high90 < centre + margin:
        return HOLDS
    if low > centre + margin or high < centre - margin:
        return FAILS
    return UNTESTABLE


def verdict(
    kind: str,
    paper: float,
    ours,
    low,
    high,
    control=_NAN3,
    *,
    control_explains: bool = True,
    null_value: float | None = None,
    equivalence_margin: float | None = None,
    equivalence_interval=None,
    control_share: float | None = None,
) -> str:
    """The verdict of one claim (the rules of the module docstring).

    A tolerance claim, and a level claim with an ``equivalence_margin``, is decided by
    :func:`equivalence_verdict` (its control is shown for context only); a level, ratio or
    direction claim that would hold is *explained by a control* when
    :func:`explained_by_control`.

    Parameters
    ----------
    kind : {"level", "ratio", "direction", "tolerance"}
    paper : float
        The paper's value: a level, a ratio, the signed effect of a direction claim (only its
        sign counts) or the tolerance of a tolerance claim.
    ours, low, high : float
        Our value and its 95% interval (a ratio's on the ratio scale).
    control : tuple (value, low, high)
        The bearing control with its 95% interval.
    control_explains : bool, keyword-only
        Whether the control can explain the claim away (False when it is shown for context).
    null_value : float, keyword-only, optional
        The no-effect value a level or ratio interval must exclude (default :data:`NULLS`).
    equivalence_margin : float, keyword-only, optional
        A level claim's margin: the claim is then equivalence to the paper's value within it.
        A tolerance claim's margin is its tolerance, ``paper``.
    equivalence_interval : tuple (low, high), keyword-only, optional
        The 90% interval for the equivalence test (default: the 95% one, a conservative TOST
        at 2.5%).
    control_share : float, keyword-only, optional
        The share of ours a control must reach to explain it whatever the intervals.

    Examples
    --------
    The default run's Table 3 residual SAD gt_margin on non-glass, against its sensor
    control, 30 times smaller:

    >>> verdict("direction", 59, 0.088, 0.065, 0.111, (0.003, 0.0026, 0.0034))
    'holds'
    """
    if kind not in KINDS:
        raise ValueError(f"unknown claim kind {kind!r}")
    if kind == "tolerance":
        return equivalence_verdict(
            ours, low, high, centre=0.0, margin=paper, interval90=equivalence_interval
        )
    if equivalence_margin is not None:
        if kind != "level":
            raise ValueError(f"a {kind} claim has no equivalence margin")
        return equivalence_verdict(
            ours,
            low,
            high,
            centre=paper,
            margin=equivalence_margin,
            interval90=equivalence_interval,
        )
    if not _ok(ours, low, high):
        return UNTESTABLE
    if kind in NULLS:
        null = NULLS[kind] if null_value is None else float(null_value)
        if not low <= paper <= high:
            return FAILS
        if low <= null <= high:
            return UNTESTABLE
        side = paper - null
    else:
        null, side = 0.0, paper
        if low <= 0 <= high:
            return UNTESTABLE
        if (low > 0) != (side > 0):
            return FAILS
    ours3 = (ours, low, high)
    if control_explains and explained_by_control(
        ours3, tuple(control), side=side, null=null, share=control_share
    ):
        return EXPLAINED
    return HOLDS
