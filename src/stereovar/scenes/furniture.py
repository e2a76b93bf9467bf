"""Furniture and glass objects of the generator (:mod:`stereovar.scenes.generate`): tables,
shelves, cabinets and box stacks resting on the floor, small glossy and metallic props on
their surfaces, and glass spheres, panes, lathe vases and cylinders, each added to a
:class:`~stereovar.scenes.builder.SceneDraft`.
"""

from __future__ import annotations

import math

import numpy as np

from .builder import SceneDraft, floor_footprint, overlaps, yaw_matrix

# --------------------------------------------------------------------------------------------
# furniture
# --------------------------------------------------------------------------------------------


def _support(origin, yaw, y, hx, hz, clearance):
    """A horizontal surface on which small objects can stand."""
    return {
        "origin": np.asarray(origin, float),
        "yaw": float(yaw),
        "y": float(y),
        "hx": float(hx),
        "hz": float(hz),
        "clear": float(clearance),
        "used": [],
    }


def add_table(sc: SceneDraft, origin, yaw, length, depth, height, *, wood="wood", metal_legs=False):
    rng = sc.rng
    top = rng.uniform(0.03, 0.06)
    sc.box(
        "table_top", wood, origin, yaw, (0, height - top / 2, 0), (length / 2, top / 2, depth / 2)
    )
    inset = rng.uniform(0.04, 0.1)
    leg = rng.uniform(0.035, 0.06)
    leg_h = height - top
    for sx in (-1, 1):
        for sz in (-1, 1):
            p = np.array([sx * (length / 2 - inset), 0.0, sz * (depth / 2 - inset)])
            if metal_legs:
                base = np.asarray(origin, float) + yaw_matrix(yaw) @ p
                sc.cylinder("table_leg", "metal_1", base, leg * 0.6, leg_h)
            else:
                p[1] = leg_h / 2
                sc.box("table_leg", wood, origin, yaw, p, (leg / 2, leg_h / 2, leg / 2))
    return _support(origin, yaw, height, length / 2 - 0.04, depth / 2 - 0.04, 2.0)


def add_shelf(sc: SceneDraft, origin, yaw, width, depth, height):
    rng = sc.rng
    t = rng.uniform(0.018, 0.03)
    mat = "wood2"
    sc.box(
        "shelf_side",
        mat,
        origin,
        yaw,
        (-(width / 2 - t / 2), height / 2, 0),
        (t / 2, height / 2, depth / 2),
    )
    sc.box(
        "shelf_side",
        mat,
        origin,
        yaw,
        ((width / 2 - t / 2), height / 2, 0),
        (t / 2, height / 2, depth / 2),
    )
    sc.box(
        "shelf_back",
        mat,
        origin,
        yaw,
        (0, height / 2, -depth / 2 + 0.006),
        (width / 2 - t, height / 2, 0.006),
    )
    n = int(rng.integers(3, 6))
    plinth = rng.uniform(0.05, 0.12)
    levels = np.linspace(plinth, height - t, n + 1)
    supports = []
    for k, y in enumerate(levels):
        sc.box(
            "shelf_board",
            mat,
            origin,
            yaw,
            (0, y + t / 2, 0.006),
            (width / 2 - t, t / 2, depth / 2 - 0.006),
        )
        if k < n:
            clear = levels[k + 1] - y - t - 0.02
            supports.append(
                _support(
                    origin + yaw_matrix(yaw) @ np.array([0, 0, 0.02]),
                    yaw,
                    y + t,
                    width / 2 - t - 0.02,
                    depth / 2 - 0.04,
                    clear,
                )
            )
    supports.append(_support(origin, yaw, height, width / 2 - 0.03, depth / 2 - 0.03, 0.3))
    return supports


def add_cabinet(sc: SceneDraft, origin, yaw, width, depth, height):
    rng = sc.rng
    body = str(rng.choice(["wood", "wood2", "paint"]))
    sc.box(
        "cabinet_body", body, origin, yaw, (0, height / 2, 0), (width / 2, height / 2, depth / 2)
    )
    doors = 1 if width < 0.7 else 2
    dw = (width - 0.04) / doors
    door_mat = str(rng.choice(["paint", "plastic_0", "wood2"]))
    for k in range(doors):
        cx = -width / 2 + 0.02 + dw * (k + 0.5)
        sc.box(
            "cabinet_door",
            door_mat,
            origin,
            yaw,
            (cx, height / 2 + 0.02, depth / 2 + 0.01),
            (dw / 2 - 0.006, height / 2 - 0.05, 0.01),
        )
        hx = cx + (dw / 2 - 0.06) * (1 if k == 0 else -1)
        sc.box(
            "cabinet_handle",
            "metal_0",
            origin,
            yaw,
            (hx, height * 0.6, depth / 2 + 0.035),
            (0.01, 0.07, 0.012),
        )
    return [_support(origin, yaw, height, width / 2 - 0.03, depth / 2 - 0.03, 0.6)]


