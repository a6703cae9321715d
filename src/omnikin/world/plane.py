"""Geometry of the plane: rectangles, circles and simple polygons (pure NumPy).

Arrays [m]: ``rects`` ``(m, 5)``: centre x, y, half length, half width, yaw [rad] (the half
length along the rectangle's own x); ``circles`` ``(k, 3)``: centre x, y, radius; ``points``
``(n, 2)``; polygons ``(n, 2)`` corners in order. Signed distances are negative inside: to a
rectangle the classic box distance in its frame,
``|max(|q| - h, 0)| + min(max(|q_x| - h_x, |q_y| - h_y), 0)``; to a circle ``|p - c| - r``.
"""

from __future__ import annotations

import math

import numpy as np


def wall_rects(points: np.ndarray, thickness: float) -> np.ndarray:
    """``(n - 1, 5)`` rectangles of a wall's polyline ``points`` ``(n, 2)`` (module docstring)."""
    a, b = points[:-1], points[1:]
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    centre = (a + b) / 2.0
    half_length = length / 2.0 + thickness / 2.0
    return np.column_stack([centre, half_length, np.full(len(a), thickness / 2.0), np.arctan2(d[:, 1], d[:, 0])])


def in_frames(points: np.ndarray, rects: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``points`` ``(n, 2)`` in each rectangle's frame: ``(n, m)`` x and y."""
    c, s = np.cos(rects[:, 4]), np.sin(rects[:, 4])
    dx = points[:, 0:1] - rects[None, :, 0]
    dy = points[:, 1:2] - rects[None, :, 1]
    return c * dx + s * dy, -s * dx + c * dy


def rect_distance(points: np.ndarray, rects: np.ndarray) -> np.ndarray:
    """Signed distances ``(n, m)`` [m] of ``points`` ``(n, 2)`` to ``rects`` ``(m, 5)``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    x, y = in_frames(points, rects)
    qx = np.abs(x) - rects[None, :, 2]
    qy = np.abs(y) - rects[None, :, 3]
    outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
    return outside + np.minimum(np.maximum(qx, qy), 0.0)


def rect_closest(points: np.ndarray, rects: np.ndarray) -> np.ndarray:
    """``(n, m, 2)`` the point of each rectangle's boundary or inside nearest to each point
    (the point itself when inside)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    x, y = in_frames(points, rects)
    cx = np.clip(x, -rects[None, :, 2], rects[None, :, 2])
    cy = np.clip(y, -rects[None, :, 3], rects[None, :, 3])
    c, s = np.cos(rects[:, 4]), np.sin(rects[:, 4])
    return np.stack([rects[None, :, 0] + c * cx - s * cy, rects[None, :, 1] + s * cx + c * cy], axis=-1)


def circle_distance(points: np.ndarray, circles: np.ndarray) -> np.ndarray:
    """Signed distances ``(n, k)`` [m] of ``points`` ``(n, 2)`` to ``circles`` ``(k, 3)``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return np.hypot(points[:, 0:1] - circles[None, :, 0], points[:, 1:2] - circles[None, :, 1]) - circles[None, :, 2]


def rect_corners(rects: np.ndarray) -> np.ndarray:
    """``(m, 4, 2)`` corners of each rectangle, counter-clockwise."""
    c, s = np.cos(rects[:, 4]), np.sin(rects[:, 4])
    signs = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    lx = signs[None, :, 0] * rects[:, None, 2]
    ly = signs[None, :, 1] * rects[:, None, 3]
    return np.stack(
        [rects[:, None, 0] + c[:, None] * lx - s[:, None] * ly, rects[:, None, 1] + s[:, None] * lx + c[:, None] * ly],
        axis=-1,
    )


def rect_rect_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Signed distances ``(p, m)`` [m] between rectangles ``a`` ``(p, 5)`` and ``b`` ``(m, 5)``.

    Apart, the distance is exact: the nearest points of two convex polygons include a corner of
    one, so it is the least distance of a corner of either to the other. Overlapping (no
    separating axis among the four edge normals), it is minus the least overlap along those axes
    (the penetration depth)."""
    if len(a) == 0 or len(b) == 0:
        return np.empty((len(a), len(b)))
    ca, cb = rect_corners(a), rect_corners(b)
    corner_a = rect_distance(ca.reshape(-1, 2), b).reshape(len(a), 4, len(b)).min(axis=1)
    corner_b = rect_distance(cb.reshape(-1, 2), a).reshape(len(b), 4, len(a)).min(axis=1).T
    apart = np.minimum(corner_a, corner_b)
    depth = np.full(apart.shape, np.inf)
    yaw_a, yaw_b = np.broadcast_arrays(a[:, None, 4], b[None, :, 4])
    for axis in (yaw_a, yaw_a + math.pi / 2.0, yaw_b, yaw_b + math.pi / 2.0):
        ux, uy = np.cos(axis)[..., None], np.sin(axis)[..., None]
        pa = ca[:, None, :, 0] * ux + ca[:, None, :, 1] * uy
        pb = cb[None, :, :, 0] * ux + cb[None, :, :, 1] * uy
        overlap = np.minimum(pa.max(axis=-1) - pb.min(axis=-1), pb.max(axis=-1) - pa.min(axis=-1))
        depth = np.minimum(depth, overlap)
    return np.where(depth > 0.0, -depth, np.maximum(apart, 0.0))


def segments_cross(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray, touch: bool = True) -> np.ndarray:
    """Whether segments ``a0 a1`` and ``b0 b1`` (broadcast ``(..., 2)``) cross, or touch when ``touch``."""

    def orient(p, q, r):
        return np.sign(
            (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])
        )

    d1, d2 = orient(b0, b1, a0), orient(b0, b1, a1)
    d3, d4 = orient(a0, a1, b0), orient(a0, a1, b1)
    if touch:
        return (d1 * d2 <= 0) & (d3 * d4 <= 0)
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def simple_polygon_problem(polygon: np.ndarray, tiny: float) -> str | None:
    """None if ``polygon`` ``(n, 2)`` is simple (no two edges cross but neighbours at their
    corner) and encloses more than ``tiny`` squared, else which edges cross (counted from 0)."""
    n = len(polygon)
    start, end = polygon, np.roll(polygon, -1, axis=0)
    cross = segments_cross(start[:, None], end[:, None], start[None, :], end[None, :])
    index = np.arange(n)
    apart = np.abs(index[:, None] - index[None, :])
    cross &= (apart > 1) & (apart < n - 1)
    if cross.any():
        i, j = (int(k) for k in np.argwhere(cross)[0])
        return (
            f"edges {i} and {j} (from corner {i} and from corner {j}, counted from 0) cross: the polygon must be simple"
        )
    area = 0.5 * float(np.sum(start[:, 0] * end[:, 1] - end[:, 0] * start[:, 1]))
    if abs(area) < tiny**2:
        return "encloses no area"
    return None


