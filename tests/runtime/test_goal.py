"""Driving to a goal: every layout reaches it along a path its wheels can make.

Checks are geometric (distance to the goal, distance of the path from the straight segment,
no command refused by the runtime's filter, which refuses what the wheels cannot make), never
values taken from the seeker itself.
"""

import math

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.io.robot_file import load_robot
from omnikin.runtime.goal import GoalSeeker, strategy_for, tightest_curvature
from omnikin.viewer.live import LiveRobot

DT = 0.02


def run_to(name, goal, seconds=120.0):
    live = LiveRobot(load_robot(name))
    live.go_to(goal)
    path = []
    for k in range(int(seconds / DT)):
        s, _ = live.step(k * DT)
        path.append(s.truth)
        if k > 1 and live.seeker is None:
            break
    return live, np.array(path)


def distance_from_segment(points, a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    t = np.clip(((points - a) @ d) / (d @ d), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * d), axis=1)


@pytest.mark.parametrize(
    "name, expected",
    [
        ("tomasi-omni3", "straight"),
        ("mecanum4", "straight"),
        ("xr4000", "straight"),
        ("villasenor-omni3", "straight"),
        ("diff-drive", "turn-drive-turn"),
        ("ackermann", "arc-line"),
    ],
)
def test_each_layout_takes_the_path_its_wheels_allow(name, expected):
    assert strategy_for(load_robot(name)) == expected


@pytest.mark.parametrize("name", ["tomasi-omni3", "mecanum4", "omni4", "xr4000", "synchro"])
@pytest.mark.parametrize("goal", [(1.0, 0.5, math.pi / 2), (-0.6, -0.3, -2.5), (0.0, 0.4, 0.0)])
def test_a_holonomic_robot_drives_straight_to_the_goal_and_ends_at_its_heading(name, goal):
    live, path = run_to(name, goal)
    assert live.arrived is not None and math.dist(live.arrived[:2], goal[:2]) < 0.003  # the odometry at arrival
    end = path[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) < 0.0015
    assert abs(math.remainder(end[2] - goal[2], 2 * math.pi)) < math.radians(0.6)
    assert distance_from_segment(path[:, :2], (0, 0), goal[:2]).max() < 3e-3  # 0.3 % of the way
    assert live.runtime.filter.stats.rejected == 0


@pytest.mark.parametrize("goal", [(1.0, 0.5, math.pi / 2), (-0.5, 0.1, 0.0), (0.3, -0.8, math.pi)])
def test_a_differential_drive_turns_drives_straight_and_turns(goal):
    live, path = run_to("diff-drive", goal)
    assert live.arrived is not None and math.dist(live.arrived[:2], goal[:2]) < 0.003  # the odometry at arrival
    end = path[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) < 0.003
    assert abs(math.remainder(end[2] - goal[2], 2 * math.pi)) < math.radians(0.6)
    assert distance_from_segment(path[:, :2], (0, 0), goal[:2]).max() < 5e-3
    assert live.runtime.filter.stats.rejected == 0 and live.runtime.filter.stats.projected == 0


@pytest.mark.parametrize("goal", [(2.0, 1.0, 0.0), (0.0, 0.5, 0.0), (-1.0, 0.2, 0.0), (0.3, -0.1, 0.0)])
def test_a_car_reaches_the_goal_on_arcs_its_steering_allows_even_inside_its_turning_circle(goal):
    robot = load_robot("ackermann")
    radius = 1.0 / tightest_curvature(robot)
    live, path = run_to("ackermann", goal)
    assert live.arrived is not None and math.dist(live.arrived[:2], goal[:2]) < 0.003  # the odometry at arrival
    end = path[-1]
    assert math.hypot(end[0] - goal[0], end[1] - goal[1]) < 0.002
    assert live.runtime.filter.stats.rejected == 0  # no command needed steering beyond the limits
    heading_change = np.abs(np.diff(np.unwrap(path[:, 2])))
    step = np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1)
    moving = step > 1e-6
    assert np.all(heading_change[moving] <= step[moving] / radius * 1.001 + 1e-12)  # never tighter than R
    assert not GoalSeeker(robot, goal).controls_heading


def test_a_goal_that_is_not_three_finite_numbers_is_refused():
    robot = load_robot("tomasi-omni3")
    for goal in [(1.0, float("nan"), 0.0), (1.0, 2.0)]:
        with pytest.raises(InputError, match="a goal is three finite numbers"):
            GoalSeeker(robot, goal)


def test_a_key_takes_over_from_the_goal():
    live = LiveRobot(load_robot("tomasi-omni3"))
    live.go_to((2.0, 0.0, 0.0))
    for k in range(20):
        live.step(k * DT)
    live.key({"type": "press", "action": "left"})
    s, _ = live.step(20 * DT)
    assert live.seeker is None and s.target == (0.0, live.teleop.speed, 0.0)
