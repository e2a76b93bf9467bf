"""The scalar variant (the fallback without libLLVM) builds and renders the committed scenes."""

import subprocess
import sys

import numpy as np

SCRIPT = r"""
import json, sys
import numpy as np
from stereovar.renderers.mitsuba.backend import load_mitsuba
from stereovar.renderers.mitsuba.scene import load_scene
from stereovar.renderers.mitsuba.render import render_view
from stereovar.renderers.mitsuba.sensor import integrator_dict
from stereovar.rig import make_rig
from stereovar.scenes.spec import load_scene_spec

mi = load_mitsuba(sys.argv[1])
scene, cam = load_scene(mi, load_scene_spec("scenes/scene_000.yaml"))
boxes = {s.id(): [list(map(float, s.bbox().min)), list(map(float, s.bbox().max))]
         for s in scene.shapes() if s.is_mesh()}
rig = make_rig(cam.to_world, cam.fov_deg, width=16, height=9, baseline_m=0.026,
               convention="paper")
image = np.asarray(render_view(mi, scene, rig, "left", spp=1, seed=1,
                               integrator=integrator_dict("path", 4), rfilter="box",
                               sampler="independent"))
print(json.dumps({"boxes": boxes, "shape": list(image.shape),
                  "finite": bool(np.isfinite(image).all())}))
"""


def run(variant):
    import json

    out = subprocess.run(
        [sys.executable, "-c", SCRIPT, variant], capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_lathe_meshes_match_between_scalar_and_llvm_variants():
    scalar, llvm = run("scalar_rgb"), run("llvm_ad_rgb")
    assert any("vase" in name for name in scalar["boxes"])  # scene_000 has a lathe mesh
    assert scalar["boxes"].keys() == llvm["boxes"].keys()
    for name, box in scalar["boxes"].items():
        np.testing.assert_allclose(box, llvm["boxes"][name], rtol=1e-6, atol=1e-6)
    assert scalar["shape"] == llvm["shape"] == [9, 16, 3]
    assert scalar["finite"] and llvm["finite"]
