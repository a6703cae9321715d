"""The fastest timing of a path under the wheels' limits: closed forms on a line and a turn in
place, toppra (an independent implementation of the same problem) on a circle, and the limits
held on a figure-eight when the timed motion is differentiated again."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.control import WheelLimits, circle, figure8, time_optimal
from omnikin.control.path import from_samples
from omnikin.errors import InputError
from support.toppra_reference import duration, toppra_sdot

R_WHEEL = 0.04125  # tomasi-omni3 (Tomasi & Todt): 82.5 mm wheels, hubs 113 mm from the centre, 120 deg apart
L_HUB = 0.113
PHI = np.radians([0.0, 120.0, 240.0])
# Tomasi & Todt's inverse kinematics: wheel j at angle phi_j drives tangentially (counter-clockwise)
W0 = np.column_stack((-np.sin(PHI), np.cos(PHI), np.full(3, L_HUB))) / R_WHEEL
LIMITS = WheelLimits(speed=12.0, accel=40.0)


def trapezoid_time(distance: float, vmax: float, amax: float) -> float:
    """Rest to rest over ``distance`` with speed and acceleration bounds (bang-coast-bang)."""
    if distance >= vmax**2 / amax:
        return distance / vmax + vmax / amax
    return 2.0 * math.sqrt(distance / amax)


@pytest.mark.parametrize("length", [0.05, 2.0])
def test_a_straight_line_takes_the_trapezoid_time_of_the_limiting_wheel(tomasi, length):
    n = int(length / 0.001) + 1
    xs = np.linspace(0.0, length, n)
    path = from_samples(np.column_stack((xs, np.zeros(n))), np.zeros(n), name="line")
    worst = np.max(np.abs(W0[:, 0]))  # rad/s of the busiest wheel per m/s along +x
    expected = trapezoid_time(length, LIMITS.speed / worst, LIMITS.accel / worst)
    assert time_optimal(tomasi, path, LIMITS).duration == pytest.approx(expected, rel=2e-3)


def test_a_turn_in_place_takes_the_trapezoid_time_of_the_hub_radius(tomasi):
    angle = 3 * math.pi
    n = 4001
    th = np.linspace(0.0, angle, n)
    path = from_samples(np.zeros((n, 2)), th, name="spin")
    rate, accel = LIMITS.speed * R_WHEEL / L_HUB, LIMITS.accel * R_WHEEL / L_HUB
    assert time_optimal(tomasi, path, LIMITS).duration == pytest.approx(trapezoid_time(angle, rate, accel), rel=2e-3)


@pytest.mark.parametrize("radius", [0.3, 1.0])
def test_a_circle_at_a_fixed_heading_is_as_fast_as_toppra_makes_it(tomasi, radius):
    path = circle(radius)  # from the origin along +x, counter-clockwise, heading 0
    phase = path.s / radius
    tangent = np.column_stack((np.cos(phase), np.sin(phase), np.zeros_like(phase)))
    bend = np.column_stack((-np.sin(phase), np.cos(phase), np.zeros_like(phase))) / radius
    expected = duration(path.s, toppra_sdot(path.s, tangent @ W0.T, bend @ W0.T, LIMITS.speed, LIMITS.accel))
    assert time_optimal(tomasi, path, LIMITS).duration == pytest.approx(expected, rel=1e-3)


def test_no_wheel_exceeds_its_limits_on_a_figure_eight_driven_at_its_limits(tomasi):
    path = figure8(1.0, heading="tangent")
    timing = time_optimal(tomasi, path, LIMITS)
    # the motion in time, differentiated again from the poses: world rates -> body -> wheels
    t = timing.t
    rates = np.gradient(path.pose, t, axis=0, edge_order=2)
    c, s = np.cos(path.pose[:, 2]), np.sin(path.pose[:, 2])
    body = np.column_stack((c * rates[:, 0] + s * rates[:, 1], -s * rates[:, 0] + c * rates[:, 1], rates[:, 2]))
    wheels = body @ W0.T
    accel = np.gradient(wheels, t, axis=0, edge_order=2)
    assert np.max(np.abs(wheels)) <= LIMITS.speed * 1.01
    assert np.max(np.abs(wheels)) >= LIMITS.speed * 0.99  # and somewhere at it: time-optimal
    assert np.percentile(np.abs(accel), 99.9) <= LIMITS.accel * 1.02


def test_a_differential_drive_refuses_a_path_that_needs_it_to_strafe():
    from omnikin import load_robot

    n = 200
    ys = np.linspace(0.0, 1.0, n)
    sideways = from_samples(np.column_stack((np.zeros(n), ys)), np.zeros(n), name="sideways")
    with pytest.raises(InputError, match=r"cannot drive path 'sideways': at s = 0 m .*cannot move sideways"):
        time_optimal(load_robot("diff-drive"), sideways, LIMITS)


@pytest.mark.parametrize("field", ["speed", "accel", "steer_rate"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), "12", True])
def test_limits_that_are_not_positive_numbers_are_refused(field, value):
    with pytest.raises(InputError, match=f"WheelLimits.{field} must be a number > 0"):
        WheelLimits(**{field: value})
