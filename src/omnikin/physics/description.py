"""A robot as a physical body: chassis, wheels, rollers, joints and motors, derived from any
:class:`~omnikin.kinematics.robot.Robot` (pure data and NumPy; no physics engine needed).

:func:`describe` turns the kinematic robot (wheel positions, drive directions, radii, roller
angles, steering) into the frozen :class:`PhysicalRobot` that :mod:`omnikin.physics.mjcf`
writes as a MuJoCo model, :mod:`omnikin.physics.urdf` as URDF, and a viewer draws; a robot as
built keeps the body of its design (:func:`as_built_description`). Every quantity the robot file
does not give has a default (the constants below); the optional ``physical:`` fields of the file
(:class:`~omnikin.kinematics.physical.PhysicalBody` on the robot,
:class:`~omnikin.kinematics.physical.PhysicalWheel` on each wheel) override them.

Frames and units: SI, radians. The **body frame** is ``base_link`` of ``docs/conventions.md``
(x forward, y left, z up) with its origin on the floor under the kinematic reference point: the
chassis pose is the robot's pose ``(x, y, theta)``. A **wheel's frame** has its origin at the
hub centre, at height ``r_i`` (the chassis stands level whatever the radii), x along the drive
direction ``u = (cos delta, sin delta, 0)``, y along the axle ``a = z x u``, z up; a positive
rotation about +y is a positive wheel speed.

Key equations (Swedish wheel of roller angle ``gamma``, ``R`` rows of ``n`` rollers):

- roller: ellipsoid of revolution, semi-axes ``a`` along its spin axis and ``b`` across, centre
  at ``c`` from the axle; at angle ``psi`` about the axle its centre is ``R_y(psi) (0, y_j, -c)``
  and its axis ``R_y(psi) (cos gamma, sin gamma, 0)``, row ``j`` turned by ``j 2 pi / (n R)``;
- envelope, the axle height with the roller at ``phi`` from the bottom:
  ``h(phi) = c cos(phi) + sqrt(b^2 + (a^2 - b^2) cos^2(gamma) sin^2(phi))``;
- osculation ``h''(0) = 0``: ``(a^2 - b^2) cos^2(gamma) = b c``; a row's rollers end to end in
  the side view: ``tan(pi / n) = a cos(gamma) / c`` (:func:`roller_shape`);
- scale: the mean of ``h`` over ``|phi| <= pi / (n R)`` is the file's radius (:func:`roller_geometry`);
- command ramp: the largest rim acceleration at which every driven wheel needs at most half its
  friction ``mu_i N_i`` and half its motor torque (:func:`ramp_rim_acceleration`).

``docs/physics.md`` is the full account, with the derivations, every default with its reason and
the measurements: "The model" (frames, tyres, rollers, motors), "Rollers: the osculating
ellipsoid" (the shape, rows side by side, inclined rollers), "Defaults" (the table, the robot as
built, the command ramp) and "What the engine accepts" (the rotor inertias).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..kinematics.physical import PhysicalWheel
from ..kinematics.robot import Robot
from ..kinematics.wheels import Wheel
from ..world.collision import Footprint

GRAVITY = 9.81
"""Standard gravity [m/s^2]."""
CHASSIS_DENSITY = 1000.0
"""Mean density of a chassis [kg/m^3] (docs/physics.md, "Defaults")."""
WHEEL_DENSITY = 1000.0
"""Mean density of a wheel taken as a solid cylinder [kg/m^3]."""
TYRE_WIDTH_PER_RADIUS = 0.4
"""Width of standard wheels and castors per unit radius."""
ROLLER_MASS_SHARE = 0.5
"""Part of a Swedish wheel's mass in its rollers."""
FORK_MASS_SHARE = 0.25
"""Mass of the fork of a steered wheel or castor per unit wheel mass."""
FRICTION = 1.0
"""Sliding friction between tyre or roller and floor (rubber on concrete)."""
RIM_SPEED = 3.0
"""Default rim speed limit [m/s] of a motor."""
HANDOFF_DEG = 15.0
"""Largest angle [deg] a roller carries the wheel before the next one takes over (default count)."""
SERVO_TIME_CONSTANT = 0.005
"""Time constant [s] of the wheel speed servo."""
MAX_STEP = 0.002
"""Longest time step [s] the engine accepts (:data:`omnikin.physics.mjcf.STEP_RANGE`)."""
SERVO_STEP_RATIO = 15.0
"""Largest ``gain * MAX_STEP / I_axle`` of a wheel's speed servo: beyond it a wheel whose own
axle inertia is small against the robot's mass it drives falls into a limit cycle (docs/physics.md,
"What the engine accepts")."""
INTEGRAL_TIME = 0.05
"""Integral time [s] of the wheel speed servo."""
RAMP_SHARE = 0.5
"""Part of each wheel's friction limit ``mu N`` and of its motor torque the command ramp may ask
for (docs/physics.md, "Defaults", "The command ramp")."""
DRIVABLE = 0.05
"""Relative singular value of the rim rows below which a body motion counts as not driven by the
rims (:func:`drivable_rows`; docs/physics.md, "The command ramp", for the number)."""
STEER_RATE = math.pi
"""Default steering rate limit [rad/s]."""
STEER_FULL_TORQUE_ANGLE = 0.05
"""Steering error [rad] at which the steering servo gives its full torque."""
CIRCLE_TOLERANCE = 1e-3
"""Relative tolerance for mounting points evenly spaced on a circle (cylinder chassis)."""


