"""Regulated pure pursuit: a circle is its fixed point (the pursued arc through a point of the
circle, tangent to it, is the circle itself), a car's tightest turn from its geometry, never a
curvature beyond it, and paths it cannot follow refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.control import WheelLimits, circle, plan_trajectory, polyline
from omnikin.control.path import figure8, parse_path
from omnikin.control.pursuit import PurePursuit, max_curvature
from omnikin.errors import InputError
from omnikin.evaluation.tracking import track, tracking_errors
from omnikin.simulation.error_models import noise_profile

LIMITS = WheelLimits(speed=12.0, accel=40.0)


def test_a_cars_tightest_turn_is_that_of_its_inner_front_wheel_at_its_steering_limit():
    # the inner front wheel at (L, w/2) turning about (0, R): tan(delta) = L / (R - w/2)
    car = load_robot("ackermann")
    front = [w for w in car.wheels if w.steer is not None]
    rear = [w for w in car.wheels if w.steer is None]
    wheelbase = front[0].x - rear[0].x
    half_track = abs(front[0].y)
    delta = front[0].steer.upper
    radius = half_track + wheelbase / math.tan(delta)
    assert max_curvature(car) == pytest.approx(1.0 / radius, rel=1e-6)
    assert max_curvature(load_robot("diff-drive")) == math.inf


@pytest.mark.parametrize(("name", "radius"), [("diff-drive", 1.0), ("ackermann", 5.0)])
def test_a_circle_started_on_is_followed_exactly(name, radius):
    # on the circle and along its tangent, the arc to any point of the circle ahead is the circle:
    # pure pursuit's fixed point, so the error is the integration's rounding
    robot = load_robot(name)
    trajectory = plan_trajectory(robot, circle(radius, heading="tangent"), LIMITS)
    run = track(robot, trajectory, PurePursuit(robot, trajectory, rate=50), rate=50, settle=2.0)
    on = run.t <= trajectory.duration
    radius_of = np.hypot(run.truth[on, 0], run.truth[on, 1] - radius)
    assert np.max(np.abs(radius_of - radius)) < 1e-6
    assert np.hypot(*(run.truth[-1, :2] - trajectory.path.pose[-1, :2])) <= 0.005 + 1e-9  # stopped at the end


def test_a_car_never_asks_a_curvature_beyond_its_steering_even_with_slip():
    car = load_robot("ackermann")
    trajectory = plan_trajectory(car, figure8(6.0, heading="tangent"), LIMITS)
    controller = PurePursuit(car, trajectory, rate=50)
    run = track(car, trajectory, controller, rate=50, noise=noise_profile("typical"), rng=5, settle=2.0)
    moving = np.abs(run.command[:, 0]) > 0
    curvature = np.abs(run.command[moving, 2] / run.command[moving, 0])
    assert np.max(curvature) <= controller.max_curvature * (1 + 1e-9)
    assert np.all(run.command[:, 1] == 0.0)  # never sideways
    assert tracking_errors(run, trajectory)["max_error_m"] < 0.05


def test_the_speed_follows_the_path_s_timing_at_the_point_reached():
    robot = load_robot("diff-drive")
    trajectory = plan_trajectory(robot, polyline([(0.0, 0.0), (2.0, 0.0)], heading="tangent"), LIMITS)
    run = track(robot, trajectory, PurePursuit(robot, trajectory, rate=50), rate=50, settle=2.0)
    # along a line the truth is where the reference's speed is: v(s) of the timing at the truth's s
    s_truth = run.truth[:, 0]
    speed_at = np.interp(s_truth, trajectory.path.s, trajectory.timing.sdot)
    ahead = (s_truth > 0.05) & (s_truth < 1.95)
    assert run.command[ahead, 0] == pytest.approx(speed_at[ahead], abs=0.02 + 12.0 * 0.05 / 50)
    assert tracking_errors(run, trajectory)["max_error_m"] < 1e-9


@pytest.mark.parametrize(
    ("name", "path", "message"),
    [
        ("omni4", circle(1.0, heading="fixed"), r"its heading is not its direction of travel"),
        ("tomasi-omni3", parse_path("figure8 1"), r"its heading is not its direction of travel"),
    ],
)
def test_a_path_not_along_its_tangent_is_refused(name, path, message):
    robot = load_robot(name)
    trajectory = plan_trajectory(robot, path, LIMITS)
    with pytest.raises(InputError, match=message) as info:
        PurePursuit(robot, trajectory, rate=50)
    assert "\n" not in str(info.value)


def test_a_car_is_refused_a_path_tighter_than_its_turning_radius():
    with pytest.raises(InputError, match=r"robot 'ackermann' cannot drive path 'circle 1'.*steering limits"):
        plan_trajectory(load_robot("ackermann"), circle(1.0, heading="tangent"), LIMITS)
