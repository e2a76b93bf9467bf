"""Can the user's network be tested at all? Its baseline, the best constant disparity, and its
response to a shift of its right view.

A reading of *no use* of the Monte Carlo cue (:mod:`stereovar.probe.user_model`) says that the
network's accuracy did not drop when the right view's residual was shuffled. A network whose
output does not depend on its input, an untrained or broken checkpoint, has no accuracy to
lose and reads the same. Two checks tell such a network from one that matches the views.

**Baseline.** The best constant answers of each frame, chosen knowing its ground truth
:math:`d` on its scored pixels :math:`\\Omega`:

.. math::

    c_A = \\arg\\max_c \\sum_{\\Omega} [\\,|c - d| < 1\\,], \\qquad
    c_E = \\operatorname{median}_{\\Omega} d = \\arg\\min_c \\sum_{\\Omega} |c - d|,

the constant of the highest accuracy (the centre of the densest window of ground-truth
disparities less than 2 px wide, :func:`best_constants`) and the one of the lowest end-point
error (the median). No network that answers one disparity per frame does better on either
measure. Every input of a frame is scored on the same pixels against the same ground truth, so
the constant's accuracy :math:`A(c_A)` and EPE :math:`\\mathrm{EPE}(c_E)` are one row for all
inputs (``constant``, with a tile-bootstrap interval), and the network's gain on the renders is

.. math::

    G_A = A(\\text{normal}) - A(c_A), \\qquad
    G_E = \\mathrm{EPE}(c_E) - \\mathrm{EPE}(\\text{normal})

(row ``over_constant``, paired by tile). The network *beats the constant* when the interval
of :math:`G_A` or of :math:`G_E` lies above 0 (the point value where there is no interval).

**Response.** The first test render's ``normal`` pair is run once more with its right view
moved by :math:`k =` :data:`RESPONSE_SHIFT` px so that every match lies :math:`k` px farther
(:func:`shifted_right`; :math:`s` the frames' disparity sign):

.. math:: R'(x) = R\\bigl(\\operatorname{clip}(x - s k,\\ 0,\\ W - 1)\\bigr),

one forward pass per frame. A network that matches answers :math:`\\hat d + k` wherever it
matches; its mean change

.. math::

    \\bar\\Delta = \\frac{1}{|\\Omega_k|} \\sum_{x \\in \\Omega_k}
        \\bigl|\\hat d'(x) - \\hat d(x)\\bigr|,

over the pixels :math:`\\Omega_k` of :math:`\\Omega` whose moved match stays in the image and
where both answers are finite (:func:`response_sums`, pooled over frames), is :math:`k` for a
network that matches everywhere. The network *responds* when :math:`\\bar\\Delta \\ge`
:data:`MIN_RESPONSE` = 0.1 px, 5 % of the shift: a network that follows the shift on one
pixel in 20, or a twentieth of it everywhere, passes; a near-constant output, such as a
random-weight network's whose bias dominates (a 2-px move changed the answer of one at
5.4 px by 2e-5 px), does not. A network whose answer moves but not to a match
fails the baseline instead.

The network is *testable* when it responds and beats the constant (:func:`testability`);
otherwise the reading says so instead of *no use* (:func:`testability_warning`).

Importing this module does not import PyTorch.
"""

from __future__ import annotations

import math

import numpy as np

from ..statistics.regions import valid_set

__all__ = [
    "CONSTANT_ROW",
    "MIN_RESPONSE",
    "RESPONSE_ROW",
    "RESPONSE_SHIFT",
    "best_constants",
    "response_sums",
    "shift_response",
    "shifted_right",
    "testability",
    "testability_warning",
]

CONSTANT_ROW = "constant"
"""The table's row (and the scored rows' ``test_input``) of the best constant answers."""

RESPONSE_ROW = "shift_response"
"""The ``test_input`` of a frame's response sums (:func:`response_sums`)."""

RESPONSE_SHIFT = 2
"""Pixels the right view is moved by for the response check: more than the 1-px tolerance of
a hit, so that a network that follows it leaves its own earlier answer's window, and small, so
that the moved disparities stay within a small network's range."""

MIN_RESPONSE = 0.1
"""Mean absolute change of disparity (px) below which the network does not respond to the
shift: 5 % of :data:`RESPONSE_SHIFT` (module docstring)."""

HIT = 1.0
"""The accuracy's tolerance: a hit is :math:`|\\hat d - d| <` ``HIT``
(:mod:`stereovar.probe.scoring`)."""