@dataclass(frozen=True)
class Chassis:
    """The chassis (body frame). ``shape`` ``"cylinder"`` (``size = (radius, half height)``) or
    ``"box"`` (``size = (half x, half y, half z)``) centred at ``centre`` [m]; ``mass`` [kg],
    ``com`` [m] and principal moments ``inertia`` [kg m^2] about the com along the body axes."""

    shape: str
    centre: tuple[float, float, float]
    size: tuple[float, ...]
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float]


@dataclass(frozen=True)
class Roller:
    """One roller in its wheel's frame: centre ``position`` [m], unit spin ``axis``, ``row``
    (0-based) and ``index`` in its row."""

    row: int
    index: int
    position: tuple[float, float, float]
    axis: tuple[float, float, float]


@dataclass(frozen=True)
class RollerSet:
    """The rollers of a Swedish wheel (docs/physics.md, "Rollers: the osculating ellipsoid").

    ``rows`` x ``per_row`` ellipsoids of semi-axes ``half_length`` (``a``, along the spin axis)
    and ``radius`` (``b``, across), centres at ``centre_radius`` (``c``) from the axle and
    ``offsets`` [m] along it per row; ``crest`` = ``b + c`` [m], ``ripple`` [m] the fall of the
    axle between two hand-overs, ``mass`` [kg] and ``inertia`` (about the spin axis, across)
    [kg m^2] of one roller."""

    angle: float
    rows: int
    per_row: int
    half_length: float
    radius: float
    centre_radius: float
    crest: float
    ripple: float
    offsets: tuple[float, ...]
    mass: float
    inertia: tuple[float, float]
    rollers: tuple[Roller, ...]


@dataclass(frozen=True)
class Motor:
    """A wheel motor: torque limit [N m], speed limit [rad/s], the command ramp's acceleration
    limit [rad/s^2], the speed servo's gain [N m s/rad] and integral time [s] (a PI controller:
    torque ``gain (e + z)``, ``dz/dt = e / integral_time``, ``e`` the speed error [rad/s]), and
    the rotor's inertia seen at the axle, ``armature`` [kg m^2] (:func:`rotor_inertia`)."""

    max_torque: float
    max_speed: float
    max_accel: float
    gain: float
    integral_time: float
    armature: float = 0.0


@dataclass(frozen=True)
class Steering:
    """The vertical steering joint of a steered wheel or castor, through ``pivot`` (x, y) [m,
    body frame]; the wheel's hub trails it by ``trail`` [m] against the drive direction.
    ``limits`` [rad] relative to the mounting drive direction (None: turns all the way round).
    ``actuated``: a position servo with ``max_torque`` [N m], ``max_rate`` [rad/s] (command
    ramp), ``stiffness`` [N m/rad], ``damping`` [N m s/rad] and ``integral_time`` [s] (PI, as
    :class:`Motor`); a castor swivels freely.
    ``fork_mass`` [kg] and ``fork_inertia`` [kg m^2] (principal moments, fork frame) of the
    part that turns with the steering, wheel excluded; ``inertia`` [kg m^2] of everything that
    turns about the steering axis, the steering motor's rotor ``armature`` [kg m^2]
    (:func:`steering_rotor_inertia`) included."""

    pivot: tuple[float, float]
    trail: float
    limits: tuple[float, float] | None
    actuated: bool
    max_torque: float
    max_rate: float
    stiffness: float
    damping: float
    integral_time: float
    fork_mass: float
    fork_inertia: tuple[float, float, float]
    inertia: float
    armature: float = 0.0


@dataclass(frozen=True)
class WheelBody:
    """One wheel as a body (module docstring for frames).

    ``hub`` [m, body frame] at zero steering, ``drive`` ``delta`` [rad] at zero steering,
    ``axle`` the unit axle ``(-sin delta, cos delta, 0)``; ``radius`` the file's rolling radius
    [m], ``width`` [m], ``mass`` [kg] of the whole wheel; ``hub_mass`` [kg] and ``hub_inertia``
    (about the axle, across) [kg m^2] of the wheel without rollers; ``friction``; ``driven``
    with its ``motor`` (None when passive); ``rollers`` (Swedish wheels), ``steering`` (steered
    wheels and castors); ``fields`` names the physical fields the file gave."""

    name: str
    type: str
    hub: tuple[float, float, float]
    drive: float
    axle: tuple[float, float, float]
    radius: float
    width: float
    mass: float
    hub_mass: float
    hub_inertia: tuple[float, float]
    friction: float
    driven: bool
    motor: Motor | None
    rollers: RollerSet | None
    steering: Steering | None
    fields: tuple[str, ...]

    @property
    def reach(self) -> float:
        """Lowest point of the wheel below its hub at zero wheel angle [m]: the crest of the
        bottom roller, or the radius."""
        return self.rollers.crest if self.rollers is not None else self.radius


@dataclass(frozen=True)
class PhysicalRobot:
    """The physical description of a robot: its ``chassis`` and ``wheels`` (file order, castors
    included), ``gravity`` [m/s^2], total ``mass`` [kg], and ``support_margin`` [m]: distance of
    the robot's centre of mass (projected on the floor) inside the polygon of the wheels'
    contact points, negative outside (the robot tips over); contacts in a line have no inside:
    minus the distance to their segment (:func:`support_margin`)."""

    name: str
    chassis: Chassis
    wheels: tuple[WheelBody, ...]
    gravity: float
    mass: float
    com: tuple[float, float, float]
    support_margin: float

    @property
    def driven(self) -> tuple[WheelBody, ...]:
        return tuple(w for w in self.wheels if w.driven)

    @property
    def steered(self) -> tuple[WheelBody, ...]:
        """Wheels with an actuated steering joint (the robot's steerable wheels, file order)."""
        return tuple(w for w in self.wheels if w.steering is not None and w.steering.actuated)

    def wheel(self, name: str) -> WheelBody:
        for w in self.wheels:
            if w.name == name:
                return w
        raise InputError(f"robot {self.name!r} has no wheel {name!r}")


