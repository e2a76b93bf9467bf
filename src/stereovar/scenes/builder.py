"""The scene builder of the generator (:mod:`stereovar.scenes.generate`): a mutable draft of
one scene's textures, materials, objects and lights (:class:`SceneDraft`), its palette and its
room (floor, ceiling and four walls facing inwards), and the small geometric helpers the
layout uses.
"""

from __future__ import annotations

import colorsys
import math

import numpy as np

from ..geometry import euler_rotation

#: Metals the generator uses: every metal the scene schema allows.
_METALS = ("Al", "Ag", "Au", "Cu", "Cr", "W")


# --------------------------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------------------------


def rounded(x, nd: int = 4):
    """Round a number or a nested list to ``nd`` decimals as plain Python floats."""
    if isinstance(x, (list, tuple, np.ndarray)):
        return [rounded(v, nd) for v in x]
    v = round(float(x), nd)
    return 0.0 if v == 0 else v


def _linear(rgb_srgb) -> list[float]:
    """sRGB-encoded colour in [0, 1] to linear albedo."""
    c = np.clip(np.asarray(rgb_srgb, dtype=np.float64), 0.0, 1.0)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return rounded(lin, 4)


def _hsv(h, s, v) -> list[float]:
    """Linear albedo of an sRGB colour given in HSV (all in [0, 1], hue wraps)."""
    return _linear(colorsys.hsv_to_rgb(h % 1.0, float(np.clip(s, 0, 1)), float(np.clip(v, 0, 1))))


def yaw_matrix(yaw_deg: float) -> np.ndarray:
    return euler_rotation([0.0, yaw_deg, 0.0])


def floor_footprint(center_xz, half_xz, yaw_deg):
    """Axis-aligned (xmin, xmax, zmin, zmax) of a yawed rectangle on the floor."""
    c, s = abs(math.cos(math.radians(yaw_deg))), abs(math.sin(math.radians(yaw_deg)))
    ex = c * half_xz[0] + s * half_xz[1]
    ez = s * half_xz[0] + c * half_xz[1]
    return (center_xz[0] - ex, center_xz[0] + ex, center_xz[1] - ez, center_xz[1] + ez)


def overlaps(a, b, margin: float = 0.0) -> bool:
    return not (
        a[1] + margin <= b[0]
        or b[1] + margin <= a[0]
        or a[3] + margin <= b[2]
        or b[3] + margin <= a[2]
    )


# --------------------------------------------------------------------------------------------
# scene builder
# --------------------------------------------------------------------------------------------


class SceneDraft:
    """Mutable accumulator of one scene's textures, materials, objects and lights."""

    def __init__(self, rng: np.random.Generator, width: float, height: float, depth: float):
        self.rng = rng
        self.W, self.H, self.D = width, height, depth
        self.textures: dict[str, dict] = {}
        self.materials: dict[str, dict] = {}
        self.objects: list[dict] = []
        self.lights: list[dict] = []
        self.blocked: list[tuple] = []  # floor footprints (xmin, xmax, zmin, zmax, ymax)
        self.counts: dict[str, int] = {}
        self.glass_names: list[str] = []

    def name(self, stem: str) -> str:
        k = self.counts.get(stem, 0)
        self.counts[stem] = k + 1
        return f"{stem}_{k}"

    def texture(self, name, pattern, colors, *, repeat=(1.0, 1.0), resolution=512):
        self.textures[name] = {
            "pattern": pattern,
            "colors": [rounded(c) for c in colors],
            "repeat": rounded(repeat),
            "seed": int(self.rng.integers(0, 2**31 - 1)),
            "resolution": int(resolution),
        }
        return name

    def material(self, name, **kw):
        self.materials[name] = {
            k: (rounded(v) if k in ("reflectance", "tint") else v) for k, v in kw.items()
        }
        for key in ("roughness", "ior"):
            if key in self.materials[name]:
                self.materials[name][key] = rounded(self.materials[name][key])
        return name

    def add(self, stem, shape, material, *, translate, rotate=(0, 0, 0), scale=(1, 1, 1), **extra):
        name = self.name(stem)
        obj = {
            "name": name,
            "shape": shape,
            "material": material,
            "transform": {
                "translate": rounded(translate),
                "rotate": rounded(rotate),
                "scale": rounded(scale),
            },
        }
        obj.update(extra)
        self.objects.append(obj)
        if self.materials[material]["type"] == "glass":
            self.glass_names.append(name)
        return obj

    def box(self, stem, material, origin, yaw, center_local, half):
        """A box whose centre is ``center_local`` in the frame (origin, yaw)."""
        c = np.asarray(origin, float) + yaw_matrix(yaw) @ np.asarray(center_local, float)
        return self.add(stem, "box", material, translate=c, rotate=(0, yaw, 0), scale=half)

    def cylinder(self, stem, material, base, radius, height, yaw=0.0):
        return self.add(
            stem,
            "cylinder",
            material,
            translate=base,
            rotate=(0, yaw, 0),
            scale=(radius, height, radius),
        )

    def sphere(self, stem, material, center, radius):
        return self.add(stem, "sphere", material, translate=center, scale=(radius,) * 3)

    def lathe(self, stem, material, base, profile, yaw=0.0):
        return self.add(
            stem,
            "lathe",
            material,
            translate=base,
            rotate=(0, yaw, 0),
            profile=[rounded(p) for p in profile],
            segments=96,
        )

    def free(self, fp, margin=0.05) -> bool:
        """Whether a floor footprint lies inside the room and clear of other furniture."""
        if fp[0] < -self.W / 2 + 0.01 or fp[1] > self.W / 2 - 0.01:
            return False
        if fp[2] < 0.01 or fp[3] > self.D - 0.01:
            return False
        return not any(overlaps(fp, b[:4], margin) for b in self.blocked)


