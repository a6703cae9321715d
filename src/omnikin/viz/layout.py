"""Drawing of a wheel layout: wheels, drive directions, roller axes, body frame.

Body frame as in ``docs/conventions.md``: x forward (right on the page), y left
(up on the page). Each wheel is drawn as a rectangle in its wheel plane (length
2r), with an arrow along the drive direction ``u`` (scaled to the layout) and,
for Swedish wheels, a dashed line along the roller axis ``delta + gamma``.
"""

from __future__ import annotations

import math

import numpy as np

from ..model import Robot
from . import require_matplotlib

COLORS = {"omni": "#1f77b4", "mecanum": "#9467bd", "swedish": "#17becf", "standard": "#2ca02c",
          "steerable": "#ff7f0e", "castor": "#7f7f7f"}


def layout_figure(robot: Robot):
    """A matplotlib ``Figure`` of ``robot``'s layout at zero steering."""
    require_matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Rectangle

    fig = Figure(figsize=(6.4, 6.4), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    span = max([math.hypot(w.x, w.y) + w.offset + w.radius for w in robot.wheels] + [0.05])
    arrow = 0.35 * span
    ax.add_patch(Circle((0, 0), span * 0.9, fill=False, ls=":", color="0.6"))
    ax.annotate("", xy=(arrow, 0), xytext=(0, 0), arrowprops=dict(arrowstyle="->", color="red", lw=1.5))
    ax.annotate("", xy=(0, arrow), xytext=(0, 0), arrowprops=dict(arrowstyle="->", color="green", lw=1.5))
    ax.text(arrow, -0.06 * span, "x", color="red")
    ax.text(-0.06 * span, arrow, "y", color="green")
    for w in robot.wheels:
        color = COLORS[w.type]
        cx, cy = w.contact_point()
        length, width = 2 * w.radius, 0.7 * w.radius
        c, s = math.cos(w.drive), math.sin(w.drive)
        corner = (cx - c * length / 2 + s * width / 2, cy - s * length / 2 - c * width / 2)
        ax.add_patch(Rectangle(corner, length, width, angle=math.degrees(w.drive), color=color, alpha=0.45))
        if w.offset > 0:
            ax.plot([w.x, cx], [w.y, cy], color=color, lw=1)
            ax.plot([w.x], [w.y], "o", color=color, ms=4)
        if not w.is_castor:
            reach = w.radius + 0.3 * arrow
            ax.annotate("", xy=(cx + reach * c, cy + reach * s), xytext=(cx, cy),
                        arrowprops=dict(arrowstyle="-|>", color=color, lw=1.5))
        if w.is_swedish:
            a = w.drive + w.roller
            d = 0.5 * length * np.array([math.cos(a), math.sin(a)])
            ax.plot([cx - d[0], cx + d[0]], [cy - d[1], cy + d[1]], ls="--", color="k", lw=1)
        ax.text(cx - 0.25 * arrow * c + 0.05 * span, cy - 0.25 * arrow * s + 0.05 * span,
                f"{w.name}\n{w.type}", fontsize=8, color=color)
    m = robot.mobility
    ax.set_title(f"{robot.name}: Campion type {m.campion_type}, "
                 f"{'holonomic' if m.holonomic else 'non-holonomic'}\n"
                 "arrows: drive direction u (positive wheel speed); dashed: roller axis", fontsize=9)
    lim = 1.25 * span
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (forward)")
    ax.set_ylabel("y [m] (left)")
    ax.grid(True, alpha=0.3)
    return fig


def save_layout(robot: Robot, path) -> None:
    """Write the layout drawing to ``path`` (PNG, SVG, PDF by extension)."""
    layout_figure(robot).savefig(path)
