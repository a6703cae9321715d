"""What limits per axis of the body cost against the wheels' own limits: the largest box and the
largest elliptic cylinder of twists inside the wheel-space polytope, and a path's fastest timing
under each (:func:`compare_limits`).

Controllers and planners commonly limit a base's motion per axis of its body, ``|vx| <= Vx``,
``|vy| <= Vy``, ``|omega| <= Omega`` (ros2_controllers, Gazebo's MecanumDrive, Nav2's velocity
smoother), or, since navigation2 #6330 for MPPI, by an ellipse ``(vx / a)^2 + (vy / b)^2 <= 1``
with ``|omega| <= c``. The wheels' own limits ``|J xi| <= W`` make a polytope of twists ``xi``
(:mod:`omnikin.control.time_optimal`); a box or cylinder safe for the wheels must lie inside it:

    box:       |J_jx| Vx + |J_jy| Vy + |J_jw| Omega <= W                  for every wheel j
    cylinder:  sqrt((J_jx a)^2 + (J_jy b)^2) + |J_jw| c <= W

(the largest ``|J_j xi|`` over the shape). The largest of each (greatest volume ``Vx Vy Omega``,
``a b c``) is found by SciPy's SLSQP on the logarithms. The accelerations scale the same way
(``A / W`` times the shape). A path is then timed under the shape by the planner of the wheels
(:func:`~omnikin.control.time_optimal.time_rates`) with the shape's rows: the box's three axes;
the cylinder's ellipse as the polygon of :data:`ELLIPSE_SIDES` sides inscribed in it (its
vertices on the ellipse: inside the polytope too, its timing at most ``1 / cos(pi /
ELLIPSE_SIDES) - 1`` = 0.12 % slower than the ellipse's) and its ``omega`` row.

The largest shape by volume shares the wheels between translation and rotation: on a path that
does not turn, the rotation's share is of no use, which the polytope does not ask of it.

Every shape inside the polytope is slower than the polytope itself on every path: the ratio of
durations is what the per-axis limits cost.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from .path import Path, body_rates, derivative
from .time_optimal import PathRates, WheelLimits, path_rates, time_optimal, time_rates

ELLIPSE_SIDES = 64
"""Sides of the polygon the ellipse of a cylinder is timed as (inscribed in it)."""


@dataclass(frozen=True)
class TwistShape:
    """A box (``kind`` ``"box"``: ``|vx| <= a``, ``|vy| <= b``, ``|omega| <= c``) or an
    elliptic cylinder (``"ellipse"``: ``(vx / a)^2 + (vy / b)^2 <= 1``, ``|omega| <= c``) of body
    twists [m/s, m/s, rad/s]."""

    kind: str
    a: float
    b: float
    c: float

    @property
    def volume(self) -> float:
        """``a b c`` (the box's or the cylinder's volume up to a constant)."""
        return self.a * self.b * self.c


def _rows(robot: Robot) -> np.ndarray:
    if robot.steerable or robot.fixed:
        raise InputError(
            f"robot {robot.name!r} does not translate in every direction with wheels that do not steer: "
            "per-axis limits are compared for omni and mecanum layouts"
        )
    return np.abs(np.asarray(robot.ik_matrix, dtype=float))


def largest_shape(robot: Robot, kind: str, speed: float = 1.0) -> TwistShape:
    """The largest box or elliptic cylinder (``kind``) of twists inside ``robot``'s polytope
    ``|J xi| <= speed`` [rad/s] (module docstring)."""
    from scipy.optimize import minimize

    if kind not in ("box", "ellipse"):
        raise InputError(f"kind must be 'box' or 'ellipse', got {kind!r}")
    j = _rows(robot)

    def reach(v: np.ndarray) -> np.ndarray:  # the largest |J_j xi| over the shape, per wheel
        a, b, c = np.exp(v)
        planar = j[:, 0] * a + j[:, 1] * b if kind == "box" else np.hypot(j[:, 0] * a, j[:, 1] * b)
        return planar + j[:, 2] * c

    # a start inside: each axis alone at a third of its own limit
    start = np.log([speed / (3 * max(float(np.max(j[:, k])), 1e-12)) for k in range(3)])
    done = minimize(
        lambda v: -float(np.sum(v)),
        start,
        jac=lambda v: -np.ones(3),
        constraints=[{"type": "ineq", "fun": lambda v: speed - reach(v)}],
        method="SLSQP",
        options={"ftol": 1e-12, "maxiter": 500},
    )
    a, b, c = np.exp(done.x)
    shrink = speed / float(np.max(reach(done.x)))  # onto the boundary exactly (SLSQP's tolerance)
    return TwistShape(kind, float(a * shrink), float(b * shrink), float(c * shrink))


def shape_rates(path: Path, shape: TwistShape, speed: float) -> PathRates:
    """The rows of ``shape`` along ``path``, scaled so that each is within ``speed`` where the
    twist is within the shape: the body twist per unit path speed ``xi(s) = (R^T (x', y'),
    theta')`` divided by the shape's axes, times ``speed``; an ellipse as the polygon of
    :data:`ELLIPSE_SIDES` sides inscribed in it."""
    unit = body_rates(path) / np.array([shape.a, shape.b, shape.c])
    if shape.kind == "box":
        rows = unit
    else:  # |cos(phi) u + sin(phi) v| <= cos(pi / K) for K / 2 directions phi: the polygon inscribed in the circle
        phi = np.pi * np.arange(ELLIPSE_SIDES // 2) / (ELLIPSE_SIDES // 2)
        flat = (unit[:, :1] * np.cos(phi) + unit[:, 1:2] * np.sin(phi)) / math.cos(math.pi / ELLIPSE_SIDES)
        rows = np.column_stack((flat, unit[:, 2]))
    rows = rows * speed
    empty = np.zeros((len(rows), 0))
    return PathRates(rows, derivative(path, rows), empty, empty)


def compare_limits(robot: Robot, path: Path, limits: WheelLimits | None = None) -> dict[str, float]:
    """The fastest durations [s] of ``path`` under the wheels' polytope (``polytope``), the largest
    box inside it (``box``) and the largest elliptic cylinder inside it (``ellipse``), the
    accelerations limited alike (module docstring), and the ratios ``box / polytope`` and
    ``ellipse / polytope``."""
    limits = WheelLimits() if limits is None else limits
    path_rates(robot, path)  # (refuses a path the robot cannot drive, naming where)
    out = {"polytope": time_optimal(robot, path, limits).duration}
    for kind in ("box", "ellipse"):
        shape = largest_shape(robot, kind, limits.speed)
        rates = shape_rates(path, shape, limits.speed)
        out[kind] = time_rates(path, rates, np.full(rates.w.shape[1], limits.speed), limits.accel).duration
        out[f"{kind}_ratio"] = out[kind] / out["polytope"]
    return out