def best_constants(values) -> tuple[float, float]:
    """The constant disparity of the highest accuracy and the one of the lowest end-point
    error on ground-truth disparities ``values``.

    .. math::

        c_A = \\arg\\max_c \\sum_i [\\,|c - d_i| < 1\\,], \\qquad
        c_E = \\operatorname{median}_i d_i

    The hits of a constant :math:`c` are the :math:`d_i` in the open window
    :math:`(c - 1, c + 1)`: over the sorted values, the largest run
    :math:`d_a \\le \\dots \\le d_b` with :math:`d_b - d_a < 2`, centred, :math:`c_A = (d_a +
    d_b) / 2`. The median minimises the summed absolute error.

    Parameters
    ----------
    values : array_like
        Ground-truth disparities (non-finite ones are left out).

    Returns
    -------
    (float, float)
        :math:`c_A` and :math:`c_E`.

    Raises
    ------
    ValueError
        No finite value.

    Examples
    --------
    Three pixels at 2 px, two at 3.5 and four at 6: the window around 2 and 3.5 holds 5
    pixels (the one of the four at 6 holds 4); the median is 3.5.

    >>> best_constants([2, 2, 2, 3.5, 3.5, 6, 6, 6, 6])
    (2.75, 3.5)
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    v = np.sort(v[np.isfinite(v)])
    if not v.size:
        raise ValueError("no finite ground-truth disparity to choose a constant from")
    ends = np.searchsorted(v, v + 2 * HIT, side="left")  # first value outside [v_i, v_i + 2)
    i = int(np.argmax(ends - np.arange(v.size)))
    return float(0.5 * (v[i] + v[ends[i] - 1])), float(np.median(v))


def shifted_right(right, *, sign: int, shift: int = RESPONSE_SHIFT) -> np.ndarray:
    """The right view moved by ``shift`` pixels so that every match lies ``shift`` pixels
    farther, the edge column repeated.

    .. math:: R'(x) = R\\bigl(\\operatorname{clip}(x - s k,\\ 0,\\ W - 1)\\bigr)

    With :math:`s = -1` left pixel :math:`x` matches :math:`R(x - d) = R'(x - d - k)`; with
    :math:`s = +1`, :math:`R(x + d) = R'(x + d + k)`.

    Parameters
    ----------
    right : array_like, shape (H, W, ...)
    sign : {1, -1}, keyword-only
        The frame's disparity sign.
    shift : int, keyword-only
        :math:`k`.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> shifted_right(np.array([[0, 1, 2, 3, 4]]), sign=-1).tolist()
    [[2, 3, 4, 4, 4]]
    >>> shifted_right(np.array([[0, 1, 2, 3, 4]]), sign=1).tolist()
    [[0, 0, 0, 1, 2]]
    """
    right = np.asarray(right)
    if int(sign) not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    cols = np.clip(np.arange(right.shape[1]) - int(sign) * int(shift), 0, right.shape[1] - 1)
    return np.ascontiguousarray(right[:, cols])


def response_sums(d_hat, d_moved, d_gt, omega, *, sign: int, shift: int = RESPONSE_SHIFT):
    """How far the network's answer moved when the right view was moved
    (:func:`shifted_right`): pixels compared and summed changes.

    .. math::

        n = |\\Omega_k|, \\qquad \\sum_{\\Omega_k} |\\hat d' - \\hat d|, \\qquad
        \\sum_{\\Omega_k} (\\hat d' - \\hat d),

    :math:`\\Omega_k` the pixels of :math:`\\Omega` whose match at :math:`d + k` lies in the
    image (:func:`stereovar.statistics.regions.valid_set`) and where both answers are finite.

    Parameters
    ----------
    d_hat, d_moved : array_like, shape (H, W)
        The network's disparity on the pair and on the pair with the moved right view.
    d_gt : array_like, shape (H, W)
        Ground-truth disparity magnitudes.
    omega : array_like of bool, shape (H, W)
        The scored pixels.
    sign, shift : int, keyword-only

    Returns
    -------
    dict
        ``n``, ``abs_change``, ``change``.

    Examples
    --------
    A network that follows the shift on the two pixels whose moved match stays inside:

    >>> d = np.full((1, 5), 1.0)
    >>> response_sums(d, d + 2, d, np.ones((1, 5), bool), sign=-1)
    {'n': 2, 'abs_change': 4.0, 'change': 4.0}
    """
    d_hat = np.asarray(d_hat, dtype=np.float64)
    d_moved = np.asarray(d_moved, dtype=np.float64)
    omega = np.asarray(omega, dtype=bool)
    moved = np.where(omega, np.asarray(d_gt, dtype=np.float64) + int(shift), np.nan)
    inside = omega & valid_set(moved, sign=int(sign))
    both = inside & np.isfinite(d_hat) & np.isfinite(d_moved)
    delta = d_moved[both] - d_hat[both]
    return {
        "n": int(both.sum()),
        "abs_change": float(np.abs(delta).sum()),
        "change": float(delta.sum()),
    }


def shift_response(rows) -> dict:
    """The network's response to the shift, pooled over the frames' :data:`RESPONSE_ROW`
    rows (:func:`response_sums`).

    .. math:: \\bar\\Delta = \\frac{\\sum_f \\sum_{\\Omega_k} |\\hat d' - \\hat d|}
        {\\sum_f |\\Omega_k|}

    Returns
    -------
    dict
        ``shift_px`` (:math:`k`), ``shift_pixels``, ``mean_change_px`` (signed; :math:`k`
        for a network that matches), ``mean_abs_change_px`` (:math:`\\bar\\Delta`) and
        ``responds``: :math:`\\bar\\Delta \\ge` :data:`MIN_RESPONSE`, None where no pixel
        could be compared.

    Examples
    --------
    >>> r = shift_response([{"test_input": RESPONSE_ROW, "n": 4, "abs_change": 0.02,
    ...                      "change": 0.0}])
    >>> r["mean_abs_change_px"], r["responds"]
    (0.005, False)
    """
    own = [r for r in rows if r.get("test_input") == RESPONSE_ROW]
    n = sum(int(r["n"]) for r in own)
    abs_change = sum(float(r["abs_change"]) for r in own)
    change = sum(float(r["change"]) for r in own)
    mean_abs = abs_change / n if n else math.nan
    return {
        "shift_px": RESPONSE_SHIFT,
        "shift_pixels": n,
        "mean_change_px": change / n if n else math.nan,
        "mean_abs_change_px": mean_abs,
        "responds": bool(mean_abs >= MIN_RESPONSE) if n else None,
    }


def _px(value: float) -> str:
    """A small length in pixels: three decimals, or two significant digits below 0.001.

    Examples
    --------
    >>> _px(0.0123), _px(2.4e-05), _px(0.0)
    ('0.012', '2.4e-05', '0')
    """
    if value == 0:
        return "0"
    return f"{value:.3f}" if abs(value) >= 0.001 else f"{value:.1e}"


def _above_zero(point: float, low: float) -> bool:
    """The interval's lower end lies above 0; the point value where there is no interval."""
    return bool(low > 0) if math.isfinite(low) else bool(point > 0)


def testability(table, response: dict) -> dict:
    """Whether the probe can read *no use* from this network: it responds to the shift of
    its right view and beats the best constant (module docstring).

    Parameters
    ----------
    table : list of dict
        :func:`stereovar.probe.user_summary.model_rows`' rows (``normal``,
        :data:`CONSTANT_ROW` and ``over_constant`` are read).
    response : dict
        :func:`shift_response`.

    Returns
    -------
    dict
        ``response``'s keys and ``beats_constant``, ``testable`` and ``problem`` (one
        clause naming what failed, with its numbers; None when testable).
    """
    by = {r["row"]: r for r in table}
    normal, constant, gain = by["normal"], by[CONSTANT_ROW], by["over_constant"]
    beats = _above_zero(gain["accuracy"], gain["accuracy_low"]) or _above_zero(
        gain["epe"], gain["epe_low"]
    )
    problems = []
    if response["responds"] is False:
        k = response["shift_px"]
        problems.append(
            "the network's output does not respond to its input (moving the right view "
            f"{k} px moved its disparity by {_px(response['mean_abs_change_px'])} px on "
            f"average, under {MIN_RESPONSE:g} px; a network that matches moves it by {k} px)"
        )
    if not beats:
        problems.append(
            "the network is no better than a constant disparity (accuracy "
            f"{100 * normal['accuracy']:.1f} % vs {100 * constant['accuracy']:.1f} % and EPE "
            f"{normal['epe']:.3f} vs {constant['epe']:.3f} px for the best constant of each "
            "frame)"
        )
    return {
        **response,
        "beats_constant": beats,
        "testable": not problems,
        "problem": " and ".join(problems) or None,
    }


def testability_warning(checks: dict) -> str | None:
    """The one-line warning of :func:`testability`'s failed checks; None when the network is
    testable.

    Examples
    --------
    >>> testability_warning({"testable": True, "problem": None}) is None
    True
    >>> testability_warning({"testable": False, "problem": "x"})[:41]
    'the probe cannot test this network: x; an'
    """
    if checks["testable"]:
        return None
    return (
        f"the probe cannot test this network: {checks['problem']}; an untrained or broken "
        "checkpoint reads the same, so a reading of no use would mean nothing (the reading "
        "says not testable instead); check that --weights is this network's trained "
        "checkpoint and that it returns disparity in pixels"
    )
