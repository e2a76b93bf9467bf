"""Layout checks of a figure: text cut off at the figure's edge, and text drawn over text.

A figure that is saved without ``bbox_inches="tight"`` loses whatever is drawn past its edge,
and two labels placed at one spot are unreadable in either. Both show only once the figure is
drawn, so :func:`layout_problems` draws it (on the Agg renderer) and compares the window
extents of every text a reader sees: figure and axes titles, axis labels, the tick labels that
are drawn, offset texts, annotations, free texts, legend entries and titles; and every
legend's frame, which may cover a text that is not its own.

A rotated text is compared by its rotated rectangle, not by the axis-aligned box around it
(the box of a label at 35 degrees covers much of its neighbour's box while the glyphs stay
apart). Two rectangles collide where they overlap by more than a tolerance in the direction
in which they are the least apart (separating axis test):

.. math::

    \\text{depth}(A, B) = \\min_{u \\in \\text{axes}(A) \\cup \\text{axes}(B)}
        \\bigl(\\min(\\max_A u, \\max_B u) - \\max(\\min_A u, \\min_B u)\\bigr)

with :math:`\\max_A u` the largest projection of a corner of :math:`A` on the unit edge normal
:math:`u`; they collide where :math:`\\text{depth} > \\text{tol}`.

:func:`wrap_to_width` breaks a long title onto lines that fit a width, before the figure is
laid out.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np

TOLERANCE_PT = 1.0
"""Overlap (and overhang past the edge) tolerated, in points (1/72 inch): anti-aliasing and
the padding of glyph extents stay within it."""


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _shown(text) -> bool:
    """Whether a :class:`~matplotlib.text.Text` draws anything."""
    alpha = text.get_alpha()
    return bool(text.get_visible() and text.get_text().strip() and (alpha is None or alpha > 0))


def _axis_texts(ax) -> list[tuple[str, object]]:
    """(kind, text) of one axes: titles, axis labels, offset texts, drawn tick labels, free
    texts and annotations."""
    out = [("title", t) for t in (ax._left_title, ax.title, ax._right_title)]
    for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
        if not axis.get_visible():
            continue
        out.append((f"{name} label", axis.label))
        out.append((f"{name} offset", axis.get_offset_text()))
        for tick in axis._update_ticks():  # the ticks inside the view limits, which are drawn
            for label in (tick.label1, tick.label2):
                out.append((f"{name} tick label", label))
    out.extend(("text", t) for t in ax.texts)
    return out


def _legend_texts(legend) -> list[tuple[str, object]]:
    return [("legend title", legend.get_title())] + [("legend", t) for t in legend.get_texts()]


def text_items(fig) -> list[tuple[str, object, object]]:
    """Every shown text of a figure as (kind, text artist, owning legend or None).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure that has been drawn (the tick labels are those of its last draw).

    Returns
    -------
    list of tuple
        ``kind`` (``"title"``, ``"x tick label"``, ``"legend"``, ...), the
        :class:`~matplotlib.text.Text` and the :class:`~matplotlib.legend.Legend` it belongs
        to (``None`` outside a legend).
    """
    items: list[tuple[str, object, object]] = []
    for kind in ("suptitle", "supxlabel", "supylabel"):
        text = getattr(fig, f"_{kind}", None)
        if text is not None:
            items.append((kind, text, None))
    items.extend(("figure text", t, None) for t in fig.texts)
    for ax in fig.axes:
        if ax.get_visible():
            items.extend((kind, t, None) for kind, t in _axis_texts(ax))
    for legend in _legends(fig):
        items.extend((kind, t, legend) for kind, t in _legend_texts(legend))
    seen: set[int] = set()
    unique = []
    for kind, text, legend in items:
        if id(text) not in seen and _shown(text):
            seen.add(id(text))
            unique.append((kind, text, legend))
    return unique


def _legends(fig) -> list:
    """Every shown legend: the figure's, each axes' own and those added as artists."""
    from matplotlib.legend import Legend

    legends = list(fig.legends)
    for ax in fig.axes:
        if ax.get_visible():
            legends.append(ax.get_legend())
            legends.extend(a for a in ax.artists if isinstance(a, Legend))
    unique = {id(lg): lg for lg in legends if lg is not None and lg.get_visible()}
    return list(unique.values())


def _corners(text, renderer) -> np.ndarray:
    """The four corners (4, 2) of a text's drawn rectangle in display pixels, rotated with it.

    The rectangle has the size of the unrotated text and the centre of the axis-aligned box
    around the rotated one (a rotation about any point keeps that box's centre at the
    rectangle's).
    """
    from matplotlib.text import Text

    extent = Text.get_window_extent  # of the text alone: an annotation's adds its arrow
    box = extent(text, renderer)
    angle = text.get_rotation() % 180.0
    if min(angle, 180.0 - angle) < 1e-6 or abs(angle - 90.0) < 1e-6:
        return np.array([[box.x0, box.y0], [box.x1, box.y0], [box.x1, box.y1], [box.x0, box.y1]])
    text.set_rotation(0.0)
    try:
        flat = extent(text, renderer)
    finally:
        text.set_rotation(angle)
    w, h = flat.width / 2.0, flat.height / 2.0
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    local = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
    rot = np.array([[c, -s], [s, c]])
    centre = np.array([(box.x0 + box.x1) / 2.0, (box.y0 + box.y1) / 2.0])
    return local @ rot.T + centre


def _box_corners(bbox) -> np.ndarray:
    return np.array(
        [[bbox.x0, bbox.y0], [bbox.x1, bbox.y0], [bbox.x1, bbox.y1], [bbox.x0, bbox.y1]]
    )


def overlap_depth(a: np.ndarray, b: np.ndarray) -> float:
    """How far two convex quadrilaterals overlap: the least overlap of their projections on
    the edge normals of either (separating axis test); <= 0 where they are apart.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (4, 2)
        Corners in order around each rectangle.

    Returns
    -------
    float
        The overlap depth in the corners' units.

    Examples
    --------
    >>> import numpy as np
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)
    >>> overlap_depth(square, square + [1.5, 0.0])
    0.5
    >>> overlap_depth(square, square + [3.0, 0.0])
    -1.0
    """
    depth = math.inf
    for quad in (a, b):
        for k in range(4):
            edge = quad[(k + 1) % 4] - quad[k]
            norm = math.hypot(*edge)
            if norm == 0:
                continue
            u = np.array([-edge[1], edge[0]]) / norm
            pa, pb = a @ u, b @ u
            depth = min(depth, float(min(pa.max(), pb.max()) - max(pa.min(), pb.min())))
    return depth


def _name(kind: str, text, fig) -> str:
    words = " ".join(text.get_text().split())
    if len(words) > 40:
        words = words[:37] + "..."
    where = ""
    axes = text.axes
    if axes is not None and axes in fig.axes and len(fig.axes) > 1:
        where = f" (axes {fig.axes.index(axes)})"
    return f"{kind} {words!r}{where}"


def layout_problems(fig, *, tolerance_pt: float = TOLERANCE_PT, draw: bool = True) -> list[str]:
    """Draw a figure and name every text cut off at its edge and every two texts that collide.

    Clipped: a shown text (:func:`text_items`) or a legend whose rectangle reaches more than
    ``tolerance_pt`` past the figure's edge. Colliding: two shown texts, or a legend and a
    text outside it, whose rectangles overlap by more than ``tolerance_pt``
    (:func:`overlap_depth`); texts of one legend are not compared with each other's frame.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure, as the caller would save it (its size and dpi as they are).
    tolerance_pt : float, keyword-only
        Overhang and overlap tolerated, in points.
    draw : bool, keyword-only
        Draw the figure first. ``False`` where it was just drawn as it is (saved): the
        layout of that draw is measured, at the figure's own dpi.

    Returns
    -------
    list of str
        One sentence per problem; empty for a clean figure.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> fig, ax = plt.subplots(figsize=(3, 2), layout="constrained")
    >>> _ = ax.set_title("fits")
    >>> layout_problems(fig)
    []
    >>> _ = fig.text(0.9, 0.5, "runs off the right edge")
    >>> layout_problems(fig)[0].startswith("clipped: figure text 'runs off the right edge'")
    True
    >>> plt.close(fig)
    """
    if not hasattr(fig.canvas, "get_renderer"):  # a closed figure: measure on Agg
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    if draw:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    tol = tolerance_pt * fig.dpi / 72.0
    width, height = fig.bbox.width, fig.bbox.height
    problems = []
    shapes = []
    for kind, text, legend in text_items(fig):
        corners = _corners(text, renderer)
        if np.ptp(corners[:, 0]) <= 0 or np.ptp(corners[:, 1]) <= 0:
            continue
        shapes.append((_name(kind, text, fig), corners, legend))
    for legend in _legends(fig):
        frame = _box_corners(legend.get_window_extent(renderer))
        shapes.append((f"legend frame of {len(legend.get_texts())} entries", frame, legend))
    for name, corners, _ in shapes:
        over = {
            "left": -corners[:, 0].min(),
            "right": corners[:, 0].max() - width,
            "bottom": -corners[:, 1].min(),
            "top": corners[:, 1].max() - height,
        }
        sides = [f"{side} by {v:.0f} px" for side, v in over.items() if v > tol]
        if sides:
            problems.append(f"clipped: {name} runs past the figure's {', '.join(sides)}")
    if not shapes:
        return problems
    lo = np.array([c.min(axis=0) for _, c, _ in shapes])
    hi = np.array([c.max(axis=0) for _, c, _ in shapes])
    # the boxes around the rectangles must overlap for the rectangles to: a cheap first cut
    near = np.all(
        np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None]) > tol, axis=-1
    )
    for i, j in zip(*np.nonzero(np.triu(near, k=1)), strict=True):
        (name_a, a, legend_a), (name_b, b, legend_b) = shapes[i], shapes[j]
        if legend_a is not None and legend_a is legend_b:
            continue  # a legend's own texts sit in its frame, apart from each other
        depth = overlap_depth(a, b)
        if depth > tol:
            problems.append(f"colliding: {name_a} and {name_b} overlap by {depth:.0f} px")
    return problems


def wrap_to_width(text: str, width_in: float, *, fontsize: float = 12.0) -> str:
    """Break ``text`` at spaces onto lines that fit ``width_in`` inches at ``fontsize`` points.

    A line holds about ``width_in * 72 / (0.6 * fontsize)`` characters (0.6 em: a wide
    average glyph of DejaVu Sans); existing line breaks stay, and a line too long that ends
    in a parenthesis breaks before it first.

    Examples
    --------
    >>> wrap_to_width("scene_000, SPP 32 (renderer mitsuba, estimator seeds)", 3.5)
    'scene_000, SPP 32\\n(renderer mitsuba, estimator seeds)'
    >>> wrap_to_width("fits (as it is)", 3.0)
    'fits (as it is)'
    """
    chars = max(int(width_in * 72.0 / (0.6 * fontsize)), 10)
    lines = []
    for line in text.split("\n"):
        # a parenthesis that does not fit starts its own line
        head, sep, tail = line.rpartition(" (")
        parts = [head, f"({tail}"] if sep and len(line) > chars and head else [line]
        for part in parts:
            lines += textwrap.wrap(part, chars, break_on_hyphens=False) or [part]
    return "\n".join(lines)


def _ring(r: float) -> list[tuple[float, float, str, str]]:
    """Label positions at offset ``r`` points around a point: (dx, dy, ha, va), the
    diagonals first (a label there covers neither the point's vertical nor its horizontal
    error bar near the point)."""
    return [
        (r, r, "left", "bottom"),
        (-r, r, "right", "bottom"),
        (r, -r, "left", "top"),
        (-r, -r, "right", "top"),
        (0.0, r, "center", "bottom"),
        (0.0, -r, "center", "top"),
        (r, 0.0, "left", "center"),
        (-r, 0.0, "right", "center"),
    ]


LABEL_RINGS_PT = (4.0, 12.0, 20.0, 28.0, 38.0, 48.0, 60.0)
"""Offsets (points) tried in turn around a point by :func:`place_labels`; from the third on,
a thin leader line joins the label to its point."""


def _anchored_box(x: float, y: float, w: float, h: float, ha: str, va: str) -> np.ndarray:
    x0 = x - {"left": 0.0, "center": w / 2.0, "right": w}[ha]
    y0 = y - {"bottom": 0.0, "center": h / 2.0, "top": h}[va]
    return np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])


def place_labels(ax, points, labels, *, colors=None, fontsize: float = 8.0,
                 marker_pt: float = 3.5, draw: bool = True) -> list[str]:  # fmt: skip
    """Annotate points with their labels where no two labels collide.

    Each label in turn goes to the first position of :data:`LABEL_RINGS_PT` (eight per
    ring, :func:`_ring`) where its rectangle stays inside the axes and overlaps neither a
    label placed before it, nor any point's marker (a square of half-side ``marker_pt``),
    nor a text or legend already in the axes; a label that finds no place is left out (the
    caller's legend names it). Call it once the figure's layout is final (its axes keep
    their place): it draws the figure to measure it, unless told it is drawn.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes holding the points.
    points : sequence of (float, float)
        The points, in data coordinates.
    labels : sequence of str
        One label per point, placed in this order.
    colors : sequence, optional
        Leader-line colour per point (default black).
    fontsize : float, keyword-only
        Label size in points.
    marker_pt : float, keyword-only
        Half-side of the square kept free around every point, in points.
    draw : bool, keyword-only
        Draw the figure first (``False``: the caller drew it since its layout was final).

    Returns
    -------
    list of str
        The labels left out.
    """
    fig = ax.figure
    if draw:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    px = fig.dpi / 72.0
    frame = ax.get_window_extent(renderer)
    xy = ax.transData.transform(np.asarray(points, dtype=np.float64).reshape(-1, 2))
    m = marker_pt * px
    taken = [np.array([[x - m, y - m], [x + m, y - m], [x + m, y + m], [x - m, y + m]])
             for x, y in xy if np.isfinite(x) and np.isfinite(y)]  # fmt: skip
    taken += [_corners(t, renderer) for t in ax.texts if _shown(t)]
    if ax.get_legend() is not None:
        taken.append(_box_corners(ax.get_legend().get_window_extent(renderer)))
    colors = list(colors) if colors is not None else ["black"] * len(labels)
    left_out = []
    for (x, y), point, label, colour in zip(xy, points, labels, colors, strict=True):
        probe = ax.text(0.0, 0.0, label, fontsize=fontsize, transform=None)
        size = probe.get_window_extent(renderer)
        probe.remove()
        spot = _free_spot(x, y, size.width, size.height, px, frame, taken)
        if spot is None:
            left_out.append(label)
            continue
        k, dx, dy, ha, va, box = spot
        arrow = {"arrowstyle": "-", "color": colour, "lw": 0.6, "shrinkA": 0,
                 "shrinkB": marker_pt} if k >= 2 else None  # fmt: skip
        ax.annotate(label, point, xytext=(dx, dy), textcoords="offset points",
                    fontsize=fontsize, ha=ha, va=va, arrowprops=arrow)  # fmt: skip
        taken.append(box)
    return left_out


def _free_spot(x, y, w, h, px, frame, taken):
    """The first position around (x, y) (display pixels) where a w x h label stays inside
    ``frame`` and clear of ``taken``: (ring index, dx, dy in points, ha, va, corners)."""
    for k, r in enumerate(LABEL_RINGS_PT):
        for dx, dy, ha, va in _ring(r):
            box = _anchored_box(x + dx * px, y + dy * px, w, h, ha, va)
            inside = (box[:, 0].min() >= frame.x0 and box[:, 0].max() <= frame.x1
                      and box[:, 1].min() >= frame.y0 and box[:, 1].max() <= frame.y1)  # fmt: skip
            if inside and all(overlap_depth(box, other) <= 0 for other in taken):
                return k, dx, dy, ha, va, box
    return None