# --- rollers -----------------------------------------------------------------------------------
def roller_shape(gamma: float, per_row: int) -> tuple[float, float, float]:
    """``(a, b, c)`` of an osculating roller of a wheel with crest radius ``b + c = 1`` (module
    docstring): roller angle ``gamma`` [rad], ``per_row`` rollers meeting end to end in the side
    view; ``b`` the small root of ``b^2 (T^2 + sin^2 gamma) - b (2 T^2 + 1) + T^2 = 0``,
    ``T = tan(pi / per_row)``, ``a = c T / cos(gamma)``."""
    t2 = math.tan(math.pi / per_row) ** 2
    cg = math.cos(gamma)
    b = 2.0 * t2 / (2.0 * t2 + 1.0 + math.sqrt(1.0 + 4.0 * t2 * cg * cg))
    c = 1.0 - b
    a = c * math.sqrt(t2) / cg
    return a, b, c


def axle_height(b: float, c: float, phi) -> np.ndarray:
    """Height of the axle above the floor [units of b, c] with an osculating roller at angle
    ``phi`` [rad] from the bottom: ``c cos(phi) + sqrt(b^2 + b c sin^2(phi))``."""
    phi = np.asarray(phi, dtype=float)
    return c * np.cos(phi) + np.sqrt(b * b + b * c * np.sin(phi) ** 2)


def roller_geometry(wheel: Wheel, rows: int, per_row: int) -> tuple[float, float, float, float, float]:
    """``(a, b, c, ripple, row_width)`` [m] of the rollers of Swedish ``wheel``: the osculating
    shape scaled so that the mean axle height over a roller's hand-over interval
    ``|phi| <= pi / (per_row rows)`` is the wheel's radius (module docstring); ``row_width`` is a
    roller's extent along the axle, ``2 sqrt(b^2 + (a^2 - b^2) sin^2 gamma)``."""
    a1, b1, c1 = roller_shape(wheel.roller, per_row)
    half = math.pi / (per_row * rows)
    phi = np.linspace(-half, half, 401)
    heights = axle_height(b1, c1, phi)
    mean = float(np.sum(heights[1:] + heights[:-1]) * (phi[1] - phi[0]) / 2.0) / (2.0 * half)
    scale = wheel.radius / mean
    a, b, c = a1 * scale, b1 * scale, c1 * scale
    ripple = float(heights[200] - heights[0]) * scale
    sg = math.sin(wheel.roller)
    return a, b, c, ripple, 2.0 * math.sqrt(b * b + (a * a - b * b) * sg * sg)


def roller_set(wheel: Wheel, rows: int, per_row: int, width: float | None, mass: float) -> RollerSet:
    """The rollers of Swedish ``wheel`` in its frame (module docstring): :func:`roller_geometry`,
    the rows staggered evenly about the axle, spread evenly over ``width`` ``w`` [m] at
    ``y_j = (j - (rows - 1) / 2) w / rows`` (None: all in the wheel's mid-plane, ``y_j = 0``);
    ``mass`` [kg] of all rollers."""
    gamma = wheel.roller
    a, b, c, ripple, _ = roller_geometry(wheel, rows, per_row)
    spread = 0.0 if width is None else width / rows
    offsets = tuple((j - (rows - 1) / 2.0) * spread for j in range(rows))
    each = mass / (rows * per_row)
    cg, sg = math.cos(gamma), math.sin(gamma)
    rollers = []
    for j in range(rows):
        for k in range(per_row):
            psi = 2.0 * math.pi * k / per_row + 2.0 * math.pi * j / (per_row * rows)
            cp, sp = math.cos(psi), math.sin(psi)
            rollers.append(Roller(j, k, (-c * sp, offsets[j], -c * cp), (cg * cp, sg, -cg * sp)))
    return RollerSet(
        angle=gamma,
        rows=rows,
        per_row=per_row,
        half_length=a,
        radius=b,
        centre_radius=c,
        crest=b + c,
        ripple=ripple,
        offsets=offsets,
        mass=each,
        inertia=(0.4 * each * b * b, 0.2 * each * (a * a + b * b)),
        rollers=tuple(rollers),
    )


def default_rows(wheel: Wheel) -> int:
    """2 staggered rows for omni rollers (gamma = 0), 1 for inclined ones (docs/physics.md, "Defaults")."""
    return 2 if wheel.roller == 0.0 else 1


def default_rollers(rows: int) -> int:
    """Rollers per row so that a roller hands over every :data:`HANDOFF_DEG` (at least 3)."""
    return max(3, math.ceil(180.0 / (rows * HANDOFF_DEG) - 1e-9))


# --- chassis ------------------------------------------------------------------------------------
def mounting_points(robot: Robot) -> np.ndarray:
    """``(n, 2)`` mounting points [m]: hub positions, steering axes for steered wheels and castors."""
    return np.array([[w.x, w.y] for w in robot.wheels], dtype=float)


