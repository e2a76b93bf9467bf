"""The photometric check that settles the disparity sign (paper Eq. 2).

A Lambertian, textured scene looks the same from both cameras, so warping the clean right
render into the left view with the ground-truth disparity must reproduce the left render up
to Monte Carlo noise and interpolation. Warping with the opposite sign must not.
"""

import pytest

from stereovar.audit.sign import median_relative_error
from stereovar.ground_truth import compute_ground_truth
from stereovar.renderers.mitsuba import MitsubaScene
from stereovar.renderers.mitsuba.render import render_view
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.rig import make_rig
from stereovar.seeding import derive_seed
from stereovar.statistics.warp import warp_right_to_left

WIDTH, HEIGHT, SPP, BASELINE = 128, 72, 2048, 0.08


def lambertian_spec():
    """A textured box room with diffuse blocks at several depths, lit by a large panel."""

    def tex(seed, colors):
        return {
            "pattern": "noise",
            "colors": colors,
            "repeat": [1.0, 1.0],
            "seed": seed,
            "resolution": 128,
        }

    def wall(name, translate, rotate, scale):
        return {
            "name": name,
            "shape": "rectangle",
            "material": name,
            "transform": {"translate": translate, "rotate": rotate, "scale": scale},
        }

    textures = {
        "back": tex(1, [[0.25, 0.25, 0.25], [0.85, 0.75, 0.55]]),
        "floor": tex(2, [[0.2, 0.25, 0.3], [0.8, 0.8, 0.85]]),
        "left": tex(3, [[0.35, 0.2, 0.2], [0.9, 0.65, 0.55]]),
        "right": tex(4, [[0.2, 0.35, 0.2], [0.55, 0.9, 0.65]]),
        "block": tex(5, [[0.2, 0.2, 0.4], [0.9, 0.9, 0.65]]),
    }
    materials = {k: {"type": "diffuse", "texture": k} for k in textures}
    materials["ceiling"] = {"type": "diffuse", "reflectance": [0.7, 0.7, 0.7]}
    objects = [
        wall("back", [0, 1.5, 5.0], [0, 180, 0], [3, 1.5, 1]),
        wall("floor", [0, 0, 2.5], [-90, 0, 0], [3, 2.5, 1]),
        wall("ceiling", [0, 3.0, 2.5], [90, 0, 0], [3, 2.5, 1]),
        wall("left", [3.0, 1.5, 2.5], [0, -90, 0], [2.5, 1.5, 1]),
        wall("right", [-3.0, 1.5, 2.5], [0, 90, 0], [2.5, 1.5, 1]),
    ]
    for k, (x, z, s) in enumerate([(0.6, 2.2, 0.3), (-0.7, 3.2, 0.4), (0.0, 4.0, 0.5)]):
        objects.append(
            {
                "name": f"block{k}",
                "shape": "box",
                "material": "block",
                "transform": {"translate": [x, s, z], "rotate": [0, 25 * k, 0], "scale": [s, s, s]},
            }
        )
    return {
        "name": "lambertian",
        "camera": {
            "origin": [0, 1.3, -0.2],
            "target": [0, 0.9, 4.0],
            "up": [0, 1, 0],
            "fov_deg": 70,
        },
        "textures": textures,
        "materials": materials,
        "objects": objects,
        "lights": [
            {
                "name": "panel",
                "radiance": [3, 3, 3],
                "transform": {
                    "translate": [0, 2.95, 1.5],
                    "rotate": [90, 0, 0],
                    "scale": [2.5, 1.2, 1],
                },
            }
        ],
    }


@pytest.fixture(scope="module")
def lambertian(mi):
    return load_scene(mi, lambertian_spec())


@pytest.mark.parametrize("convention", ["paper", "conventional"])
def test_clean_right_view_warps_onto_left(mi, lambertian, convention):
    scene, cam = lambertian
    rig = make_rig(
        cam.to_world,
        cam.fov_deg,
        width=WIDTH,
        height=HEIGHT,
        baseline_m=BASELINE,
        convention=convention,
    )
    gt = compute_ground_truth(MitsubaScene(rig, mi=mi, scene=scene)).sel(view="left")
    images = {
        view: render_view(
            mi, scene, rig, view, spp=SPP, seed=derive_seed("photometric", convention, view)
        )
        for view in ("left", "right")
    }
    mask_base = gt.valid.values & ~gt.glass.values & ~gt.occluded.values
    sign = int(gt.attrs["disparity_sign"])
    warped, omega = warp_right_to_left(
        images["right"], gt.disparity.values, sign=sign, valid=mask_base
    )
    assert omega.mean() > 0.8
    error = median_relative_error(images["left"], warped, omega)
    wrong, omega_wrong = warp_right_to_left(
        images["right"], gt.disparity.values, sign=-sign, valid=mask_base
    )
    error_wrong = median_relative_error(images["left"], wrong, omega_wrong)
    print(
        f"{convention}: median relative error {100 * error:.2f}% with the recorded sign, "
        f"{100 * error_wrong:.2f}% with the opposite sign"
    )
    assert error < 0.03
    assert error_wrong > 2 * error
