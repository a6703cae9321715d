"""The world as plane shapes: rectangles and circles, with signed distances and ray casts.

What a robot can touch seen from above (``docs/world.md``, "Geometry"): each wall segment is a
rectangle (the segment lengthened by half the thickness at both ends, as wide as the wall is
thick), each box a rectangle, each cylinder a circle. Arrays, world frame, metres:

- ``rects`` ``(m, 5)``: centre x, y, half length, half width, yaw [rad] (the half length along
  the rectangle's own x);
- ``circles`` ``(k, 3)``: centre x, y, radius;
- ``rect_body`` ``(m,)``, ``circle_body`` ``(k,)``: the index of the body each belongs to in
  :attr:`omnikin.world.model.World.bodies` (walls first, then obstacles);
- ``rect_height`` ``(m,)``, ``circle_height`` ``(k,)``: the height of that body [m] (None: not known).

Distances are those of :mod:`omnikin.world.plane`. A ray ``o + t d`` (``|d| = 1``) meets a
rectangle by the slab method in its frame and a circle at the smaller root of
``|o + t d - c|^2 = r^2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import World, outline
from .plane import circle_distance, in_frames, rect_distance

BLOCK = 1 << 18
"""Most ray-shape (or point-shape) pairs computed at once: memory stays bounded (a few MB) for a
scan of many beams against many shapes."""


@dataclass(frozen=True)
class Shapes:
    """Plane shapes (module docstring for the arrays' layout)."""

    rects: np.ndarray
    rect_body: np.ndarray
    circles: np.ndarray
    circle_body: np.ndarray
    rect_height: np.ndarray | None = None
    circle_height: np.ndarray | None = None

    def above(self, z: float) -> Shapes:
        """The shapes of bodies taller than ``z`` [m]: what a beam at that height can meet
        (all of them when no heights are known)."""
        if self.rect_height is None or self.circle_height is None:
            return self
        r, c = self.rect_height > z, self.circle_height > z
        return Shapes(
            self.rects[r],
            self.rect_body[r],
            self.circles[c],
            self.circle_body[c],
            self.rect_height[r],
            self.circle_height[c],
        )

    @classmethod
    def none(cls) -> Shapes:
        """No shapes at all: an empty floor."""
        return cls(np.empty((0, 5)), np.empty(0, dtype=np.int64), np.empty((0, 3)), np.empty(0, dtype=np.int64))

    @property
    def count(self) -> int:
        """Number of shapes."""
        return len(self.rects) + len(self.circles)

    def distances(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances ``(n, m)`` of ``points`` ``(n, 2)`` [m] to each rectangle and ``(n, k)``
        to each circle."""
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        return rect_distance(points, self.rects), circle_distance(points, self.circles)


def shapes_of(world: World) -> Shapes:
    """The plane shapes of ``world``'s walls and obstacles (:func:`omnikin.world.model.outline`)."""
    rects, rect_body, circles, circle_body, rect_height, circle_height = [], [], [], [], [], []
    for i, body in enumerate((*world.walls, *world.obstacles)):
        r, c = outline(body)
        rects.append(r)
        circles.append(c)
        rect_body.extend([i] * len(r))
        circle_body.extend([i] * len(c))
        rect_height.extend([body.height] * len(r))
        circle_height.extend([body.height] * len(c))
    return Shapes(
        np.concatenate(rects) if rects else np.empty((0, 5)),
        np.asarray(rect_body, dtype=np.int64),
        np.concatenate(circles) if circles else np.empty((0, 3)),
        np.asarray(circle_body, dtype=np.int64),
        np.asarray(rect_height, dtype=float),
        np.asarray(circle_height, dtype=float),
    )


def cast_rays(shapes: Shapes, origins, angles, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Where rays from ``origins`` ``(n, 2)`` [m] along ``angles`` ``(n,)`` [rad, world frame]
    first meet a shape within ``max_range`` [m].

    Returns ``ranges`` ``(n,)`` [m] (``inf`` for no shape within ``max_range``; 0 for an origin
    inside a shape) and ``bodies`` ``(n,)`` (the body index hit, -1 for none). Computed in blocks
    of at most :data:`BLOCK` ray-shape pairs."""
    origins = np.asarray(origins, dtype=float).reshape(-1, 2)
    angles = np.asarray(angles, dtype=float).reshape(-1)
    n = len(angles)
    ranges = np.full(n, np.inf)
    bodies = np.full(n, -1, dtype=np.int64)
    count = max(shapes.count, 1)
    rows = max(1, BLOCK // count)
    for lo in range(0, n, rows):
        hi = min(n, lo + rows)
        o, d = origins[lo:hi], np.column_stack([np.cos(angles[lo:hi]), np.sin(angles[lo:hi])])
        t_r = _rect_hits(o, d, shapes.rects)
        t_c = _circle_hits(o, d, shapes.circles)
        t = np.concatenate([t_r, t_c], axis=1)
        owner = np.concatenate([shapes.rect_body, shapes.circle_body])
        if t.shape[1]:
            first = np.argmin(t, axis=1)
            best = t[np.arange(hi - lo), first]
            hit = best <= max_range
            ranges[lo:hi] = np.where(hit, best, np.inf)
            bodies[lo:hi] = np.where(hit, owner[first], -1)
    return ranges, bodies


def _rect_hits(o: np.ndarray, d: np.ndarray, rects: np.ndarray) -> np.ndarray:
    """``(n, m)`` distance along each ray to each rectangle (``inf`` if missed), slab method."""
    if len(rects) == 0:
        return np.empty((len(o), 0))
    x, y = in_frames(o, rects)
    c, s = np.cos(rects[:, 4]), np.sin(rects[:, 4])
    dx = c[None, :] * d[:, 0:1] + s[None, :] * d[:, 1:2]
    dy = -s[None, :] * d[:, 0:1] + c[None, :] * d[:, 1:2]
    enter = np.full(x.shape, -np.inf)
    leave = np.full(x.shape, np.inf)
    for pos, dirn, half in ((x, dx, rects[None, :, 2]), (y, dy, rects[None, :, 3])):
        parallel = dirn == 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (-half - pos) / dirn
            t2 = (half - pos) / dirn
        low = np.where(parallel, np.where(np.abs(pos) <= half, -np.inf, np.inf), np.minimum(t1, t2))
        high = np.where(parallel, np.where(np.abs(pos) <= half, np.inf, -np.inf), np.maximum(t1, t2))
        enter = np.maximum(enter, low)
        leave = np.minimum(leave, high)
    met = (enter <= leave) & (leave >= 0.0)
    return np.where(met, np.maximum(enter, 0.0), np.inf)


def _circle_hits(o: np.ndarray, d: np.ndarray, circles: np.ndarray) -> np.ndarray:
    """``(n, k)`` distance along each ray to each circle (``inf`` if missed)."""
    if len(circles) == 0:
        return np.empty((len(o), 0))
    ox = o[:, 0:1] - circles[None, :, 0]
    oy = o[:, 1:2] - circles[None, :, 1]
    b = ox * d[:, 0:1] + oy * d[:, 1:2]
    c = ox * ox + oy * oy - circles[None, :, 2] ** 2
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    near, far = -b - root, -b + root
    met = (disc >= 0.0) & (far >= 0.0)
    return np.where(met, np.maximum(near, 0.0), np.inf)