def regular_circle(points: np.ndarray) -> tuple[np.ndarray, float] | None:
    """``(centre, radius)`` when three or more ``points`` lie evenly spaced on a circle about
    their centroid (within :data:`CIRCLE_TOLERANCE`), else None."""
    n = len(points)
    if n < 3:
        return None
    centre = points.mean(axis=0)
    rel = points - centre
    dist = np.hypot(rel[:, 0], rel[:, 1])
    radius = float(dist.mean())
    if radius <= 0.0 or np.max(np.abs(dist - radius)) > CIRCLE_TOLERANCE * radius:
        return None
    angles = np.sort(np.arctan2(rel[:, 1], rel[:, 0]))
    gaps = np.diff(np.concatenate([angles, angles[:1] + 2.0 * math.pi]))
    if np.max(np.abs(gaps - 2.0 * math.pi / n)) > CIRCLE_TOLERANCE * 2.0 * math.pi:
        return None
    return centre, radius


def chassis_shape(robot: Robot, mean_radius: float, height: float) -> tuple[str, tuple, tuple]:
    """``(shape, centre, size)`` [m, body frame] of the chassis (docs/physics.md, "Defaults", "chassis
    shape"): ``"cylinder"`` with ``size = (radius, half height)`` or ``"box"`` with its half extents."""
    points = mounting_points(robot)
    circle = regular_circle(points)
    if circle is not None:
        centre, radius = circle
        return "cylinder", (float(centre[0]), float(centre[1]), mean_radius), (radius, height / 2.0)
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2.0
    half = np.maximum((high - low) / 2.0, mean_radius)
    return "box", (float(centre[0]), float(centre[1]), mean_radius), (float(half[0]), float(half[1]), height / 2.0)


def shape_volume_inertia(shape: str, size: tuple, mass: float) -> tuple[float, tuple[float, float, float]]:
    """Volume [m^3] and principal moments about the centre [kg m^2] of a uniform cylinder
    (radius, half height) or box (half extents)."""
    if shape == "cylinder":
        radius, half = size
        h = 2.0 * half
        side = mass * (3.0 * radius * radius + h * h) / 12.0
        return math.pi * radius * radius * h, (side, side, mass * radius * radius / 2.0)
    lx, ly, lz = (2.0 * s for s in size)
    inertia = (mass * (ly * ly + lz * lz) / 12.0, mass * (lx * lx + lz * lz) / 12.0, mass * (lx * lx + ly * ly) / 12.0)
    return lx * ly * lz, inertia


