"""The zero-cost route to N = 2 for new data (docs/single_render.md): each view rendered as
two seeds at half the SPP, whose mean ships. With the independent sampler and the box
filter, that mean is distributed as one render at the full SPP, so the shipped image is
unchanged and the audit gets its two seeds."""

import numpy as np

from stereovar.estimators.seeds import variance_field

from .test_ground_truth import REPO

RIG = {"width": 128, "height": 72, "baseline_m": 0.026, "convention": "paper"}
N = 8


def _renders(mi, spp: int, seeds) -> np.ndarray:
    from stereovar.renderers.mitsuba.render import render_view
    from stereovar.renderers.mitsuba.scene import load_scene
    from stereovar.rig import make_rig
    from stereovar.scenes.spec import load_scene_spec

    scene, cam = load_scene(mi, load_scene_spec(REPO / "scenes/scene_001.yaml"))
    rig = make_rig(cam.to_world, cam.fov_deg, **RIG)
    return np.stack([render_view(mi, scene, rig, "left", spp=spp, seed=s) for s in seeds])


def test_the_mean_of_two_half_spp_renders_is_one_full_spp_render(mi):
    """Eq. 1 over N pair means of half-SPP renders equals Eq. 1 over N full-SPP renders: the
    per-pixel ratio of the two fields has median 1 (two fields of one distribution: their
    log-ratio is symmetric about 0), where Eq. 1 over the half-SPP renders themselves reads
    twice the variance. The images agree in the mean too."""
    halves = _renders(mi, 2, range(100, 100 + 2 * N))
    full = _renders(mi, 4, range(200, 200 + N))
    pairs = 0.5 * (halves[0::2] + halves[1::2])
    mean_pairs, var_pairs = variance_field(pairs)
    mean_full, var_full = variance_field(full)
    _, var_halves = variance_field(halves[:N])
    ok = (var_pairs > 0) & (var_full > 0) & (var_halves > 0)
    assert ok.mean() > 0.5
    ratio = float(np.median(var_pairs[ok] / var_full[ok]))
    assert abs(ratio - 1.0) < 0.08, ratio
    assert abs(float(np.median(var_halves[ok] / var_full[ok])) - 2.0) < 0.2
    # the two means differ by their own noise only (green channel): the difference over
    # its standard error is about standard normal, |z| with the half-normal's median
    diff = mean_pairs[..., 1] - mean_full[..., 1]
    se = np.sqrt((pairs[..., 1].var(axis=0, ddof=1) + full[..., 1].var(axis=0, ddof=1)) / N)
    z = diff[ok] / se[ok]
    assert abs(float(np.median(np.abs(z))) - 0.674) < 0.1