def add_box_stack(sc: SceneDraft, origin, yaw, size):
    rng = sc.rng
    y = 0.0
    n = int(rng.integers(1, 4))
    hx, hz = size / 2, size / 2 * rng.uniform(0.7, 1.0)
    for _ in range(n):
        hy = rng.uniform(0.12, 0.25)
        mat = str(rng.choice(["cardboard", "cardboard", "patterned", "plastic_1", "plastic_2"]))
        jitter = rng.uniform(-8, 8)
        sc.box("box", mat, origin, yaw + jitter, (0, y + hy, 0), (hx, hy, hz))
        y += 2 * hy
        hx *= rng.uniform(0.7, 0.95)
        hz *= rng.uniform(0.7, 0.95)
    return y


def place_on(sc: SceneDraft, support, radius, height, *, toward=None, tries=30):
    """Find a free spot of ``radius`` on a support; return the world base point or ``None``.

    With ``toward`` (a world point, the camera), only the half of the support facing it is
    used.
    """
    rng = sc.rng
    if radius > min(support["hx"], support["hz"]) or height > support["clear"]:
        return None
    rot = yaw_matrix(support["yaw"])
    facing = None
    if toward is not None:
        facing = rot.T @ (np.asarray(toward, float) - support["origin"])
    for _ in range(tries):
        lx = rng.uniform(-support["hx"] + radius, support["hx"] - radius)
        lz = rng.uniform(-support["hz"] + radius, support["hz"] - radius)
        if facing is not None and lx * facing[0] + lz * facing[2] < 0:
            lx, lz = -lx, -lz
        if all(
            (lx - ux) ** 2 + (lz - uz) ** 2 >= (radius + ur + 0.02) ** 2
            for ux, uz, ur in support["used"]
        ):
            support["used"].append((lx, lz, radius))
            p = support["origin"] + rot @ np.array([lx, 0.0, lz])
            p[1] = support["y"]
            return p
    return None


def add_small_object(sc: SceneDraft, support, kind: str) -> bool:
    """Put a small glossy/metal/diffuse prop on a support."""
    rng = sc.rng
    if kind == "metal_sphere":
        r = rng.uniform(0.05, 0.11)
        p = place_on(sc, support, r, 2 * r)
        if p is None:
            return False
        sc.sphere("metal_ball", "metal_0", p + [0, r, 0], r)
    elif kind == "metal_can":
        r, h = rng.uniform(0.035, 0.08), rng.uniform(0.1, 0.28)
        p = place_on(sc, support, r, h)
        if p is None:
            return False
        sc.cylinder("metal_can", str(rng.choice(["metal_0", "metal_1"])), p, r, h)
    elif kind == "plastic_box":
        hx, hy, hz = rng.uniform(0.04, 0.12), rng.uniform(0.03, 0.1), rng.uniform(0.04, 0.1)
        p = place_on(sc, support, math.hypot(hx, hz), 2 * hy)
        if p is None:
            return False
        sc.add(
            "plastic_box",
            "box",
            str(rng.choice(["plastic_0", "plastic_1", "plastic_2"])),
            translate=p + [0, hy, 0],
            rotate=(0, support["yaw"] + rng.uniform(-30, 30), 0),
            scale=(hx, hy, hz),
        )
    elif kind == "plastic_ball":
        r = rng.uniform(0.04, 0.1)
        p = place_on(sc, support, r, 2 * r)
        if p is None:
            return False
        sc.sphere(
            "plastic_ball",
            str(rng.choice(["plastic_0", "plastic_1", "plastic_2"])),
            p + [0, r, 0],
            r,
        )
    elif kind == "books":
        n = int(rng.integers(3, 9))
        thick = rng.uniform(0.02, 0.05, size=n)
        heights = rng.uniform(0.15, 0.28, size=n)
        depth = rng.uniform(0.1, 0.16)
        width = float(thick.sum())
        p = place_on(sc, support, math.hypot(width / 2, depth / 2) + 0.01, float(heights.max()))
        if p is None:
            return False
        x = -width / 2
        for t, h in zip(thick, heights, strict=False):
            mat = str(rng.choice(["patterned", "plastic_0", "plastic_1", "paint", "cardboard"]))
            sc.box(
                "book",
                mat,
                p,
                support["yaw"],
                (x + t / 2, h / 2, 0),
                (t / 2 - 0.001, h / 2, depth / 2),
            )
            x += t
    else:
        raise ValueError(kind)
    return True


