"""Per-axis limits against the wheels' polytope: the largest box and elliptic cylinder lie inside
it and no larger one does (a grid search), and on a straight line their durations are the
trapezoids of their own axes (closed forms); every shape is slower than the polytope."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.control import WheelLimits, polyline
from omnikin.control.path import parse_path
from omnikin.control.twist_limits import ELLIPSE_SIDES, compare_limits, largest_shape
from omnikin.errors import InputError

LIMITS = WheelLimits(speed=12.0, accel=40.0)
ROBOTS = ("tomasi-omni3", "omni4", "mecanum4")


def reach(jac: np.ndarray, twists: np.ndarray) -> float:
    """The largest wheel speed over the twists ``(k, 3)``."""
    return float(np.max(np.abs(twists @ jac.T)))


def boundary(shape, count: int = 720) -> np.ndarray:
    """Twists on the shape's edge: its corners (box) or its rim at both ends of omega (cylinder)."""
    signs = np.array([(i, j, k) for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)
    if shape.kind == "box":
        return signs * np.array([shape.a, shape.b, shape.c])
    phi = np.linspace(0.0, 2 * math.pi, count, endpoint=False)
    rim = np.column_stack((shape.a * np.cos(phi), shape.b * np.sin(phi)))
    return np.vstack([np.column_stack((rim, np.full(count, s * shape.c))) for s in (-1.0, 1.0)])


def grid_best_volume(jac: np.ndarray, kind: str, speed: float, steps: int = 300) -> float:
    """The largest ``a b c`` on a grid of ``(a, b)``, ``c`` the most the wheels leave for it."""
    j = np.abs(jac)
    a_max = speed / np.max(j[:, 0])
    b_max = speed / np.max(j[:, 1])
    a, b = np.meshgrid(np.linspace(0, a_max, steps), np.linspace(0, b_max, steps))
    planar = (
        a[..., None] * j[:, 0] + b[..., None] * j[:, 1]
        if kind == "box"
        else np.hypot(a[..., None] * j[:, 0], b[..., None] * j[:, 1])
    )
    c = np.min((speed - planar) / j[:, 2], axis=-1)
    return float(np.max(np.where(c > 0, a * b * c, 0.0)))


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("kind", ["box", "ellipse"])
def test_the_largest_shape_is_inside_the_polytope_and_none_larger_is_found(name, kind):
    robot = load_robot(name)
    jac = np.asarray(robot.ik_matrix)
    shape = largest_shape(robot, kind, LIMITS.speed)
    assert reach(jac, boundary(shape)) <= LIMITS.speed * (1 + 1e-9)
    assert reach(jac, boundary(shape)) >= LIMITS.speed * (1 - 1e-6)  # it touches the polytope
    assert shape.volume >= grid_best_volume(jac, kind, LIMITS.speed) * (1 - 1e-3)


@pytest.mark.parametrize("name", ROBOTS)
def test_on_a_straight_line_each_shape_takes_the_trapezoid_of_its_own_axis(name):
    robot = load_robot(name)
    jac = np.asarray(robot.ik_matrix)
    length = 2.0
    line = polyline([(0.0, 0.0), (length, 0.0)], heading="fixed")

    def trapezoid(v: float, a: float) -> float:
        return length / v + v / a if v * v / a < length else 2 * math.sqrt(length / a)

    per_speed = float(np.max(np.abs(jac[:, 0])))  # the polytope along x: the fastest wheel binds
    box = largest_shape(robot, "box", LIMITS.speed)
    cylinder = largest_shape(robot, "ellipse", LIMITS.speed)
    along = cylinder.a * math.cos(math.pi / ELLIPSE_SIDES)  # the inscribed polygon's edge crosses +x
    durations = compare_limits(robot, line, LIMITS)
    scale = LIMITS.accel / LIMITS.speed  # accelerations: the same shape, A / W times
    assert durations["polytope"] == pytest.approx(
        trapezoid(LIMITS.speed / per_speed, LIMITS.accel / per_speed), rel=2e-3
    )
    assert durations["box"] == pytest.approx(trapezoid(box.a, box.a * scale), rel=2e-3)
    assert durations["ellipse"] == pytest.approx(trapezoid(along, along * scale), rel=2e-3)


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("spec", ["figure8 1", "square 2 0.3"])
def test_every_shape_inside_the_polytope_is_slower_than_the_polytope(name, spec):
    durations = compare_limits(load_robot(name), parse_path(spec), LIMITS)
    assert durations["box_ratio"] > 1.0 and durations["ellipse_ratio"] > 1.0


def test_layouts_without_every_direction_are_refused():
    with pytest.raises(InputError, match=r"robot 'diff-drive' does not translate in every direction"):
        largest_shape(load_robot("diff-drive"), "box")
    with pytest.raises(InputError, match=r"kind must be 'box' or 'ellipse'"):
        largest_shape(load_robot("omni4"), "sphere")
