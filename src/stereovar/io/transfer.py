"""The sRGB transfer function of integer images, decoding and encoding.

Integer images (PNG, BlenderProc's 8-bit colors) store linear values or sRGB-encoded ones (IEC
61966-2-1): :func:`srgb_to_linear` decodes them, :func:`linear_to_srgb` encodes.
"""

from __future__ import annotations

import numpy as np

TRANSFERS = ("linear", "srgb")
"""Transfer functions of integer images: stored values are linear, or sRGB-encoded."""


def srgb_to_linear(v):
    r"""The sRGB decoding function (IEC 61966-2-1) on values in [0, 1].

    .. math::

        L = \begin{cases} V / 12.92 & V \le 0.04045 \\
            \left(\frac{V + 0.055}{1.055}\right)^{2.4} & \text{otherwise} \end{cases}
    """
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(v):
    r"""The sRGB encoding function (IEC 61966-2-1), the inverse of :func:`srgb_to_linear`.

    .. math::

        V = \begin{cases} 12.92\,L & L \le 0.0031308 \\
            1.055\,L^{1/2.4} - 0.055 & \text{otherwise} \end{cases}
    """
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, None)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
