"""Render N seeds per view of the open Blender scene with Cycles, and write the files and the
audit.yaml that ``stereovar audit`` reads.

Run it in Blender on your scene, with your generator's render settings as they ship (only the
seed changes between renders)::

    blender -b scene.blend -P render_seeds.py -- OUT N_SEEDS BASELINE_M

(or ``python render_seeds.py OUT N_SEEDS BASELINE_M`` with the ``bpy`` module, after opening
the scene), then ``stereovar audit OUT/audit.yaml``. The scene's camera is the left view; the
right view is the same camera moved BASELINE_M along its own x axis (to the image's right:
x_R = x_L - d, the conventional rig). Each render is a 32-bit float multilayer EXR holding the
render (ViewLayer.Combined) and Blender's planar depth (ViewLayer.Depth.Z), which the audit
picks by name. Where the scene's Cycles denoiser is on, each EXR also keeps the render
before it (ViewLayer.Noisy Image), and OUT/audit_noisy.yaml audits that, so the audit can
measure the cue before and after the denoiser.
"""

import re
import sys
from pathlib import Path

import bpy
import mathutils

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
OUT = Path(args[0] if args else "stereo_audit").resolve()
N_SEEDS = int(args[1]) if len(args) > 1 else 16
BASELINE_M = float(args[2]) if len(args) > 2 else 0.065

scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.use_animated_seed = False  # the seed below is the only one
scene.render.use_multiview = False
bpy.context.view_layer.use_pass_z = True  # planar depth, the audit's ground truth
DENOISED = bool(scene.cycles.use_denoising)
if DENOISED:  # keep the render before the denoiser too: ViewLayer.Noisy Image
    bpy.context.view_layer.cycles.denoising_store_passes = True
image = scene.render.image_settings
if hasattr(image, "media_type"):  # Blender 5: multilayer EXR is a media type
    image.media_type = "MULTI_LAYER_IMAGE"
image.file_format = "OPEN_EXR_MULTILAYER"
image.color_depth = "32"  # float: half floats would quantise the noise

left = scene.camera
right = left.copy()
right.data = left.data.copy()
scene.collection.objects.link(right)
right.matrix_world = left.matrix_world @ mathutils.Matrix.Translation((BASELINE_M, 0.0, 0.0))

for view, camera in (("L", left), ("R", right)):
    scene.camera = camera
    for s in range(N_SEEDS):
        # independent seeds: every render and view its own (to audit a generator that
        # shares one seed between the views, give both views the same seed here)
        scene.cycles.seed = 1 + s + (N_SEEDS if view == "R" else 0)
        scene.render.filepath = str(OUT / view / f"seed_{s:03d}.exr")
        bpy.ops.render.render(write_still=True)
scene.camera = left
bpy.data.objects.remove(right)

# the focal length in pixels (square pixels; Blender's sensor fit)
lens, render = left.data, scene.render
width = render.resolution_x * render.resolution_percentage / 100
height = render.resolution_y * render.resolution_percentage / 100
if lens.sensor_fit == "AUTO":  # the sensor width spans the longer side
    fit, sensor = ("HORIZONTAL" if width >= height else "VERTICAL"), lens.sensor_width
else:
    fit = lens.sensor_fit
    sensor = lens.sensor_width if fit == "HORIZONTAL" else lens.sensor_height
focal_px = lens.lens / sensor * (width if fit == "HORIZONTAL" else height)
name = re.sub(r"[^A-Za-z0-9_-]", "_", OUT.name)
audit = (
    f"  renders: {OUT}/{{view}}/seed_{{seed}}.exr\n"
    "  views: {left: L, right: R}\n"
    f"  depth: {OUT}/{{view}}/seed_000.exr\n"
    f"  focal_px: {focal_px!r}\n"
    f"  baseline_m: {BASELINE_M!r}\n"
    "  convention: conventional\n"
    f"  spp: {scene.cycles.samples}\n"
)
(OUT / "audit.yaml").write_text(f"audit:\n  name: {name}\n" + audit)
if DENOISED:
    (OUT / "audit_noisy.yaml").write_text(
        f"audit:\n  name: {name}_noisy\n" + audit
        + "  channels: {render: ViewLayer.Noisy Image}\n"
    )
print(f"wrote {2 * N_SEEDS} renders and {OUT / 'audit.yaml'}"
      + (f" and {OUT / 'audit_noisy.yaml'}" if DENOISED else ""))
