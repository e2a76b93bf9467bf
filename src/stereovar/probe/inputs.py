"""What the learned matcher sees: one render per view, and the counterfactual test inputs.

A data set ships one render per view, tone-mapped for display. The matcher's input is that
render as an 8-bit-free display image: the grey (RGB-mean) radiance clipped to [0, 1],
sRGB-encoded, then standardised to zero mean and unit variance over the image's finite pixels
(MC-CNN's normalisation). Non-finite pixels become 0.

The counterfactual inputs split each render of a view into the seed mean and its residual,
:math:`I_V^{(n)} = \\bar I_V + \\epsilon_V^{(n)}` (paper Sec. 3.4), and change the residual
only:

``normal``
    :math:`(I_L^{(n)}, I_R^{(n)})`;
``shuffled``
    :math:`(I_L^{(n)}, \\bar I_R + \\Pi(\\epsilon_R^{(n)}))`: the paper's block shuffle, which
    breaks the alignment of the right residual and keeps the clean image;
``camera``
    :math:`(\\bar I_L + \\eta_L, \\bar I_R + \\eta_R)`, :math:`\\eta` Poisson-Gaussian camera
    noise of the seed mean: the residual of a camera, which has no Monte Carlo structure;
``clean``
    :math:`(\\bar I_L, \\bar I_R)`;
``conflict``
    :math:`(I_L^{(n)}, \\bar I_R + \\epsilon_R^{(n)}(x - s k, y))`: the right residual moved
    by :math:`k` pixels, so its variance structure lines up with the left at
    :math:`d_{GT} + k` while the clean image still lines up at :math:`d_{GT}`.

Importing this module pulls in only numpy.
"""

from __future__ import annotations

import numpy as np

from ..intervention.shuffle import apply_block_permutation, block_permutation
from ..io.images import linear_to_srgb

__all__ = [
    "LEFT_KEPT",
    "TEST_INPUTS",
    "counterfactual_pair",
    "grey",
    "network_input",
    "shift_columns",
]

TEST_INPUTS = ("normal", "shuffled", "camera", "clean", "conflict")
"""The test inputs, in table order."""

LEFT_KEPT = ("normal", "shuffled", "conflict")
"""The test inputs whose left view is the render itself (only the right residual changes)."""


def grey(render) -> np.ndarray:
    """The RGB mean of a render (H, W, 3) as float64; a (H, W) array is returned as is."""
    a = np.asarray(render, dtype=np.float64)
    if a.ndim == 3:
        return a.mean(axis=2)
    if a.ndim != 2:
        raise ValueError(f"a render must have shape (H, W) or (H, W, 3), got {a.shape}")
    return a


def network_input(render) -> np.ndarray:
    """The matcher's input of one render: display-encoded grey, standardised.

    .. math::

        u = \\mathrm{sRGB}\\bigl(\\min(\\max(\\bar c, 0), 1)\\bigr), \\qquad
        x = \\frac{u - \\operatorname{mean}(u)}{\\operatorname{std}(u)},

    with :math:`\\bar c` the RGB mean of the linear radiance and the mean and standard
    deviation over the image's finite pixels (non-finite pixels become 0).

    Parameters
    ----------
    render : array_like, shape (H, W, 3) or (H, W)
        Linear radiance.

    Returns
    -------
    numpy.ndarray, float32, shape (H, W)

    Examples
    --------
    >>> x = network_input(np.array([[0.0, 1.0], [2.0, np.nan]]))
    >>> np.round(x.astype(float), 3).tolist()
    [[-1.414, 0.707], [0.707, 0.0]]
    """
    g = grey(render)
    finite = np.isfinite(g)
    u = linear_to_srgb(np.clip(np.where(finite, g, 0.0), 0.0, 1.0))
    values = u[finite]
    if values.size == 0:
        raise ValueError("the render has no finite pixel")
    std = values.std()
    x = (u - values.mean()) / (std if std > 0 else 1.0)
    return np.where(finite, x, 0.0).astype(np.float32)


def shift_columns(field, shift: int) -> np.ndarray:
    """Move a field by ``shift`` columns: ``out[:, x] = field[:, x - shift]``; the columns
    that have no source repeat the nearest edge column.

    Examples
    --------
    >>> shift_columns(np.arange(4.0)[None], 1).tolist()
    [[0.0, 0.0, 1.0, 2.0]]
    """
    a = np.asarray(field)
    width = a.shape[1]
    src = np.clip(np.arange(width) - int(shift), 0, width - 1)
    return a[:, src]


def counterfactual_pair(
    kind: str,
    left,
    right,
    mean_left,
    mean_right,
    *,
    sign: int,
    block: int = 16,
    shuffle_seed: int = 0,
    conflict_shift: int = 3,
    camera=None,
) -> tuple[np.ndarray, np.ndarray]:
    """One test pair of linear renders (see the module docstring for each ``kind``).

    Parameters
    ----------
    kind : str
        One of :data:`TEST_INPUTS`.
    left, right : numpy.ndarray, shape (H, W, 3)
        One seed's render of each view.
    mean_left, mean_right : numpy.ndarray, shape (H, W, 3)
        Each view's seed mean :math:`\\bar I_V`.
    sign : {1, -1}, keyword-only
        The ground truth's ``disparity_sign`` :math:`s`.
    block, shuffle_seed : int, keyword-only
        Block side and seed of :math:`\\Pi`
        (:func:`stereovar.intervention.shuffle.block_permutation`).
    conflict_shift : int, keyword-only
        :math:`k`, in pixels.
    camera : tuple of numpy.ndarray, optional, keyword-only
        ``(eta_left, eta_right)``: the camera's noise of each view, needed for ``camera``.

    Returns
    -------
    (left, right) : numpy.ndarray, float64, shape (H, W, 3)

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> m = rng.random((32, 32, 3)); r = m + rng.normal(size=m.shape)
    >>> _, right = counterfactual_pair("conflict", r, r, m, m, sign=1, conflict_shift=2)
    >>> bool(np.allclose(right[:, 5] - m[:, 5], r[:, 3] - m[:, 3]))
    True
    """
    if kind not in TEST_INPUTS:
        raise ValueError(f"unknown test input {kind!r}; use one of {', '.join(TEST_INPUTS)}")
    sign = int(sign)
    if sign not in (1, -1):
        raise ValueError(f"sign must be 1 or -1, got {sign}")
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    mean_left = np.asarray(mean_left, dtype=np.float64)
    mean_right = np.asarray(mean_right, dtype=np.float64)
    shapes = {a.shape for a in (left, right, mean_left, mean_right)}
    if len(shapes) != 1:
        raise ValueError(f"renders and seed means differ in shape: {sorted(shapes)}")
    if kind == "normal":
        return left, right
    if kind == "clean":
        return mean_left, mean_right
    if kind == "camera":
        if camera is None:
            raise ValueError("the camera test input needs camera=(eta_left, eta_right)")
        eta_l, eta_r = (np.asarray(e, dtype=np.float64) for e in camera)
        return mean_left + eta_l, mean_right + eta_r
    residual = right - mean_right
    if kind == "shuffled":
        height, width = residual.shape[:2]
        perm = block_permutation(height, width, block=block, seed=shuffle_seed)
        return left, mean_right + apply_block_permutation(residual, perm, block=block)
    return left, mean_right + shift_columns(residual, sign * int(conflict_shift))
