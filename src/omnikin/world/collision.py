"""A robot's footprint against the world's shapes: clearance, first contact, contacts.

The **footprint** is the robot seen from above, in the body frame: circles ``(c, 3)`` (x, y,
radius) and rectangles ``(p, 5)`` (as :mod:`omnikin.world.shapes` lays them out), [m]; the
physics description gives it for any robot (:func:`omnikin.physics.description.footprint`).
Its **clearance** at a pose is the least signed distance between any of its shapes and any of
the world's, negative when they overlap.

The kinematic engine moves the robot along exact SE(2) arcs ``pose (+) exp(s xi)``, ``s`` in
[0, 1] (``xi`` the step's body increment). :func:`advance` stops it at first contact by
conservative advancement: no point of the footprint moves faster than ``|v| + |omega| R`` (R the
footprint's reach from the body origin), so the robot may go ``clearance / (|v| + |omega| R)`` of
the step without touching anything; repeated, this ends within :data:`TOUCH` of the first contact
without ever passing through a wall however thin or fast (Mirtich's conservative advancement).
A robot in contact stays where it is while its motion does not take it away from what it
touches: it stops at the wall, then backs or turns away from it freely.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import WorldFileError
from ..kinematics.se2 import between, compose, exp, log
from .model import World
from .plane import circle_distance, rect_closest, rect_corners, rect_distance, shape_gaps
from .shapes import Shapes, shapes_of

TOUCH = 1e-4
"""Clearance [m] at which the robot touches a body: it stops within this of the first contact."""
NEAR = 0.05
"""Clearance [m] within which :func:`clearance` is exact (farther: a lower bound)."""
START_TOLERANCE = 1e-9
"""Overlap [m] a start pose may have with a body (rounding of a pose written exactly at contact)."""
SLIDE = 1e-9
"""Loss of clearance [m] over the first :data:`TOUCH` of a step below which a robot in contact
slides along what it touches instead of stopping (a motion parallel to a wall)."""
MAX_ADVANCES = 200
"""Most conservative advances in one step; a robot that needs more (grazing a wall at a tiny
angle) goes only as far as they took it in that step, without a contact."""


@dataclass(frozen=True)
class Footprint:
    """The robot seen from above (module docstring): ``circles`` ``(c, 3)`` and ``rects``
    ``(p, 5)`` in the body frame [m]."""

    circles: np.ndarray
    rects: np.ndarray

    @property
    def reach(self) -> float:
        """Farthest point of the footprint from the body origin [m]."""
        far = 0.0
        if len(self.circles):
            far = float(np.max(np.hypot(self.circles[:, 0], self.circles[:, 1]) + self.circles[:, 2]))
        if len(self.rects):
            corners = rect_corners(self.rects).reshape(-1, 2)
            far = max(far, float(np.max(np.hypot(corners[:, 0], corners[:, 1]))))
        return far

    def placed(self, pose) -> tuple[np.ndarray, np.ndarray]:
        """The circles and rectangles in the world frame with the body at ``pose`` (x, y, theta)."""
        x, y, theta = (float(v) for v in pose)
        c, s = math.cos(theta), math.sin(theta)
        circles = self.circles.copy()
        circles[:, 0] = x + c * self.circles[:, 0] - s * self.circles[:, 1]
        circles[:, 1] = y + s * self.circles[:, 0] + c * self.circles[:, 1]
        rects = self.rects.copy()
        rects[:, 0] = x + c * self.rects[:, 0] - s * self.rects[:, 1]
        rects[:, 1] = y + s * self.rects[:, 0] + c * self.rects[:, 1]
        rects[:, 4] = self.rects[:, 4] + theta
        return circles, rects


@dataclass(frozen=True)
class Clearance:
    """The footprint's clearance at a pose: ``distance`` [m] (``inf`` in an empty world), the
    ``body`` nearest (index in the world's bodies, -1 for none) and the ``point`` (x, y) [m,
    world frame] of that body nearest the robot."""

    distance: float
    body: int
    point: tuple[float, float]


@dataclass(frozen=True)
class Contact:
    """The robot began to touch a body of the world: at ``time`` [s] of the run, ``body`` (its
    name), at ``point`` (x, y) [m, world frame]. Both engines report contacts so."""

    time: float
    body: str
    point: tuple[float, float]


def clearance(shapes: Shapes, footprint: Footprint, pose, reach: float | None = None, point: bool = False) -> Clearance:
    """The :class:`Clearance` of ``footprint`` (of ``reach``, :attr:`Footprint.reach`) at
    ``pose`` (x, y, theta) among ``shapes``.

    Exact within :data:`NEAR` of a body. Farther, a lower bound (what conservative advancement
    needs), cheap to compute: the distance from the body origin to the nearest shape less the
    footprint's reach. The ``point`` is computed when asked for (``point``), within
    :data:`NEAR` only (else NaN)."""
    if shapes.count == 0:
        return Clearance(math.inf, -1, (math.nan, math.nan))
    reach = footprint.reach if reach is None else reach
    origin = np.asarray(pose, dtype=float)[None, :2]
    to_rects = rect_distance(origin, shapes.rects)[0] - reach
    to_circles = circle_distance(origin, shapes.circles)[0] - reach
    bound = np.concatenate([to_rects, to_circles])
    nearest = int(np.argmin(bound))
    if bound[nearest] >= NEAR:
        owner = shapes.rect_body[nearest] if nearest < len(to_rects) else shapes.circle_body[nearest - len(to_rects)]
        return Clearance(float(bound[nearest]), int(owner), (math.nan, math.nan))
    near_r, near_c = to_rects < NEAR, to_circles < NEAR
    # the shapes left out are at least their bound away: the clearance is never more than that
    far = np.concatenate([to_rects[~near_r], to_circles[~near_c]])
    far_bound = float(far.min()) if len(far) else math.inf
    shapes = Shapes(shapes.rects[near_r], shapes.rect_body[near_r], shapes.circles[near_c], shapes.circle_body[near_c])
    circles, rects = footprint.placed(pose)
    rr, cr, rc, cc = shape_gaps(rects, circles, shapes.rects, shapes.circles)
    pairs = [  # (signed distances (footprint shape, world shape), their bodies, the point of a pair (i, j))
        (rr, shapes.rect_body, lambda i, j: _rect_rect_point(rects[i], shapes.rects[j])),
        (cr, shapes.rect_body, lambda i, j: _rect_point(shapes.rects[j], circles[i, :2])),
        (
            rc,
            shapes.circle_body,
            lambda i, j: _circle_point(shapes.circles[j], np.array(_rect_point(rects[i], shapes.circles[j, :2]))),
        ),
        (cc, shapes.circle_body, lambda i, j: _circle_point(shapes.circles[j], circles[i, :2])),
    ]
    candidates: list[tuple[float, int, Any]] = []
    for d, bodies, point_of in pairs:
        if d.size == 0:
            continue
        i, j = np.unravel_index(np.argmin(d), d.shape)
        candidates.append((float(d[i, j]), int(bodies[j]), lambda i=i, j=j, point_of=point_of: point_of(i, j)))
    distance, body, where = min(candidates, key=lambda c: c[0])
    if distance > far_bound:  # a shape left out may be nearer than the exact ones: its bound holds
        return Clearance(far_bound, body, (math.nan, math.nan))
    return Clearance(distance, body, where() if point else (math.nan, math.nan))


def _rect_point(rect: np.ndarray, towards: np.ndarray) -> tuple[float, float]:
    """The point of rectangle ``rect`` (x, y, half length, half width, yaw) nearest ``towards``."""
    near = rect_closest(np.asarray(towards, dtype=float)[None], rect[None])[0, 0]
    return float(near[0]), float(near[1])


def _circle_point(circle: np.ndarray, towards: np.ndarray) -> tuple[float, float]:
    """The point of ``circle`` (x, y, r) nearest ``towards`` (x, y)."""
    dx, dy = float(towards[0] - circle[0]), float(towards[1] - circle[1])
    norm = math.hypot(dx, dy)
    if norm == 0.0:
        return float(circle[0]), float(circle[1])
    return float(circle[0] + circle[2] * dx / norm), float(circle[1] + circle[2] * dy / norm)


def _rect_rect_point(robot: np.ndarray, body: np.ndarray) -> tuple[float, float]:
    """The point of rectangle ``body`` nearest rectangle ``robot`` (nearest to a corner of
    ``robot``, or a corner of ``body`` nearest ``robot``)."""
    mine, theirs = rect_corners(robot[None])[0], rect_corners(body[None])[0]
    to_body = rect_distance(mine, body[None])[:, 0]
    to_robot = rect_distance(theirs, robot[None])[:, 0]
    if to_body.min() <= to_robot.min():
        k = int(np.argmin(to_body))
        near = rect_closest(mine[k : k + 1], body[None])[0, 0]
        return float(near[0]), float(near[1])
    k = int(np.argmin(to_robot))
    return float(theirs[k, 0]), float(theirs[k, 1])


def arc_pose(pose, xi, s: float) -> np.ndarray:
    """``pose (+) exp(s xi)``: the body ``s`` of the way along the step ``xi`` (vx dt, vy dt, omega dt)."""
    return compose(np.asarray(pose, dtype=float), exp(s * np.asarray(xi, dtype=float)))


def advance(
    shapes: Shapes, footprint: Footprint, pose, xi, reach: float, here: Clearance | None = None
) -> tuple[np.ndarray, Clearance | None, float]:
    """The robot at ``pose`` moved along the step ``xi`` until it ends or touches a body.

    Parameters
    ----------
    shapes : Shapes
        The world's shapes.
    footprint : Footprint
        The robot's footprint, of ``reach`` [m] (:attr:`Footprint.reach`).
    pose : array_like, shape (3,)
        Start pose (x, y, theta) [m, m, rad], clear of every body (clearance >= -:data:`TOUCH`).
    xi : array_like, shape (3,)
        The step's body increment ``(vx dt, vy dt, omega dt)`` [m, m, rad].
    here : Clearance, optional
        The clearance at ``pose``, if known.

    Returns
    -------
    pose : numpy.ndarray, shape (3,)
        Where the robot is at the end of the step.
    touch : Clearance or None
        The clearance where the robot stopped against a body (module docstring), None when it
        went the whole step.
    gone : float
        The part of the step [0, 1] the robot went (1 when it went the whole step).
    """
    pose = np.asarray(pose, dtype=float)
    xi = np.asarray(xi, dtype=float)
    speed = math.hypot(xi[0], xi[1]) + abs(xi[2]) * reach
    if here is None:
        here = clearance(shapes, footprint, pose, reach)
    if speed == 0.0:
        return pose, None, 1.0
    s = 0.0
    if here.distance < TOUCH:
        probe = min(1.0, TOUCH / speed)
        ahead = clearance(shapes, footprint, arc_pose(pose, xi, probe), reach)
        if ahead.distance < here.distance - SLIDE:
            return pose, here, 0.0  # pushing against what it touches: it stays
        s, here = probe, ahead
    for _ in range(MAX_ADVANCES):
        if s >= 1.0:
            return arc_pose(pose, xi, 1.0), None, 1.0
        step = max(here.distance - TOUCH / 2.0, TOUCH / 2.0) / speed  # stop short of the contact, never in it
        s_next = min(1.0, s + step)
        there = clearance(shapes, footprint, arc_pose(pose, xi, s_next), reach)
        if there.distance < TOUCH and there.distance <= here.distance:
            if there.distance < 0.0:  # went in by less than TOUCH: stay at the last clear pose
                return arc_pose(pose, xi, s), here, s
            return arc_pose(pose, xi, s_next), there, s_next
        s, here = s_next, there
    return arc_pose(pose, xi, s), None, s  # grazing: slowed this step, no contact


class Collider:
    """A robot's ``footprint`` among the bodies of ``world``: where it may go (module docstring).

    Parameters
    ----------
    world : World
        The world (its walls and obstacles; movable obstacles count as fixed here: the
        kinematic engine has no forces to push them).
    footprint : Footprint
        The robot seen from above, body frame.
    """

    def __init__(self, world: World, footprint: Footprint):
        self.world = world
        self.footprint = footprint
        self.shapes = shapes_of(world)
        self.reach = footprint.reach
        self.bodies = world.bodies

    def require_clear(self, pose, what: str = "its start pose") -> None:
        """Refuse, in one line, a ``pose`` where the footprint overlaps a body of the world."""
        here = clearance(self.shapes, self.footprint, pose)
        if here.distance < -START_TOLERANCE:
            x, y, theta = (float(v) for v in pose)
            raise WorldFileError(
                f"world {self.world.name!r}: the robot at {what} ({x:.4g} m, {y:.4g} m, "
                f"{math.degrees(theta):.4g} deg) overlaps {self.bodies[here.body]!r} by "
                f"{-here.distance * 1e3:.3g} mm: move the start pose or the body"
            )

    def contact(self, time: float, pose) -> Contact:
        """The :class:`Contact` of the robot touching a body at ``pose`` at ``time`` [s]."""
        touch = clearance(self.shapes, self.footprint, pose, self.reach, point=True)
        return Contact(float(time), self.bodies[touch.body], touch.point)

    def follow(self, t, poses) -> tuple[np.ndarray, list[Contact]]:
        """The robot that would move through ``poses`` ``(N + 1, 3)`` (at times ``t`` ``(N + 1,)``
        [s], in the frame where it starts, as on an empty floor) moved through the world from its
        start pose instead: each step's body increment is kept until the robot touches a body
        (:func:`advance`).

        Returns the poses ``(N + 1, 3)`` in the world frame and the contacts, each where a touch
        begins (not repeated while the robot stays against the body)."""
        t = np.asarray(t, dtype=float)
        poses = np.asarray(poses, dtype=float)
        steps = log(between(poses[:-1], poses[1:]))  # (N, 3) exact body increments
        bound = np.hypot(steps[:, 0], steps[:, 1]) + np.abs(steps[:, 2]) * self.reach
        out = np.empty_like(poses)
        start = np.asarray(self.world.start, dtype=float)
        self.require_clear(start)
        out[0] = start
        contacts: list[Contact] = []
        touching = False
        k, n = 0, len(steps)
        while k < n:
            here = clearance(self.shapes, self.footprint, out[k], self.reach)
            free = here.distance - TOUCH
            # steps whose summed bound stays within the clearance cannot touch anything
            reach = np.cumsum(bound[k:]) if free > 0 else np.zeros(0)
            run = int(np.searchsorted(reach, free, side="left")) if free > 0 else 0
            if run > 0:
                out[k + 1 : k + run + 1] = compose(out[k], between(poses[k], poses[k + 1 : k + run + 1]))
                k += run
                touching = False
                continue
            pose, touch, s = self.step(out[k], steps[k], here)
            out[k + 1] = pose
            if touch is not None and not touching:
                contacts.append(self.contact(t[k] + s * (t[k + 1] - t[k]), pose))
            touching = touch is not None
            k += 1
        return out, contacts

    def step(self, pose, xi, here: Clearance | None = None) -> tuple[np.ndarray, Clearance | None, float]:
        """:func:`advance` in this world (``here``: the clearance at ``pose`` if known)."""
        return advance(self.shapes, self.footprint, pose, xi, self.reach, here)