# --- support polygon -------------------------------------------------------------------------
def convex_hull(points: np.ndarray) -> np.ndarray:
    """Vertices of the convex hull of ``(n, 2)`` points, counter-clockwise (Andrew's monotone
    chain); collinear points are dropped."""
    pts = sorted({(float(p[0]), float(p[1])) for p in points})
    if len(pts) < 3:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def cross(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def wheel_loads(contacts: np.ndarray, com: np.ndarray, weight: float) -> np.ndarray:
    """Static normal loads [N] of wheels at ``contacts`` ``(n, 2)`` [m] carrying ``weight`` [N]
    whose line of action passes through ``com`` (x, y): the force and moment balance
    ``sum N_i = W``, ``sum N_i x_i = W x``, ``sum N_i y_i = W y``; its least-norm solution (exact
    for three wheels not in a line, the even share for symmetric layouts), at least 1 % of the
    even share (a robot that cannot stand is refused by the engine, not here)."""
    a = np.vstack([np.ones(len(contacts)), contacts[:, 0], contacts[:, 1]])
    b = weight * np.array([1.0, com[0], com[1]])
    loads = np.linalg.pinv(a) @ b
    return np.maximum(loads, 0.01 * weight / len(contacts))


def support_margin(contacts: np.ndarray, point: np.ndarray) -> float:
    """Signed distance [m] of ``point`` inside the convex hull of ``contacts`` (negative
    outside). A hull without area (one contact, or all in a line) has no inside: the margin is
    minus the distance to that point or segment, 0 on it."""
    hull = convex_hull(contacts)
    if len(hull) < 3:
        return -segment_distance(point, hull[0], hull[-1])
    margin = math.inf
    for i in range(len(hull)):
        p, q = hull[i], hull[(i + 1) % len(hull)]
        edge = q - p
        inward = np.array([-edge[1], edge[0]]) / math.hypot(edge[0], edge[1])
        margin = min(margin, float(inward @ (point - p)))
    return margin


def segment_distance(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Distance [m] from ``point`` to the segment from ``start`` to ``end`` (x, y), a point
    when they coincide: to the nearest point ``start + t (end - start)``, ``t`` clipped to [0, 1]."""
    edge = np.asarray(end, dtype=float) - start
    length2 = float(edge @ edge)
    t = 0.0 if length2 == 0.0 else min(1.0, max(0.0, float((point - start) @ edge) / length2))
    return float(np.hypot(*(np.asarray(point, dtype=float) - start - t * edge)))


def steered_support_margin(robot: Robot, com, steer) -> float:
    """:func:`support_margin` of the centre of mass ``com`` (x, y) [m] among the contacts of
    ``robot``'s wheels with its steerable wheels at ``steer`` [rad] (file order): an off-centred
    wheel's contact trails its steering axis and swings round it as it steers
    (:meth:`omnikin.kinematics.wheels.Wheel.contact_point`); castors and fixed wheels at their mounting."""
    angles = dict(zip(robot.steer_names, np.atleast_1d(np.asarray(steer, dtype=float)), strict=True))
    contacts = np.array([w.contact_point(angles.get(w.name, 0.0)) for w in robot.wheels])
    return support_margin(contacts, np.asarray(com, dtype=float)[:2])


# --- command ramp -------------------------------------------------------------------------------
def planar_mass_matrix(mass: float, com, yaw_inertia: float) -> np.ndarray:
    """Mass matrix ``(3, 3)`` of a rigid body for the planar twist ``(vx, vy, omega)`` of the body
    frame: ``mass`` [kg], centre of mass ``com`` (x, y) [m] and ``yaw_inertia`` [kg m^2] about
    the body origin's vertical axis (kinetic energy ``xi^T M xi / 2``)."""
    cx, cy = float(com[0]), float(com[1])
    return np.array([[mass, 0.0, -mass * cy], [0.0, mass, mass * cx], [-mass * cy, mass * cx, yaw_inertia]])


def polytope_max(rows: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """For each row ``c`` of ``costs`` ``(k, d)``, ``max |c . x|`` over ``x`` in the row space of
    ``rows`` ``(n, d)`` with ``|rows x|_inf <= 1`` (a bounded, centrally symmetric polytope there):
    the largest value over its vertices.

    In the orthonormal coordinates ``y`` of the row space (``x = B y``, ``g_i = rows_i B``) the
    polytope ``{y : |g_i . y| <= 1}`` is the polar of the convex hull of the points ``+-g_i``
    (Ziegler, "Lectures on Polytopes", 2.3): each facet ``{p : h . p = 1}`` of that hull is the
    vertex ``y = h`` of the polytope. The hull of ``2 n`` points in the rank (at most 3)
    dimensions costs ``O(n log n)`` (Qhull, Barber, Dobkin and Huhdanpaa, "The Quickhull
    algorithm for convex hulls"), where enumerating every choice of ``rank`` active constraints
    costs ``O(n^rank)``."""
    _, sv, vt = np.linalg.svd(rows, full_matrices=False)
    rank = int(np.sum(sv > sv[0] * 1e-9)) if len(sv) else 0
    if rank == 0:
        return np.zeros(len(costs))
    basis = vt[:rank].T  # (d, rank): x = basis y
    g = rows @ basis
    values = costs @ basis  # (k, rank)
    if rank == 1:  # a segment: |y| <= 1 / max |g_i|
        return np.abs(values[:, 0]) / float(np.abs(g).max())
    from scipy.spatial import ConvexHull, QhullError  # on use: importing omnikin stays light

    points = np.vstack([g, -g])
    try:
        hull = ConvexHull(points)
    except QhullError:  # nearly flat within the rank kept: joggle the input (relative 1e-11)
        hull = ConvexHull(points, qhull_options="QJ")
    # facet equations: normal . p + offset <= 0 inside, offset < 0 (the origin is inside)
    vertices = hull.equations[:, :-1] / -hull.equations[:, -1:]
    return np.abs(values @ vertices.T).max(axis=1)


def drivable_rows(rows: np.ndarray, radii: np.ndarray, lever: float) -> np.ndarray:
    """``rows`` ``(n, 3)`` [rad/s per twist] without the body motions the rims barely drive: with
    the rim rows ``r_i J_i`` on the scaled twist ``(vx, vy, lever omega)``, singular directions
    below :data:`DRIVABLE` of the largest are dropped (truncated singular value decomposition).
    Parallel drive directions off by a robot's mounting errors formally drive the motion across
    them; the tyres' sideways grip does, not the motors (docs/physics.md, "The command ramp")."""
    scale = np.array([1.0, 1.0, float(lever)])
    rim = radii[:, None] * rows / scale
    u, sv, vt = np.linalg.svd(rim, full_matrices=False)
    keep = sv > DRIVABLE * sv[0] if len(sv) else np.zeros(0, dtype=bool)
    return (u[:, keep] * sv[keep]) @ vt[keep] * scale / radii[:, None]


def ramp_rim_acceleration(
    rows: np.ndarray,
    radii: np.ndarray,
    mass_matrix: np.ndarray,
    traction_limits: np.ndarray,
    torque_limits: np.ndarray,
    axle_inertia: np.ndarray,
    gains: np.ndarray,
    lever: float = 1.0,
    share: float = RAMP_SHARE,
) -> float:
    """The command ramp's rim acceleration ``a`` [m/s^2] (docs/physics.md, "The command ramp"):
    the largest at which no driven wheel needs more than ``share`` of its friction limit
    ``traction_limits`` (``mu_i N_i`` [N]) or of its ``torque_limits`` [N m] for any body
    acceleration the wheels can produce. ``rows`` ``(n, 3)`` the driven wheels' rows [rad/s per
    twist], ``radii`` [m], ``mass_matrix`` :func:`planar_mass_matrix`, ``axle_inertia`` [kg m^2]
    each wheel's own inertia about its axle, ``gains`` the speed servos' gains [N m s/rad].
    ``lever`` [m]: the length that makes a turn rate comparable with a speed (the largest wheel
    distance from the body origin); the rows are first cut to their well-conditioned part
    (:func:`drivable_rows`). Axle torques ``t = K J (J^T K J)^+ M xi'`` (``K`` the gains, ``J``
    the rows, ``M`` the mass matrix), contact forces ``|t_i| |J_i,xy|``, maximised over the
    vertices of the body accelerations ``{xi' : |r_i J_i xi'| <= a}`` (:func:`polytope_max`)."""
    rows = drivable_rows(rows, radii, lever)
    k = np.diag(gains)
    distribution = k @ rows @ np.linalg.pinv(rows.T @ k @ rows) @ mass_matrix  # axle torque per xi'
    torque = polytope_max(radii[:, None] * rows, distribution)  # max |t_i| per unit rim acceleration
    force = torque * np.hypot(rows[:, 0], rows[:, 1])
    needed = np.concatenate([force / traction_limits, (torque + axle_inertia / radii) / torque_limits])
    worst = float(needed.max())
    return share / worst if worst > 0.0 else math.inf


def rotor_inertia(gain: float, axle_inertia: float, step: float = MAX_STEP) -> float:
    """The motor rotor's inertia [kg m^2] seen at the axle of a wheel whose speed servo has
    ``gain`` [N m s/rad] and whose own inertia about its axle is ``axle_inertia`` [kg m^2]: the
    least that keeps ``gain step / (axle_inertia + rotor) <= SERVO_STEP_RATIO`` at the longest
    ``step`` [s] (docs/physics.md, "What the engine accepts"); 0 when the wheel alone suffices."""
    return max(0.0, gain * step / SERVO_STEP_RATIO - axle_inertia)


def steering_rotor_inertia(stiffness: float, inertia: float, step: float = MAX_STEP) -> float:
    """The steering motor rotor's inertia [kg m^2] seen at the steering axis of a position servo
    of ``stiffness`` [N m/rad] turning ``inertia`` [kg m^2]: the least that keeps
    ``stiffness step^2 / (inertia + rotor) <= 1`` at the longest ``step`` [s], i.e. the servo's
    natural frequency at most one radian per step (its stiffness acts explicitly; docs/physics.md,
    "What the engine accepts"); 0 when the steered parts alone suffice."""
    return max(0.0, stiffness * step * step - inertia)


# --- wheels ---------------------------------------------------------------------------------
def _given(wheel: Wheel) -> PhysicalWheel:
    return wheel.physical if wheel.physical is not None else PhysicalWheel()


class _Placement(NamedTuple):
    """Where a wheel sits at zero steering (body frame): ``drive`` ``delta`` [rad], ``trail`` [m]
    of the hub behind the steering axis (0 for fixed wheels), ``hub`` centre [m] at height ``r``,
    unit ``axle`` ``(-sin delta, cos delta, 0)`` and floor ``contact`` (x, y) [m]."""

    drive: float
    trail: float
    hub: tuple[float, float, float]
    axle: tuple[float, float, float]
    contact: tuple[float, float]


def _placement(wheel: Wheel) -> _Placement:
    """:class:`_Placement` of ``wheel``: the hub of a steered wheel or castor trails its steering
    axis ``(x, y)`` by ``offset`` against the drive direction, and so does the floor contact."""
    delta = float(wheel.drive)
    cd, sd = math.cos(delta), math.sin(delta)
    trail = wheel.offset if (wheel.is_steerable or wheel.is_castor) else 0.0
    return _Placement(
        drive=delta,
        trail=trail,
        hub=(wheel.x - trail * cd, wheel.y - trail * sd, wheel.radius),
        axle=(-sd, cd, 0.0),
        contact=(wheel.x - wheel.offset * cd, wheel.y - wheel.offset * sd),
    )


def _hub_inertia(mass: float, radius: float, width: float) -> tuple[float, float]:
    """Principal moments [kg m^2] of a hub as a uniform cylinder of ``mass`` [kg], ``radius`` and
    ``width`` [m]: about the axle, across it."""
    return mass * radius**2 / 2.0, mass * (3.0 * radius**2 + width**2) / 12.0


def _robot_com(
    chassis_mass: float,
    chassis_com,
    wheels: Sequence[Wheel],
    masses: Sequence[float],
    fork_masses: Sequence[float],
    contacts: np.ndarray,
    total: float,
) -> np.ndarray:
    """Centre of mass ``(x, y, z)`` [m, body frame] of the robot of ``total`` mass [kg]: the chassis
    of ``chassis_mass`` [kg] at ``chassis_com`` (x, y, z), each of ``wheels`` of its ``masses`` [kg]
    at its ``contacts`` ``(n, 2)`` point at hub height, its fork of its ``fork_masses`` [kg] at its
    mounting point at hub height."""
    moments = chassis_mass * np.asarray(chassis_com, dtype=float)
    for w, mass, fork_mass, (cx, cy) in zip(wheels, masses, fork_masses, contacts, strict=True):
        moments = moments + mass * np.array([cx, cy, w.radius]) + fork_mass * np.array([w.x, w.y, w.radius])
    return moments / total


def _wheel_mass_and_width(wheel: Wheel) -> tuple[float, float, RollerSet | None, float]:
    """Mass [kg], width [m], rollers and hub radius [m] of ``wheel`` (rollers weigh their share)."""
    given = _given(wheel)
    r = wheel.radius
    if not wheel.is_swedish:
        width = given.width if given.width is not None else TYRE_WIDTH_PER_RADIUS * r
        mass = given.mass if given.mass is not None else WHEEL_DENSITY * math.pi * r * r * width
        return mass, width, None, r
    rows = given.rows if given.rows is not None else default_rows(wheel)
    per_row = given.rollers if given.rollers is not None else default_rollers(rows)
    width = given.width if given.width is not None else roller_geometry(wheel, rows, per_row)[4]
    mass = given.mass if given.mass is not None else WHEEL_DENSITY * math.pi * r * r * width
    rollers = roller_set(wheel, rows, per_row, given.width, ROLLER_MASS_SHARE * mass)
    return mass, width, rollers, rollers.centre_radius


def describe(robot: Robot) -> PhysicalRobot:
    """The physical description of ``robot`` (docs/physics.md, "Defaults", for every default); a
    robot as built (:attr:`omnikin.kinematics.robot.Robot.design` set) keeps the body of its design
    (:func:`as_built_description`)."""
    if not isinstance(robot, Robot):
        raise InputError(f"describe: expected a Robot, got {type(robot).__name__}")
    if robot.design is not None:
        return as_built_description(robot, describe(robot.design))
    body = robot.physical
    rolling = robot.rolling
    mean_radius = float(np.mean([w.radius for w in rolling]))
    height = body.height if body is not None and body.height is not None else mean_radius
    shape, centre, size = chassis_shape(robot, mean_radius, height)
    volume, _ = shape_volume_inertia(shape, size, 1.0)
    chassis_mass = body.mass if body is not None and body.mass is not None else CHASSIS_DENSITY * volume
    _, chassis_inertia = shape_volume_inertia(shape, size, chassis_mass)
    placements = [_placement(w) for w in robot.wheels]
    contacts = np.array([place.contact for place in placements])
    balanced = (*(float(v) for v in contacts.mean(axis=0)), centre[2])
    com = body.com if body is not None and body.com is not None else balanced

    parts = [_wheel_mass_and_width(w) for w in robot.wheels]
    fork_masses = [
        FORK_MASS_SHARE * m if (w.is_steerable or w.is_castor) else 0.0
        for w, (m, *_) in zip(robot.wheels, parts, strict=True)
    ]
    total = chassis_mass + sum(p[0] for p in parts) + sum(fork_masses)

    explicit = [w for w in rolling if w.encoder is not None or _given(w).max_torque is not None]
    driven_names = {w.name for w in (explicit or rolling)}
    robot_com = _robot_com(chassis_mass, com, robot.wheels, [p[0] for p in parts], fork_masses, contacts, total)
    loads = wheel_loads(contacts, robot_com[:2], total * GRAVITY)

    driven_load = sum(n for w, n in zip(robot.wheels, loads, strict=True) if w.name in driven_names)
    wheels = []
    ramp_inputs: list[tuple[Wheel, float, float]] = []  # driven wheel, mu N [N], axle inertia [kg m^2]
    for w, place, (mass, width, rollers, hub_radius), fork_mass, load in zip(
        robot.wheels, placements, parts, fork_masses, loads, strict=True
    ):
        given = _given(w)
        friction = given.friction if given.friction is not None else FRICTION
        trail = place.trail
        hub_mass = mass - (rollers.mass * len(rollers.rollers) if rollers is not None else 0.0)
        hub_inertia = _hub_inertia(hub_mass, hub_radius, width)
        torque = given.max_torque
        if torque is None:
            torque = friction * load * w.radius
        motor = None
        driven = w.name in driven_names
        if driven:
            wheel_axle = hub_inertia[0] + (mass - hub_mass) * hub_radius**2
            i_eff = wheel_axle + total * float(load / driven_load) * w.radius**2
            max_speed = w.max_speed if w.max_speed else RIM_SPEED / w.radius
            gain = i_eff / SERVO_TIME_CONSTANT
            rotor = rotor_inertia(gain, wheel_axle)
            motor = Motor(torque, max_speed, 0.0, gain, INTEGRAL_TIME, rotor)  # max_accel: ramp below
            ramp_inputs.append((w, load * friction, wheel_axle + rotor))
        steering = None
        if w.is_steerable or w.is_castor:
            fork = max(w.radius / 2.0, 1e-3)
            fork_inertia = (fork_mass * fork * fork / 6.0,) * 3
            turning = fork_inertia[2] + hub_inertia[1] + hub_mass * trail * trail
            limits = None
            if w.steer is not None and (w.steer.lower > -math.pi + 1e-9 or w.steer.upper < math.pi - 1e-9):
                limits = (float(w.steer.lower), float(w.steer.upper))
            steer_torque = given.max_torque
            if steer_torque is None:
                steer_torque = friction * load * (trail + w.radius)
            stiffness = steer_torque / STEER_FULL_TORQUE_ANGLE
            steer_rotor = steering_rotor_inertia(stiffness, turning) if w.is_steerable else 0.0
            turning += steer_rotor
            steering = Steering(
                pivot=(float(w.x), float(w.y)),
                trail=float(trail),
                limits=limits,
                actuated=w.is_steerable,
                max_torque=steer_torque,
                max_rate=STEER_RATE,
                stiffness=stiffness,
                damping=2.0 * math.sqrt(stiffness * turning),
                integral_time=INTEGRAL_TIME,
                fork_mass=fork_mass,
                fork_inertia=fork_inertia,
                inertia=turning,
                armature=steer_rotor,
            )
        wheels.append(
            WheelBody(
                name=w.name,
                type=w.type,
                hub=place.hub,
                drive=place.drive,
                axle=place.axle,
                radius=w.radius,
                width=width,
                mass=mass,
                hub_mass=hub_mass,
                hub_inertia=hub_inertia,
                friction=friction,
                driven=driven,
                motor=motor,
                rollers=rollers,
                steering=steering,
                fields=tuple(sorted(given.given)),
            )
        )
    wheels = _with_ramp(robot, wheels, ramp_inputs, total, robot_com, chassis_mass, com, chassis_inertia[2])
    chassis = Chassis(
        shape,
        centre,
        tuple(float(s) for s in size),
        chassis_mass,
        (float(com[0]), float(com[1]), float(com[2])),
        chassis_inertia,
    )
    return PhysicalRobot(
        name=robot.name,
        chassis=chassis,
        wheels=tuple(wheels),
        gravity=GRAVITY,
        mass=total,
        com=(float(robot_com[0]), float(robot_com[1]), float(robot_com[2])),
        support_margin=support_margin(contacts, robot_com[:2]),
    )


def footprint(description: PhysicalRobot) -> Footprint:
    """The robot of ``description`` seen from above (:class:`omnikin.world.collision.Footprint`,
    body frame, m): the chassis (a circle, or a rectangle for a box chassis) and each wheel, a
    fixed one as the rectangle of its side view's length ``2 max(r, reach)`` and its width, a
    steered wheel or castor as the circle it sweeps about its steering axis (radius: the trail
    plus the half diagonal of that rectangle)."""
    chassis = description.chassis
    circles, rects = [], []
    if chassis.shape == "cylinder":
        circles.append([chassis.centre[0], chassis.centre[1], chassis.size[0]])
    else:
        rects.append([chassis.centre[0], chassis.centre[1], chassis.size[0], chassis.size[1], 0.0])
    for wheel in description.wheels:
        half_length = max(wheel.radius, wheel.reach)
        if wheel.steering is None:
            rects.append([wheel.hub[0], wheel.hub[1], half_length, wheel.width / 2.0, wheel.drive])
        else:
            pivot = wheel.steering.pivot
            circles.append([pivot[0], pivot[1], wheel.steering.trail + math.hypot(half_length, wheel.width / 2.0)])
    return Footprint(np.asarray(circles, dtype=float).reshape(-1, 3), np.asarray(rects, dtype=float).reshape(-1, 5))


def as_built_description(robot: Robot, design: PhysicalRobot) -> PhysicalRobot:
    """The physical description of ``robot``, a robot as built, from ``design``, the description
    of the robot it was built to (:attr:`omnikin.kinematics.robot.Robot.design`): it differs only where the
    errors say. Kept from the design: the chassis (shape, size, mass, centre of mass, inertia),
    every wheel's mass, width, rollers per row and rows, friction, motor (torque, speed, ramp,
    servo, rotor) and steering servo. Taken from ``robot``: each wheel's hub position, drive
    direction, radius and roller angle (the rollers' shape follows them, their mass does not;
    the hub's inertia follows its radius), the steering axis; then the robot's centre of mass
    (the wheels moved with their masses) and its support margin. Why: the defaults derive the
    chassis from the wheels' layout (docs/physics.md, "Defaults", "The robot as built keeps its
    body")."""
    wheels = []
    placements = [_placement(w) for w in robot.wheels]
    for w, place, body in zip(robot.wheels, placements, design.wheels, strict=True):
        rollers, hub_radius = body.rollers, w.radius
        if rollers is not None:
            width = body.width if "width" in body.fields else None
            rollers = roller_set(w, rollers.rows, rollers.per_row, width, rollers.mass * len(rollers.rollers))
            hub_radius = rollers.centre_radius
        steering = body.steering
        if steering is not None:
            steering = replace(steering, pivot=(float(w.x), float(w.y)), trail=float(place.trail))
        wheels.append(
            replace(
                body,
                type=w.type,
                hub=place.hub,
                drive=place.drive,
                axle=place.axle,
                radius=w.radius,
                hub_inertia=_hub_inertia(body.hub_mass, hub_radius, body.width),
                rollers=rollers,
                steering=steering,
            )
        )
    contacts = np.array([place.contact for place in placements], dtype=float)
    fork_masses = [b.steering.fork_mass if b.steering is not None else 0.0 for b in wheels]
    masses = [b.mass for b in wheels]
    com = _robot_com(design.chassis.mass, design.chassis.com, robot.wheels, masses, fork_masses, contacts, design.mass)
    return replace(
        design,
        name=robot.name,
        wheels=tuple(wheels),
        com=(float(com[0]), float(com[1]), float(com[2])),
        support_margin=support_margin(contacts, com[:2]),
    )


def _with_ramp(
    robot: Robot,
    wheels: list[WheelBody],
    driven: list[tuple[Wheel, float, float]],
    total: float,
    robot_com: np.ndarray,
    chassis_mass: float,
    chassis_com,
    chassis_yaw_inertia: float,
) -> list[WheelBody]:
    """``wheels`` with the command ramp of :func:`ramp_rim_acceleration` in their motors."""
    if not driven:
        return wheels
    yaw = chassis_yaw_inertia + chassis_mass * (chassis_com[0] ** 2 + chassis_com[1] ** 2)
    for body in wheels:  # the wheels and forks as point masses at their hubs, plus their own turn
        rest = body.mass + (body.steering.fork_mass if body.steering is not None else 0.0)
        yaw += rest * (body.hub[0] ** 2 + body.hub[1] ** 2) + body.hub_inertia[1]
    by_name = {b.name: b for b in wheels}
    motors = [by_name[w.name].motor for w, _, _ in driven]
    rows = robot.jacobian(wheels=[w.name for w, _, _ in driven])
    if robot.steerable:
        rows = rows[0] if rows.ndim == 3 else rows
    radii = np.array([w.radius for w, _, _ in driven])
    accel = ramp_rim_acceleration(
        np.asarray(rows, dtype=float),
        radii,
        planar_mass_matrix(total, robot_com[:2], yaw),
        np.array([traction for _, traction, _ in driven]),
        np.array([m.max_torque for m in motors if m is not None]),
        np.array([inertia for _, _, inertia in driven]),
        np.array([m.gain for m in motors if m is not None]),
        lever=max(math.hypot(w.x, w.y) for w in robot.wheels) or 1.0,
    )
    ramps = {w.name: accel / w.radius for w, _, _ in driven}
    return [replace(b, motor=replace(b.motor, max_accel=ramps[b.name])) if b.motor is not None else b for b in wheels]
