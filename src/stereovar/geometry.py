"""Rigid transforms and the pinhole camera model shared by the scene compiler and the rig.

Conventions (Mitsuba 3, and the paper's Sec. 2.2):

* World frame in metres with +y up.
* A camera built by ``look_at(origin, target, up)`` has camera-space +z forward, +y up and
  +x pointing to the image's *left* (``left = up x forward``).
* Continuous image coordinates ``(u, v)`` are in pixels, with ``u`` growing to the image's
  right and ``v`` growing downwards; the centre of pixel column ``i`` is at ``u = i + 0.5``.
"""

from __future__ import annotations

import numpy as np


def euler_rotation(degrees_xyz) -> np.ndarray:
    """Rotation matrix for Euler angles applied about x, then y, then z.

    Parameters
    ----------
    degrees_xyz : array_like, shape (3,)
        Angles in degrees.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        ``Rz @ Ry @ Rx``.
    """
    ax, ay, az = np.deg2rad(np.asarray(degrees_xyz, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def transform_matrix(*, translate=(0, 0, 0), rotate=(0, 0, 0), scale=(1, 1, 1)) -> np.ndarray:
    """Homogeneous object-to-world matrix ``T @ R @ S`` of a scene-spec transform.

    Parameters
    ----------
    translate, rotate, scale : array_like, shape (3,)
        Translation in metres, Euler angles in degrees (see :func:`euler_rotation`) and
        per-axis scale factors.

    Returns
    -------
    numpy.ndarray, shape (4, 4)
    """
    m = np.eye(4)
    m[:3, :3] = euler_rotation(rotate) @ np.diag(np.asarray(scale, dtype=np.float64))
    m[:3, 3] = np.asarray(translate, dtype=np.float64)
    return m


def object_matrix(obj: dict) -> np.ndarray:
    """Object-to-world matrix of a scene-spec entry with an optional ``transform`` block.

    Missing ``translate``, ``rotate`` or ``scale`` keys take their identity values; see
    :func:`transform_matrix`.
    """
    t = obj.get("transform", {})
    return transform_matrix(
        translate=t.get("translate", (0, 0, 0)),
        rotate=t.get("rotate", (0, 0, 0)),
        scale=t.get("scale", (1, 1, 1)),
    )


def camera_frame(origin, target, up) -> np.ndarray:
    """Orthonormal camera axes as Mitsuba's ``look_at`` builds them.

    Parameters
    ----------
    origin, target, up : array_like, shape (3,)
        Camera position, look-at point and approximate up vector (world frame).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Rows are the world-space camera axes ``x`` (image left), ``y`` (up) and ``z``
        (forward).

    Raises
    ------
    ValueError
        If ``target`` equals ``origin`` or ``up`` is parallel to the viewing direction.
    """
    origin = np.asarray(origin, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - origin
    norm = np.linalg.norm(forward)
    if norm == 0:
        raise ValueError("camera target equals its origin; move the target")
    forward /= norm
    left = np.cross(np.asarray(up, dtype=np.float64), forward)
    lnorm = np.linalg.norm(left)
    if lnorm < 1e-9:
        raise ValueError("camera up vector is parallel to the viewing direction; change 'up'")
    left /= lnorm
    return np.stack([left, np.cross(forward, left), forward])


def focal_length_px(fov_deg: float, width: int) -> float:
    """Focal length in pixels of a pinhole camera with horizontal field of view ``fov_deg``.

    .. math:: f = \\frac{W / 2}{\\tan(\\mathrm{fov}_x / 2)}
    """
    return 0.5 * width / np.tan(0.5 * np.deg2rad(fov_deg))


def project_points(points, *, origin, frame, focal_px: float, width: int, height: int):
    """Project world points into a pinhole camera (Sec. 2.2 ground truth).

    .. math::

        (x_c, y_c, z_c) = F\\,(P - O), \\qquad
        u = \\frac{W}{2} - f\\,\\frac{x_c}{z_c}, \\qquad
        v = \\frac{H}{2} - f\\,\\frac{y_c}{z_c}

    where ``F`` holds the camera axes of :func:`camera_frame` as rows. The minus signs come
    from Mitsuba's camera-space +x pointing to the image left and +y pointing up.

    Parameters
    ----------
    points : array_like, shape (..., 3)
        World-space points.
    origin : array_like, shape (3,)
        Camera centre.
    frame : array_like, shape (3, 3)
        Camera axes as rows, from :func:`camera_frame`.
    focal_px : float
        Focal length in pixels.
    width, height : int
        Image size in pixels.

    Returns
    -------
    u, v, z : numpy.ndarray, shape (...)
        Continuous image coordinates (pixel ``i`` has its centre at ``i + 0.5``) and planar
        depth along the optical axis. Points behind the camera get ``z <= 0``; their ``u``,
        ``v`` are NaN.
    """
    p = np.asarray(points, dtype=np.float64) - np.asarray(origin, dtype=np.float64)
    cam = p @ np.asarray(frame, dtype=np.float64).T
    z = cam[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(z > 0, 1.0 / np.where(z > 0, z, 1.0), np.nan)
    u = 0.5 * width - focal_px * cam[..., 0] * inv
    v = 0.5 * height - focal_px * cam[..., 1] * inv
    return u, v, z