# --------------------------------------------------------------------------------------------
# palette, room, materials
# --------------------------------------------------------------------------------------------


def add_palette(sc: SceneDraft) -> None:
    """Per-scene colours, textures and materials."""
    rng = sc.rng
    W, H, D = sc.W, sc.H, sc.D
    base_hue = rng.random()
    warm = rng.random() < 0.6

    # floor
    floor_pattern = rng.choice(["planks", "planks", "planks", "tiles", "checker"])
    if floor_pattern == "planks":
        h = rng.uniform(0.05, 0.11)
        v = rng.uniform(0.35, 0.75)
        cols = [
            _hsv(h, rng.uniform(0.45, 0.75), v),
            _hsv(h + 0.01, 0.7, v * 0.55),
            _hsv(h - 0.01, 0.5, min(1.0, v * 1.25)),
        ]
        tile = rng.uniform(1.2, 2.2)
    elif floor_pattern == "tiles":
        h = base_hue + rng.uniform(-0.1, 0.1)
        v = rng.uniform(0.55, 0.85)
        cols = [
            _hsv(h, rng.uniform(0.05, 0.35), v),
            _hsv(h + 0.05, rng.uniform(0.1, 0.4), v * 0.8),
            _hsv(h, 0.1, rng.uniform(0.2, 0.4)),
        ]
        tile = rng.uniform(1.0, 1.8)
    else:
        h = base_hue
        cols = [
            _hsv(h, rng.uniform(0.0, 0.2), rng.uniform(0.75, 0.9)),
            _hsv(h + 0.5, rng.uniform(0.1, 0.5), rng.uniform(0.15, 0.35)),
        ]
        tile = rng.uniform(1.2, 2.4)
    sc.texture("floor", str(floor_pattern), cols, repeat=(W / tile, D / tile), resolution=1024)
    sc.material("floor", type="diffuse", texture="floor")

    # walls: plaster or wallpaper, an accent back wall half of the time
    wall_h = base_hue + (0.08 if warm else 0.55) + rng.uniform(-0.05, 0.05)
    wall_v = rng.uniform(0.7, 0.92)
    wall_pattern = rng.choice(["noise", "noise", "stripes", "stripes", "tiles"])
    wcols = [
        _hsv(wall_h, rng.uniform(0.05, 0.3), wall_v),
        _hsv(wall_h + 0.03, rng.uniform(0.1, 0.35), wall_v * rng.uniform(0.7, 0.85)),
    ]
    if wall_pattern == "stripes":
        wcols.append(_hsv(wall_h + rng.uniform(0.3, 0.7), rng.uniform(0.3, 0.6), wall_v * 0.75))
    if wall_pattern == "tiles":
        wcols.append(_hsv(wall_h, 0.05, 0.45))
    wtile = rng.uniform(1.0, 2.0)
    sc.texture(
        "wall", str(wall_pattern), wcols, repeat=(max(W, D) / wtile, H / wtile), resolution=1024
    )
    sc.material("wall", type="diffuse", texture="wall")
    if rng.random() < 0.5:
        ah = rng.random()
        acols = [
            _hsv(ah, rng.uniform(0.2, 0.6), rng.uniform(0.5, 0.85)),
            _hsv(ah + 0.05, rng.uniform(0.2, 0.6), rng.uniform(0.3, 0.6)),
            _hsv(ah + 0.5, rng.uniform(0.0, 0.3), rng.uniform(0.7, 0.9)),
        ]
        apat = str(rng.choice(["stripes", "noise", "checker", "tiles"]))
        atile = rng.uniform(0.8, 1.6)
        sc.texture("accent", apat, acols, repeat=(W / atile, H / atile), resolution=1024)
        sc.material("accent", type="diffuse", texture="accent")
    else:
        sc.material("accent", type="diffuse", texture="wall")

    sc.texture(
        "ceiling",
        "noise",
        [_hsv(wall_h, 0.04, 0.9), _hsv(wall_h, 0.06, 0.78)],
        repeat=(W / 1.5, D / 1.5),
        resolution=512,
    )
    sc.material("ceiling", type="diffuse", texture="ceiling")

    # furniture woods
    for name in ("wood", "wood2"):
        h = rng.uniform(0.04, 0.11)
        v = rng.uniform(0.3, 0.8)
        sc.texture(
            name,
            "grain",
            [
                _hsv(h, rng.uniform(0.4, 0.7), v),
                _hsv(h, 0.75, v * 0.5),
                _hsv(h, 0.5, min(1.0, v * 1.2)),
            ],
            repeat=(1.0, 1.0),
            resolution=512,
        )
        if name == "wood2" and rng.random() < 0.5:  # lacquered wood: glossy with grain
            sc.material(
                name,
                type="glossy",
                texture=name,
                reflectance=sc.textures[name]["colors"][0],
                roughness=float(rng.uniform(0.05, 0.3)),
                ior=1.5,
            )
        else:
            sc.material(name, type="diffuse", texture=name)

    # cardboard / fabric-like noise for boxes
    ch = rng.uniform(0.06, 0.12)
    sc.texture(
        "cardboard",
        "noise",
        [_hsv(ch, 0.5, 0.7), _hsv(ch, 0.6, 0.5), _hsv(ch, 0.4, 0.8)],
        resolution=256,
    )
    sc.material("cardboard", type="diffuse", texture="cardboard")
    ph = rng.random()
    sc.texture(
        "print",
        str(rng.choice(["checker", "stripes", "tiles"])),
        [
            _hsv(ph, rng.uniform(0.3, 0.8), rng.uniform(0.5, 0.9)),
            _hsv(ph + 0.4, rng.uniform(0.3, 0.8), rng.uniform(0.2, 0.6)),
            _hsv(ph + 0.7, 0.2, 0.85),
        ],
        resolution=256,
    )
    sc.material("patterned", type="diffuse", texture="print")

    # glossy plastics
    for k in range(3):
        sc.material(
            f"plastic_{k}",
            type="glossy",
            reflectance=_hsv(rng.random(), rng.uniform(0.4, 0.9), rng.uniform(0.4, 0.9)),
            roughness=float(rng.choice([0.0, rng.uniform(0.05, 0.35)])),
            ior=float(rng.uniform(1.45, 1.6)),
        )
    sc.material(
        "paint",
        type="glossy",
        reflectance=_hsv(rng.random(), rng.uniform(0.1, 0.6), rng.uniform(0.5, 0.9)),
        roughness=float(rng.uniform(0.1, 0.4)),
        ior=1.5,
    )
    # metals
    metals = rng.choice(_METALS, size=2, replace=False)
    sc.material(
        "metal_0",
        type="conductor",
        metal=str(metals[0]),
        roughness=float(rng.choice([0.0, rng.uniform(0.05, 0.3)])),
    )
    sc.material(
        "metal_1", type="conductor", metal=str(metals[1]), roughness=float(rng.uniform(0.1, 0.4))
    )
    # glass: clear and slightly tinted
    sc.material("glass", type="glass", ior=float(rng.uniform(1.45, 1.55)), roughness=0.0)
    tint = _hsv(rng.random(), rng.uniform(0.05, 0.3), 1.0)
    sc.material(
        "glass_tinted", type="glass", ior=float(rng.uniform(1.45, 1.6)), roughness=0.0, tint=tint
    )


