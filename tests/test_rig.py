"""The stereo rig and the pinhole projection against Mitsuba's own camera rays."""

import numpy as np
import pytest

from stereovar.geometry import camera_frame, focal_length_px, transform_matrix
from stereovar.ground_truth import compute_ground_truth
from stereovar.renderers.mitsuba import MitsubaScene
from stereovar.renderers.mitsuba.scene import camera_from_spec, load_scene
from stereovar.renderers.mitsuba.sensor import sensor_dict
from stereovar.rig import make_rig


def plane_spec(depth=3.0, fov=60.0):
    """A diffuse fronto-parallel wall at planar depth ``depth`` in front of the camera."""
    return {
        "name": "plane",
        "camera": {
            "origin": [0.2, 1.0, -0.5],
            "target": [0.2, 1.0, 1.0],
            "up": [0, 1, 0],
            "fov_deg": fov,
        },
        "textures": {},
        "materials": {"grey": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
        "objects": [
            {
                "name": "wall",
                "shape": "rectangle",
                "material": "grey",
                "transform": {
                    "translate": [0.2, 1.0, -0.5 + depth],
                    "rotate": [0, 180, 0],
                    "scale": [20, 20, 1],
                },
            }
        ],
        "lights": [],
    }


def test_right_camera_is_left_translated_along_camera_x():
    cam = camera_from_spec(plane_spec())
    for convention, sign in (("paper", 1), ("conventional", -1)):
        rig = make_rig(
            cam.to_world, 60, width=32, height=18, baseline_m=0.026, convention=convention
        )
        frame = camera_frame([0.2, 1.0, -0.5], [0.2, 1.0, 1.0], [0, 1, 0])
        np.testing.assert_allclose(
            rig.origin("right") - rig.origin("left"), sign * 0.026 * frame[0], atol=1e-12
        )
        np.testing.assert_allclose(rig.frame("right"), rig.frame("left"))
        assert rig.disparity_sign == sign


def test_camera_x_axis_points_to_image_left():
    """A point displaced along camera +x lands at a smaller column (Mitsuba convention)."""
    cam = camera_from_spec(plane_spec())
    rig = make_rig(cam.to_world, 60, width=64, height=36, baseline_m=0.1, convention="paper")
    centre = rig.origin("left") + 2.0 * rig.frame("left")[2]
    u0, _, _ = rig.project(centre, "left")
    u1, _, _ = rig.project(centre + 0.1 * rig.frame("left")[0], "left")
    assert u1 < u0
    # Paper convention: the right camera moved along +x, so the point appears further right.
    ur, _, _ = rig.project(centre, "right")
    assert ur > u0


def test_projection_inverts_mitsuba_camera_rays(mi):
    rng = np.random.default_rng(0)
    width, height = 40, 24
    m = transform_matrix(translate=[1, 2, 3], rotate=[10, 35, -5])
    rig = make_rig(m, 55.0, width=width, height=height, baseline_m=0.05, convention="paper")
    sensor = mi.load_dict(sensor_dict(mi, rig, "left"))
    uv = rng.uniform(0.05, 0.95, size=(50, 2))
    for s in uv:
        ray, _ = sensor.sample_ray(
            0.0, 0.5, mi.Point2f(float(s[0]), float(s[1])), mi.Point2f(0.5, 0.5), True
        )
        t = rng.uniform(0.5, 9.0)
        p = np.array([ray.o[i] + t * ray.d[i] for i in range(3)], dtype=np.float64).ravel()
        u, v, _ = rig.project(p, "left")
        np.testing.assert_allclose([u, v], [s[0] * width, s[1] * height], atol=2e-3)


@pytest.mark.parametrize("convention", ["paper", "conventional"])
def test_disparity_is_f_b_over_z_on_fronto_parallel_plane(mi, convention):
    depth, width, height, baseline = 2.5, 64, 36, 0.026
    spec = plane_spec(depth)
    scene, cam = load_scene(mi, spec)
    rig = make_rig(
        cam.to_world,
        cam.fov_deg,
        width=width,
        height=height,
        baseline_m=baseline,
        convention=convention,
    )
    ds = compute_ground_truth(MitsubaScene(rig, mi=mi, scene=scene))
    expected = focal_length_px(60.0, width) * baseline / depth
    for view in ("left", "right"):
        g = ds.sel(view=view)
        valid = g.valid.values
        assert valid.sum() > 0.9 * width * height
        np.testing.assert_allclose(g.disparity.values[valid], expected, rtol=1e-4)
        np.testing.assert_allclose(g.depth.values, depth, rtol=1e-5)
    assert ds.attrs["max_vertical_disparity_px"] < 1e-3
    assert ds.attrs["disparity_sign"] == (1 if convention == "paper" else -1)
    # The correspondence leaves the other image exactly where x +/- d leaves [0, W - 1].
    cols = np.arange(width) + ds.attrs["disparity_sign"] * expected
    inside = (cols >= 0) & (cols <= width - 1)
    np.testing.assert_array_equal(
        ds.valid.sel(view="left").values, np.broadcast_to(inside, (height, width))
    )
