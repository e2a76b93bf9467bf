"""The stereo rig: the scene's camera as the left view and a translated copy as the right.

Two conventions are supported (paper Sec. 2.2, Eq. 2):

``paper``
    The right camera is the left one translated by the baseline along Mitsuba's camera-space
    +x axis, which points to the image's left. A scene point then appears further right in the
    right view: :math:`x_R = x_L + d` with :math:`d > 0`.
``conventional``
    The right camera sits to the image-right of the left one (translation along camera -x),
    as in a physical rig: :math:`x_R = x_L - d`.

Disparities are stored as positive magnitudes; ``disparity_sign`` (+1 or -1) records the
relation :math:`x_R = x_L + s\\,d`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import focal_length_px, project_points

CONVENTIONS = {"paper": 1, "conventional": -1}
VIEWS = ("left", "right")


@dataclass(frozen=True)
class StereoRig:
    """A rectified stereo pair of pinhole cameras.

    Attributes
    ----------
    to_world : dict of str to numpy.ndarray
        Camera-to-world matrices (4, 4) of ``"left"`` and ``"right"``.
    fov_deg : float
        Horizontal field of view (degrees), shared by both cameras.
    width, height : int
        Image size in pixels.
    baseline_m : float
        Distance between the camera centres in metres.
    convention : str
        ``"paper"`` or ``"conventional"``.
    """

    to_world: dict
    fov_deg: float
    width: int
    height: int
    baseline_m: float
    convention: str

    @property
    def disparity_sign(self) -> int:
        """``s`` in :math:`x_R = x_L + s\\,d`: +1 for ``paper``, -1 for ``conventional``."""
        return CONVENTIONS[self.convention]

    @property
    def focal_px(self) -> float:
        """Focal length in pixels."""
        return focal_length_px(self.fov_deg, self.width)

    def origin(self, view: str) -> np.ndarray:
        """Camera centre of ``view`` in world space."""
        return self.to_world[view][:3, 3].copy()

    def frame(self, view: str) -> np.ndarray:
        """Unit camera axes (x image-left, y up, z forward) of ``view`` as rows."""
        axes = self.to_world[view][:3, :3].T
        return axes / np.linalg.norm(axes, axis=1, keepdims=True)

    def pixel_rays(self, view: str) -> np.ndarray:
        """Float64 world directions (unnormalised, unit forward component) of the rays through
        each pixel centre of ``view``, shape (height, width, 3); inverse of :meth:`project`.
        """
        u = np.arange(self.width) + 0.5
        v = np.arange(self.height) + 0.5
        xc = np.broadcast_to(
            -(u[None, :] - 0.5 * self.width) / self.focal_px, (self.height, self.width)
        )
        yc = np.broadcast_to(
            -(v[:, None] - 0.5 * self.height) / self.focal_px, (self.height, self.width)
        )
        cam = np.stack([xc, yc, np.ones_like(xc)], axis=-1)
        return cam @ self.frame(view)

    def project(self, points, view: str):
        """Project world points into ``view``; see :func:`stereovar.geometry.project_points`."""
        return project_points(
            points,
            origin=self.origin(view),
            frame=self.frame(view),
            focal_px=self.focal_px,
            width=self.width,
            height=self.height,
        )


def make_rig(
    camera_to_world, fov_deg: float, *, width: int, height: int, baseline_m: float, convention: str
) -> StereoRig:
    """Build the rig from the scene camera (the left view).

    .. math::

        O_R = O_L + s\\,B\\,\\hat{x}_L, \\qquad
        s = +1\\ (\\text{paper}),\\ -1\\ (\\text{conventional})

    where :math:`\\hat{x}_L` is the left camera's unit camera-space +x axis in world space
    (the image-left direction) and :math:`B` the baseline; the orientation is shared.

    Parameters
    ----------
    camera_to_world : array_like, shape (4, 4)
        The scene camera's camera-to-world matrix.
    fov_deg : float
        Horizontal field of view in degrees.
    width, height : int
        Image size in pixels.
    baseline_m : float
        Baseline in metres (> 0).
    convention : {"paper", "conventional"}
        Which side the second camera goes.

    Returns
    -------
    StereoRig
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"rig convention {convention!r} is not one of {sorted(CONVENTIONS)}")
    if not baseline_m > 0:
        raise ValueError(f"rig baseline must be positive, got {baseline_m}")
    left = np.asarray(camera_to_world, dtype=np.float64).reshape(4, 4).copy()
    x_axis = left[:3, 0] / np.linalg.norm(left[:3, 0])
    right = left.copy()
    right[:3, 3] += CONVENTIONS[convention] * baseline_m * x_axis
    return StereoRig(
        to_world={"left": left, "right": right},
        fov_deg=float(fov_deg),
        width=int(width),
        height=int(height),
        baseline_m=float(baseline_m),
        convention=convention,
    )