def add_room(sc: SceneDraft) -> None:
    """Floor, ceiling and four walls as inward-facing rectangles (overlapping by 1 cm)."""
    W, H, D = sc.W, sc.H, sc.D
    e = 0.01
    sc.add(
        "floor",
        "rectangle",
        "floor",
        translate=(0, 0, D / 2),
        rotate=(-90, 0, 0),
        scale=(W / 2 + e, D / 2 + e, 1),
    )
    sc.add(
        "ceiling",
        "rectangle",
        "ceiling",
        translate=(0, H, D / 2),
        rotate=(90, 0, 0),
        scale=(W / 2 + e, D / 2 + e, 1),
    )
    sc.add(
        "wall_back",
        "rectangle",
        "accent",
        translate=(0, H / 2, D),
        rotate=(0, 180, 0),
        scale=(W / 2 + e, H / 2 + e, 1),
    )
    sc.add(
        "wall_front",
        "rectangle",
        "wall",
        translate=(0, H / 2, 0),
        rotate=(0, 0, 0),
        scale=(W / 2 + e, H / 2 + e, 1),
    )
    sc.add(
        "wall_left",
        "rectangle",
        "wall",
        translate=(-W / 2, H / 2, D / 2),
        rotate=(0, 90, 0),
        scale=(D / 2 + e, H / 2 + e, 1),
    )
    sc.add(
        "wall_right",
        "rectangle",
        "wall",
        translate=(W / 2, H / 2, D / 2),
        rotate=(0, -90, 0),
        scale=(D / 2 + e, H / 2 + e, 1),
    )