def place_against_wall(sc: SceneDraft, width, depth, *, walls, keep_out=None):
    """Random (origin, yaw) for furniture of (width, depth) with its back to one of ``walls``."""
    rng = sc.rng
    W, D = sc.W, sc.D
    wall = str(rng.choice(walls))
    gap = 0.02
    if wall == "back":
        span = W / 2 - width / 2 - 0.05
        if span <= 0:
            return None
        x = rng.uniform(-span, span)
        origin, yaw = (x, 0.0, D - gap - depth / 2), 180.0
    else:
        lo, hi = 1.2, D - width / 2 - 0.05
        if hi <= lo:
            return None
        z = rng.uniform(lo, hi)
        sx = -1 if wall == "left" else 1
        origin, yaw = (sx * (W / 2 - gap - depth / 2), 0.0, z), -sx * 90.0
    fp = floor_footprint((origin[0], origin[2]), (width / 2, depth / 2), yaw)
    if not sc.free(fp) or (keep_out is not None and overlaps(fp, keep_out)):
        return None
    return np.asarray(origin, float), yaw, fp


# --------------------------------------------------------------------------------------------
# glass
# --------------------------------------------------------------------------------------------


def _vase_profile(rng, height, radius):
    """A closed vase-like lathe profile ``[[r, y], ...]`` (y strictly increasing, r > 0)."""
    foot = radius * rng.uniform(0.5, 0.8)
    neck = radius * rng.uniform(0.35, 0.7)
    lip = neck * rng.uniform(1.05, 1.5)
    yb = height * rng.uniform(0.3, 0.5)
    yn = height * rng.uniform(0.7, 0.85)
    return [
        [foot, 0.0],
        [radius * 0.9, yb * 0.6],
        [radius, yb],
        [radius * 0.85, (yb + yn) / 2],
        [neck, yn],
        [lip, height],
    ]


def glass_dims(rng, kind: str, *, floor: bool, factor: float) -> dict:
    """Random size of a glass object; ``radius`` is its footprint radius."""
    f = factor
    if kind == "sphere":
        r = (rng.uniform(0.18, 0.3) if floor else rng.uniform(0.09, 0.17)) * f
        return {"kind": kind, "r": r, "radius": r, "height": 2 * r}
    if kind == "pane":
        w = (rng.uniform(0.5, 0.9) if floor else rng.uniform(0.3, 0.6)) * f
        h = (rng.uniform(0.6, 1.1) if floor else rng.uniform(0.25, 0.5)) * f
        return {
            "kind": kind,
            "w": w,
            "h": h,
            "t": rng.uniform(0.012, 0.04),
            "turn": rng.uniform(-35, 35),
            "radius": w / 2 + 0.01,
            "height": h,
        }
    if kind == "vase":
        h = (rng.uniform(0.5, 0.85) if floor else rng.uniform(0.25, 0.45)) * f
        r = h * rng.uniform(0.22, 0.35)
        prof = _vase_profile(rng, h, r)
        return {
            "kind": kind,
            "profile": prof,
            "spin": rng.uniform(0, 360),
            "radius": max(p[0] for p in prof),
            "height": h,
        }
    if kind == "cylinder":
        r = (rng.uniform(0.12, 0.2) if floor else rng.uniform(0.05, 0.11)) * f
        h = (rng.uniform(0.4, 0.7) if floor else rng.uniform(0.15, 0.35)) * f
        return {"kind": kind, "r": r, "radius": r, "height": h}
    raise ValueError(kind)


def add_glass_object(sc: SceneDraft, dims: dict, base, facing_deg: float) -> None:
    """Add a glass object of ``dims`` (from :func:`glass_dims`) standing at ``base``."""
    mat = "glass" if sc.rng.random() < 0.7 else "glass_tinted"
    base = np.asarray(base, dtype=np.float64)
    kind = dims["kind"]
    if kind == "sphere":
        sc.sphere("glass_sphere", mat, base + [0, dims["r"], 0], dims["r"])
    elif kind == "pane":
        sc.add(
            "glass_pane",
            "box",
            mat,
            translate=base + [0, dims["h"] / 2, 0],
            rotate=(0, facing_deg + dims["turn"], 0),
            scale=(dims["w"] / 2, dims["h"] / 2, dims["t"] / 2),
        )
    elif kind == "vase":
        sc.lathe("glass_vase", mat, base, dims["profile"], yaw=dims["spin"])
    else:
        sc.cylinder("glass_cylinder", mat, base, dims["r"], dims["height"])
