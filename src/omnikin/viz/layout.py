"""Drawing of a wheel layout: wheels, drive directions, roller axes, body frame.

Body frame as in ``docs/conventions.md``: x forward (right on the page), y left
(up on the page), lengths in metres. Each wheel is drawn as a rectangle in its wheel plane
(length 2r), with an arrow along the drive direction ``u`` (the motion of a positive wheel
speed) and, for Swedish wheels, a dashed line along the roller axis ``delta + gamma``. Wheel
names stand next to their wheels where they cover no part of the drawing; the legend (below
the axes) gives the wheel types and symbols.
"""

from __future__ import annotations

import math

import numpy as np

from ..kinematics.robot import Robot
from . import DPI, require_matplotlib, save_figure

COLORS = {
    "omni": "#1f77b4",
    "mecanum": "#9467bd",
    "swedish": "#17becf",
    "standard": "#2ca02c",
    "steerable": "#ff7f0e",
    "castor": "#7f7f7f",
}

LABEL_GAP = 0.08
"""Gap between the drawing and a wheel name placed beyond it, as a fraction of the drawing's radius."""


def _wheel_outline(w) -> np.ndarray:
    """Corners ``(4, 2)`` [m] of the wheel rectangle (length 2r along the drive direction)."""
    cx, cy = w.contact_point()
    half_len, half_wid = w.radius, 0.35 * w.radius
    c, s = math.cos(w.drive), math.sin(w.drive)
    along, across = np.array([c, s]), np.array([-s, c])
    centre = np.array([cx, cy])
    return np.array(
        [centre + a * half_len * along + b * half_wid * across for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    )


def layout_figure(robot: Robot):
    """A matplotlib ``Figure`` of ``robot``'s layout at zero steering (module docstring)."""
    require_matplotlib()
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch, Patch, Polygon

    fig = Figure(figsize=(6.0, 6.6), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    outlines = {w.name: _wheel_outline(w) for w in robot.wheels}
    corners = np.vstack(list(outlines.values()))
    radius = float(np.max(np.hypot(corners[:, 0], corners[:, 1]), initial=0.05))
    arrow = 0.3 * radius
    points = [corners]
    for w in robot.wheels:
        color = COLORS[w.type]
        cx, cy = w.contact_point()
        c, s = math.cos(w.drive), math.sin(w.drive)
        ax.add_patch(
            Polygon(outlines[w.name], closed=True, facecolor=color, alpha=0.45, edgecolor=color, gid=f"wheel:{w.name}")
        )
        if w.offset > 0:
            ax.plot([w.x, cx], [w.y, cy], color=color, lw=1, gid=f"offset:{w.name}")
            ax.plot([w.x], [w.y], "o", color=color, ms=4, gid=f"axis:{w.name}")
        if not w.is_castor:
            tip = (cx + (w.radius + arrow) * c, cy + (w.radius + arrow) * s)
            ax.add_patch(
                FancyArrowPatch(
                    (cx, cy), tip, arrowstyle="-|>", mutation_scale=12, color=color, lw=1.5, gid=f"drive:{w.name}"
                )
            )
            points.append(np.array([tip]))
        if w.is_swedish:
            a = w.drive + w.roller
            d = w.radius * np.array([math.cos(a), math.sin(a)])
            ax.plot([cx - d[0], cx + d[0]], [cy - d[1], cy + d[1]], ls="--", color="k", lw=1, gid=f"roller:{w.name}")
    # body frame at the origin, short enough to stay clear of every wheel
    clearance = float(np.min(np.hypot(corners[:, 0], corners[:, 1]), initial=radius))
    frame = max(0.5 * clearance, 0.12 * radius)
    ax.add_patch(
        FancyArrowPatch((0, 0), (frame, 0), arrowstyle="-|>", mutation_scale=12, color="#d62728", lw=1.5, gid="frame:x")
    )
    ax.add_patch(
        FancyArrowPatch(
            (0, 0),
            (0, frame),
            arrowstyle="-|>",
            mutation_scale=12,
            color="#2ca02c",
            lw=1.5,
            gid="frame:y",
            linestyle="-",
        )
    )
    reach = float(np.max(np.hypot(*np.vstack(points).T)))
    m = robot.mobility
    ax.set_title(
        f"{robot.name}: Campion type {m.campion_type}, {'holonomic' if m.holonomic else 'non-holonomic'}", fontsize=10
    )
    handles: list[Artist] = [
        Patch(facecolor=COLORS[t], alpha=0.45, edgecolor=COLORS[t], label=f"{t} wheel")
        for t in dict.fromkeys(w.type for w in robot.wheels)
    ]
    handles.append(Line2D([], [], color="0.3", marker=">", markevery=[1], label="drive direction (positive speed)"))
    if any(w.is_swedish for w in robot.wheels):
        handles.append(Line2D([], [], color="k", ls="--", lw=1, label="roller axis"))
    handles.append(Line2D([], [], color="#d62728", label="body x (forward)"))
    handles.append(Line2D([], [], color="#2ca02c", label="body y (left)"))
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=8, frameon=False)
    ax.set_aspect("equal")
    lim = reach * 1.35
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_xlabel("x [m] (forward)")
    ax.set_ylabel("y [m] (left)")
    ax.grid(True, alpha=0.3)
    _label_wheels(fig, ax, robot, reach)
    return fig


def _drawing_paths(ax) -> list:
    """``(path in display coordinates, filled)`` of every patch and line drawn in ``ax``."""
    from matplotlib.patches import Patch

    out = []
    for artist in [*ax.patches, *ax.lines]:
        path = artist.get_transform().transform_path(artist.get_path())
        out.append((path, isinstance(artist, Patch) and artist.get_fill()))
    return out


def _label_wheels(fig, ax, robot: Robot, reach: float) -> None:
    """Put each wheel's name next to it where it covers no part of the drawing, no other name
    and stays inside the axes: candidate spots around the wheel, outward first (rendered and
    measured with the Agg canvas); a wheel without a free spot is named beyond the drawing at
    its bearing from the origin, the axes widened to hold it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.transforms import Bbox

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    drawing = _drawing_paths(ax)
    frame = ax.get_window_extent(renderer)
    taken: list[Bbox] = []
    for w in robot.wheels:
        cx, cy = w.contact_point()
        outward = math.atan2(cy, cx) if math.hypot(cx, cy) > 1e-9 else -math.pi / 2
        spot = None
        for step in (1.0, 1.5, 2.2, 3.0):
            for turn in (0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6, -6, 7, -7, 8):
                b = outward + turn * math.pi / 8
                d = (w.radius * 1.2 + 0.04 * reach) * step
                text = _name(ax, w, cx + d * math.cos(b), cy + d * math.sin(b), b)
                box = text.get_window_extent(renderer).expanded(1.15, 1.3)
                free = (
                    frame.contains(box.x0, box.y0)
                    and frame.contains(box.x1, box.y1)
                    and not any(box.overlaps(t) for t in taken)
                    and not any(path.intersects_bbox(box, filled=filled) for path, filled in drawing)
                )
                if free:
                    spot = box
                    break
                text.remove()
            if spot is not None:
                break
        if spot is None:  # beyond the drawing, at the wheel's bearing
            at = reach * (1 + LABEL_GAP)
            text = _name(ax, w, at * math.cos(outward), at * math.sin(outward), outward)
            lim = max(ax.get_xlim()[1], 1.6 * reach)
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
            spot = text.get_window_extent(renderer)
        taken.append(spot)


def _name(ax, w, x: float, y: float, bearing: float):
    """The wheel's name at ``(x, y)`` [m], extending away from the wheel along ``bearing``."""
    c, s = math.cos(bearing), math.sin(bearing)
    ha = "left" if c > 0.3 else "right" if c < -0.3 else "center"
    va = "bottom" if s > 0.3 else "top" if s < -0.3 else "center"
    return ax.text(x, y, w.name, ha=ha, va=va, fontsize=9, color=COLORS[w.type], gid=f"label:{w.name}")


def save_layout(robot: Robot, path, *, dpi: float = DPI) -> None:
    """Write the layout drawing to ``path`` (PNG, SVG or PDF by the extension; :func:`~omnikin.viz.save_figure`)."""
    save_figure(layout_figure(robot), path, dpi=dpi)