def point_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """``(m,)`` whether each of ``points`` ``(m, 2)`` lies inside ``polygon`` ``(n, 2)`` (even-odd rule)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    x, y = points[:, 0:1], points[:, 1:2]
    a, b = polygon, np.roll(polygon, -1, axis=0)
    straddles = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        at = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return (np.count_nonzero(straddles & (x < at), axis=1) % 2) == 1


def interior_point(polygon: np.ndarray, shift: float) -> np.ndarray:
    """A point just inside the simple ``polygon`` ``(n, 2)``: the middle of its first edge moved
    by ``shift`` [m] to the inner side."""
    a, b = polygon[0], polygon[1]
    end = np.roll(polygon, -1, axis=0)
    area = float(np.sum(polygon[:, 0] * end[:, 1] - end[:, 0] * polygon[:, 1]))
    edge = b - a
    inward = np.array([-edge[1], edge[0]]) / np.hypot(*edge) * (1.0 if area > 0 else -1.0)
    return (a + b) / 2.0 + inward * shift


def overlapping_polygons(polygons: list[np.ndarray], shift: float) -> list[tuple[int, int]]:
    """Pairs ``(i, j)``, i < j, of simple polygons that overlap: edges cross, or one lies inside
    the other (polygons that share an edge or a corner do not overlap)."""
    found = []
    for j in range(len(polygons)):
        for i in range(j):
            a, b = polygons[i], polygons[j]
            edges_cross = segments_cross(
                a[:, None], np.roll(a, -1, axis=0)[:, None], b[None, :], np.roll(b, -1, axis=0)[None, :], touch=False
            ).any()
            inside = (
                point_in_polygon(interior_point(a, shift)[None], b)[0]
                or point_in_polygon(interior_point(b, shift)[None], a)[0]
            )
            if edges_cross or inside:
                found.append((i, j))
    return found


def triangulate(polygon: np.ndarray) -> np.ndarray:
    """``(n - 2, 3)`` corner indices of triangles that tile the simple ``polygon`` ``(n, 2)``
    (ear clipping: cut off a convex corner whose triangle holds no other corner, repeat;
    quadratic in n, which a world bounds)."""
    points = np.asarray(polygon, dtype=float)
    end = np.roll(points, -1, axis=0)
    ccw = float(np.sum(points[:, 0] * end[:, 1] - end[:, 0] * points[:, 1])) > 0.0
    left = list(range(len(points))) if ccw else list(range(len(points)))[::-1]
    triangles = []

    def cross(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    while len(left) > 3:
        for k in range(len(left)):
            i, j, m = left[k - 1], left[k], left[(k + 1) % len(left)]
            a, b, c = points[i], points[j], points[m]
            if cross(a, b, c) <= 0.0:
                continue  # a reflex (or flat) corner is no ear
            others = [q for q in left if q not in (i, j, m)]
            inside = any(
                cross(a, b, points[q]) >= 0.0 and cross(b, c, points[q]) >= 0.0 and cross(c, a, points[q]) >= 0.0
                for q in others
            )
            if not inside:
                triangles.append((i, j, m))
                del left[k]
                break
        else:  # only flat corners left: what remains encloses no area
            break
    if len(left) == 3:
        triangles.append((left[0], left[1], left[2]))
    return np.array(triangles, dtype=np.int64).reshape(-1, 3)


def shape_gaps(
    rects_a: np.ndarray, circles_a: np.ndarray, rects_b: np.ndarray, circles_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Signed distances [m] between two sets of shapes, each rectangles ``(m, 5)`` and circles
    ``(k, 3)``: rectangle against rectangle ``(m_a, m_b)``, circle against rectangle
    ``(k_a, m_b)``, rectangle against circle ``(m_a, k_b)`` and circle against circle
    ``(k_a, k_b)``, rows the shapes of ``a``, columns those of ``b``."""
    return (
        rect_rect_distance(rects_a, rects_b),
        rect_distance(circles_a[:, :2], rects_b) - circles_a[:, 2:3],
        rect_distance(circles_b[:, :2], rects_a).T - circles_b[None, :, 2],
        circle_distance(circles_a[:, :2], circles_b) - circles_a[:, 2:3],
    )
