"""Following a path that arrives while the robot runs (omnikin.control.follower), and timing a path
within the body's limits as a runtime's command filter applies them (time_optimal's body rows).

Closed forms: a straight line from rest to rest under a speed limit V and an acceleration limit
A takes L / V + V / A' (A' = A cos(pi / 32), the linear acceleration limit as the rows of
ACCEL_DIRECTIONS = 16 directions keep it, exact along one of them); on a circle of radius R
driven along its tangent the turn rate v / R bounds the speed, and held at a fixed heading the
body-frame velocity turns at v / R, an acceleration v^2 / R that the rows bound by A' where it
points along one of their directions and by A between them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.control import WheelLimits, circle, plan_trajectory, polyline, spline
from omnikin.control.follower import MARGIN, MAX_WAYPOINTS, PathFollower, plan_follow
from omnikin.errors import InputError
from omnikin.motion.limits import MotionLimits
from omnikin.runtime.base import BaseRuntime
from omnikin.simulation.backend import SimBackend
from support.kinematics import distance_to_polyline

V, W, A, ALPHA = 0.3, 1.0, 0.5, 2.0  # the node's default body limits [m/s, rad/s, m/s^2, rad/s^2]
BODY = MotionLimits(linear=V, angular=W, linear_accel=A, angular_accel=ALPHA)
FREE = WheelLimits(speed=math.inf, accel=math.inf)  # the body's limits alone
A_ROWS = A * math.cos(math.pi / 32)


def body_motion(trajectory, dt=1e-3):
    """Body-frame velocity ``(n, 2)``, turn rate ``(n,)`` and body-frame acceleration ``(n - 1, 2)``
    of the reference, by finite differences of its poses ``dt`` apart."""
    t = np.arange(0.0, trajectory.duration, dt)
    pose = trajectory.at(t)[0]
    world = np.diff(pose[:, :2], axis=0) / dt
    mid = pose[:-1, 2] + np.diff(pose[:, 2]) / 2
    c, s = np.cos(mid), np.sin(mid)
    body = np.column_stack((c * world[:, 0] + s * world[:, 1], -s * world[:, 0] + c * world[:, 1]))
    return body, np.diff(pose[:, 2]) / dt, np.diff(body, axis=0) / dt


def test_a_straight_line_takes_the_trapezoid_of_the_body_s_speed_and_acceleration():
    robot = load_robot("omni4")
    trajectory = plan_trajectory(robot, polyline([[0.0, 0.0], [2.0, 0.0]], heading="fixed"), FREE, BODY)
    assert trajectory.duration == pytest.approx(2.0 / V + V / A_ROWS, rel=1e-4)
    assert trajectory.timing.sdot.max() == pytest.approx(V, rel=1e-9)


def middle_speed(trajectory) -> np.ndarray:
    """The body's speed [m/s] over the middle half of the trajectory's time."""
    velocity, _, _ = body_motion(trajectory, dt=0.01)
    speed = np.hypot(*velocity.T)
    return speed[len(speed) // 4 : 3 * len(speed) // 4]


@pytest.mark.parametrize("radius, speed", [(0.2, W * 0.2), (1.0, V)])
def test_along_a_circle_s_tangent_the_turn_rate_or_the_speed_limit_binds(radius, speed):
    trajectory = plan_trajectory(load_robot("omni4"), circle(radius, heading="tangent"), FREE, BODY)
    assert middle_speed(trajectory) == pytest.approx(speed, rel=1e-4)


def test_at_a_fixed_heading_on_a_tight_circle_the_acceleration_rows_bind_the_speed():
    radius = 0.1  # sqrt(A R) = 0.224 m/s < V
    trajectory = plan_trajectory(load_robot("omni4"), circle(radius, heading="fixed"), FREE, BODY)
    speed = middle_speed(trajectory)
    # (the rows' finite differences over the 2 mm samples of a 0.1 m radius: 2e-3)
    assert speed.min() == pytest.approx(math.sqrt(A_ROWS * radius), rel=2e-3)
    assert speed.max() <= math.sqrt(A * radius) * (1 + 1e-3)


@pytest.mark.parametrize(
    ("name", "heading"), [("omni4", "fixed"), ("tomasi-omni3", "tangent"), ("diff-drive", "tangent")]
)
def test_a_trajectory_timed_within_the_body_limits_never_leaves_them(name, heading):
    # a smooth path (a corner cut by an arc makes the turn rate step where line meets arc)
    path = spline([[0, 0], [1, 0], [1, 1], [0, 1.5]], heading=heading)
    trajectory = plan_trajectory(load_robot(name), path, WheelLimits(speed=12.0, accel=40.0), BODY)
    dt = 0.01
    velocity, turn, accel = body_motion(trajectory, dt)
    assert np.hypot(*velocity.T).max() <= V * (1 + 1e-3)
    assert np.abs(turn).max() <= W * (1 + 1e-3)
    assert np.hypot(*accel.T).max() <= A * (1 + 1e-3)
    assert np.abs(np.diff(turn) / dt).max() <= ALPHA * (1 + 1e-2)


def test_nothing_limiting_the_speed_is_refused_in_one_line():
    with pytest.raises(InputError, match=r"path 'polyline': nothing limits the speed at s = "):
        plan_trajectory(load_robot("omni4"), polyline([[0, 0], [1, 0]]), FREE)


def drive(robot, follower, plan, seconds, rate=50.0, runtime=None):
    """The runtime of ``robot`` (exact kinematic back-end, the body limits ``BODY``) driven by
    ``follower`` at ``rate`` for ``seconds`` of simulated time from ``plan``; the true poses."""
    backend = SimBackend(robot)
    runtime = runtime or BaseRuntime(robot, backend, limits=BODY, cmd_vel_timeout=0.0)
    follower.begin(plan, 0.0)
    truth = []
    for k in range(int(seconds * rate) + 1):
        t = k / rate
        state = runtime.sense(t)
        twist = follower.command(t, runtime.pose)
        runtime.command(np.zeros(3) if twist is None else twist, t)
        runtime.act(t, state)
        truth.append(backend.truth.copy())
    return np.array(truth)


def test_a_path_beginning_away_from_the_robot_is_driven_from_the_robot_to_its_end():
    robot = load_robot("omni4")
    plan = plan_follow(robot, [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], (0.0, 0.0, 0.0), limits=FREE, body=BODY, smooth=False)
    follower = PathFollower()
    truth = drive(robot, follower, plan, plan.trajectory.duration + 2.0)
    assert follower.state == "done"
    assert truth[-1] == pytest.approx([1.0, 1.0, 0.0], abs=1e-6)
    # on the two segments: robot to the first waypoint, then to the second
    gap = distance_to_polyline(truth[:, :2], [(0, 0), (1, 0), (1, 1)])
    assert gap.max() < 1e-4
    # stopped at the corner; timed within MARGIN of the limits
    assert plan.trajectory.duration == pytest.approx(2 * (1.0 / (MARGIN * V) + V / (A_ROWS)), rel=1e-3)
    values = dict(follower.values())
    assert values["path_state"] == "done" and values["path_waypoints"] == "2"
    assert float(values["max_distance_to_path_m"]) < 1e-4
    assert follower.summary().startswith("done path 'plan' (2 m in")


def test_a_differential_drive_follows_the_tangent_whatever_headings_the_waypoints_give():
    robot = load_robot("diff-drive")
    waypoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [1.5, 0.5, -2.0], [1.5, 1.5, 0.3]]
    plan = plan_follow(robot, waypoints, (0.0, 0.0, 0.0), limits=WheelLimits(speed=12.0, accel=40.0), body=BODY)
    path = plan.trajectory.path
    tangent = np.arctan2(path.d1[:, 1], path.d1[:, 0])
    assert np.abs(np.angle(np.exp(1j * (path.pose[:, 2] - tangent)))).max() < 1e-5
    assert plan.controller.name == "mpc"


def test_waypoints_closer_than_a_millimetre_are_one_with_the_later_heading():
    robot = load_robot("omni4")
    waypoints = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0005, 0.5], [2.0, 0.0, 0.5]]
    plan = plan_follow(robot, waypoints, (0.0, 0.0, 0.0), limits=FREE, body=BODY, smooth=False)
    path = plan.trajectory.path
    corner = np.argmin(np.hypot(path.pose[:, 0] - 1.0, path.pose[:, 1]))
    assert path.pose[corner, 2] == pytest.approx(0.5, abs=1e-3)  # the heading of the merged point
    assert path.pose[-1, :2] == pytest.approx([2.0, 0.0])


def test_stop_and_refuse_end_the_following_and_say_why():
    robot = load_robot("omni4")
    follower = PathFollower()
    assert not follower.stop("cmd_vel") and follower.state == "idle" and follower.summary() == "no path yet"
    plan = plan_follow(robot, [[1.0, 0.0]], (0.0, 0.0, 0.0), limits=FREE, body=BODY)
    follower.begin(plan, 10.0)
    assert follower.command(10.0, (0.0, 0.0, 0.0)) is not None
    assert follower.stop("a cmd_vel arrived") and follower.state == "stopped"
    assert follower.command(10.1, (0.0, 0.0, 0.0)) is None
    assert dict(follower.values())["path_note"] == "a cmd_vel arrived"
    follower.begin(plan, 20.0)
    assert follower.refuse("path 'plan': waypoint 3 is not finite")
    assert follower.state == "refused" and follower.command(20.1, (0, 0, 0)) is None
    assert follower.summary() == "path refused: path 'plan': waypoint 3 is not finite"


@pytest.mark.parametrize(
    ("waypoints", "message"),
    [
        ([[0.0, 0.0], [0.0005, 0.0]], r"does not go anywhere \(every waypoint within 1 mm of the robot\)"),
        ([[0.0, 0.0], [1.0, math.nan]], r"waypoint 1 is not finite"),
        ([[0.0, 0.0], [1e300, 0.0]], r"1e\+300 m of waypoints, longer than 200 m: send it in parts"),
        ([[0.0, 0.0], [300.0, 0.0]], r"300 m of waypoints, longer than 200 m: send it in parts"),
        ([], r"no waypoints|shape"),
        ([[0.0, 0.0, 0.0, 0.0]], r"rows of \(x, y\) or \(x, y, theta\)"),
        ("xy", r"waypoints|shape"),
    ],
)
def test_paths_that_cannot_be_followed_are_one_line_errors(waypoints, message):
    with pytest.raises(InputError, match=message) as caught:
        plan_follow(load_robot("omni4"), waypoints, (0.0, 0.0, 0.0), limits=FREE, body=BODY, name="plan")
    assert "\n" not in str(caught.value) and "plan" in str(caught.value)


def test_too_many_waypoints_are_refused_before_any_work():
    many = np.zeros((MAX_WAYPOINTS + 1, 2))
    with pytest.raises(InputError, match=rf"{MAX_WAYPOINTS + 1} waypoints, more than {MAX_WAYPOINTS}"):
        plan_follow(load_robot("omni4"), many, (0.0, 0.0, 0.0), limits=FREE, body=BODY)


@pytest.mark.parametrize("target", [(0.0, 1.0), (-1.0, 0.0)])
def test_a_robot_with_fixed_wheels_is_refused_a_path_that_leaves_it_sideways_or_backwards(target):
    with pytest.raises(InputError, match=r"leaves the robot at (90|180) deg, but robot 'diff-drive' faces 0 deg"):
        plan_follow(load_robot("diff-drive"), [target], (0.0, 0.0, 0.0), limits=FREE, body=BODY, smooth=False)


def test_a_smooth_path_leaves_a_robot_with_fixed_wheels_along_its_heading():
    plan = plan_follow(load_robot("diff-drive"), [(1.0, 1.0)], (0.0, 0.0, 0.3), limits=FREE, body=BODY)
    assert plan.trajectory.path.pose[0, 2] == pytest.approx(0.3, abs=1e-3)


@pytest.mark.parametrize(
    ("robot", "controller", "message"),
    [
        ("diff-drive", "feedback", "cannot move sideways"),
        ("synchro", "mpc", "steers its wheels"),
        ("omni4", "bogus", "controller must be one of feedback, mpc, pursuit"),
    ],
)
def test_a_controller_the_layout_cannot_take_is_refused_before_any_path(robot, controller, message):
    from omnikin.control.controllers import check_controller_for

    with pytest.raises(InputError, match=message):
        check_controller_for(controller, load_robot(robot))
    assert check_controller_for(None, load_robot(robot)) in ("feedback", "mpc", "pursuit")


def test_long_straight_stretches_are_planned_without_a_floating_point_warning():
    # (the command line turns numpy's warnings into errors: a row that is zero along a straight
    # stretch must not overflow the speed ceiling)
    line = np.column_stack((np.linspace(0.0, 10.0, 1001), np.full(1001, -0.2)))
    with np.errstate(divide="raise", over="raise", invalid="raise"):  # (numpy's warnings; underflow is silent)
        plan = plan_follow(load_robot("omni4"), line, (0.0, 0.0, 0.0), limits=FREE, body=BODY, heading="tangent")
    assert plan.trajectory.timing.sdot.max() == pytest.approx(MARGIN * V, rel=1e-3)


def test_the_plan_worker_plans_the_latest_request_and_drops_the_ones_it_superseded():
    import threading

    from omnikin.control.follower import PlanWorker
    from support.browser import wait_until

    gate = threading.Event()
    seen = []

    def job(generation, value):
        seen.append(value)
        if value == "first":
            gate.wait(10)
        if value == "bad":
            raise InputError("refused")
        return value

    worker = PlanWorker(job)
    worker.request(value="first")
    wait_until(lambda: seen == ["first"], "the first request taken")
    worker.request(value="second")
    worker.request(value="third")  # supersedes the second before it is taken
    gate.set()
    wait_until(lambda: not worker.busy, "the worker idle")
    assert worker.take() == "third" and worker.take() is None
    assert seen == ["first", "third"]
    worker.request(value="bad")
    wait_until(lambda: not worker.busy, "the worker idle")
    assert str(worker.take()) == "refused"
    worker.request(value="first")
    wait_until(lambda: seen[-1] == "first", "taken")
    assert worker.cancel()
    gate.set()
    wait_until(lambda: not worker.busy, "the worker idle")
    assert worker.take() is None  # cancelled: its result dropped
