"""Replay tracks: the pose, twist and wheels at any time of a recorded run, checked against
closed forms (a circle driven at a constant twist, a straight line, a differential drive's
wheel speeds), not against the interpolation itself."""

import math

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.io.robot_file import load_robot
from omnikin.physics.description import describe
from omnikin.viewer.replay import JointSeries, PoseSeries, Track, TrackReplay

V, W = 0.3, 0.4  # m/s, rad/s: a circle of radius 0.75 m


def circle(t):
    """The pose after ``t`` s at the body twist (V, 0, W) from the origin (closed form)."""
    t = np.asarray(t, dtype=float)
    return np.column_stack([V / W * np.sin(W * t), V / W * (1 - np.cos(W * t)), W * t])


def wrapped(theta):
    return (theta + math.pi) % (2 * math.pi) - math.pi


def test_at_a_sample_time_the_pose_is_the_sample():
    t = np.array([0.0, 0.7, 1.1, 2.9, 3.0])
    poses = np.array([[0.0, 0.0, 0.0], [1.0, -0.5, 2.0], [1.2, 0.3, -3.0], [-4.0, 2.0, 0.1], [-4.0, 2.1, 0.2]])
    series = PoseSeries(t, poses)
    for k in range(len(t)):
        p = series.at(t[k])
        assert p[:2] == pytest.approx(poses[k, :2], abs=1e-12)
        assert wrapped(p[2] - poses[k, 2]) == pytest.approx(0.0, abs=1e-12)


def test_between_samples_of_a_circle_the_pose_lies_on_the_circle():
    """Samples 1 s apart on the circle: the constant-twist interpolation between them is the
    circle itself (an SE(2) geodesic), where a linear interpolation of x, y cuts the chord."""
    t = np.arange(0.0, 8.5, 1.0)
    series = PoseSeries(t, circle(t))
    between = np.array([0.25, 0.5, 3.33, 7.9])
    for time, exact in zip(between, circle(between), strict=True):
        p = series.at(time)
        assert p[:2] == pytest.approx(exact[:2], abs=1e-12)
        assert wrapped(p[2] - exact[2]) == pytest.approx(0.0, abs=1e-12)
        assert series.twist(time) == pytest.approx([V, 0.0, W], abs=1e-12)
    chord_middle = (circle([0.0])[0, :2] + circle([1.0])[0, :2]) / 2
    assert np.linalg.norm(series.at(0.5)[:2] - chord_middle) > 1e-3  # not the straight chord


def test_a_straight_run_interpolates_linearly_and_rests_outside_its_times():
    t = np.array([1.0, 3.0])
    poses = np.array([[0.0, 0.0, 0.5], [2.0, -1.0, 0.5]])
    series = PoseSeries(t, poses)
    assert series.at(1.5) == pytest.approx([0.5, -0.25, 0.5], abs=1e-12)
    assert series.at(0.0) == pytest.approx(poses[0]) and series.at(9.0) == pytest.approx(poses[1])
    assert series.twist(0.0) == pytest.approx([0, 0, 0]) and series.twist(9.0) == pytest.approx([0, 0, 0])
    body = [math.cos(0.5) * 1.0 - math.sin(0.5) * 0.5, -math.sin(0.5) * 1.0 - math.cos(0.5) * 0.5, 0.0]
    assert series.twist(2.0) == pytest.approx(body, abs=1e-12)  # world (1, -0.5) m/s in the body frame


@pytest.mark.parametrize(
    "t, poses",
    [
        ([0.0], [[0, 0, 0]]),
        ([0.0, 1.0, 1.0], [[0, 0, 0]] * 3),
        ([0.0, 2.0, 1.0], [[0, 0, 0]] * 3),
        ([0.0, math.nan], [[0, 0, 0]] * 2),
        ([0.0, 1.0], [[0, 0, 0], [math.inf, 0, 0]]),
    ],
)
def test_a_pose_series_refuses_too_few_non_increasing_or_non_finite_samples(t, poses):
    with pytest.raises(InputError):
        PoseSeries(np.array(t), np.array(poses, dtype=float))


def test_a_differential_drive_replay_turns_its_wheels_as_the_closed_form_says():
    """diff-drive: wheels at y = +-0.165 m, radius 0.0825 m; on the circle (V, 0, W) the left
    wheel turns at (V - 0.165 W) / 0.0825 rad/s and the right at (V + 0.165 W) / 0.0825, the
    castor not at all; the angles are those speeds times the time."""
    robot = load_robot("diff-drive")
    description = describe(robot)
    t = np.arange(0.0, 5.5, 0.5)
    track = Track("circle", PoseSeries(t, circle(t)), PoseSeries(t, circle(t) * 0.9))
    replay = TrackReplay(robot, description, track)
    names = [w.name for w in description.wheels]
    left, right = (V - 0.165 * W) / 0.0825, (V + 0.165 * W) / 0.0825
    for time in (0.0, 0.3, 2.5, 4.75):
        s = replay.snapshot(time)
        assert s.wheel_speeds[names.index("left")] == pytest.approx(left, rel=1e-9)
        assert s.wheel_speeds[names.index("right")] == pytest.approx(right, rel=1e-9)
        assert s.wheel_speeds[names.index("castor")] == 0.0
        assert s.wheel_angles[names.index("left")] == pytest.approx(left * time, rel=1e-9, abs=1e-12)
        assert s.wheel_angles[names.index("right")] == pytest.approx(right * time, rel=1e-9, abs=1e-12)
        assert s.truth[:2] == pytest.approx(tuple(circle([time])[0, :2]), abs=1e-12)
        assert s.twist == pytest.approx((V, 0.0, W), abs=1e-12)
    end = replay.snapshot(99.0)
    assert end.twist == (0.0, 0.0, 0.0) and not np.any(end.wheel_speeds)
    assert end.wheel_angles[names.index("left")] == pytest.approx(left * 5.0, rel=1e-9)
    assert end.odometry[:2] == pytest.approx(tuple(0.9 * circle([5.0])[0, :2]), abs=1e-12)


def test_measured_joints_replace_the_kinematic_wheels_and_steering():
    """A track with joint states: angles and steering interpolated linearly in time, speeds
    the finite difference of the interval."""
    robot = load_robot("diff-drive")
    description = describe(robot)
    t = np.array([0.0, 1.0, 2.0])
    line = np.array([[0.0, 0, 0], [0.3, 0, 0], [0.6, 0, 0]])
    joints = JointSeries(np.array([0.0, 2.0]), ("left", "right"), np.array([[0.0, 1.0], [4.0, -3.0]]))
    replay = TrackReplay(robot, description, Track("line", PoseSeries(t, line), PoseSeries(t, line), joints))
    names = [w.name for w in description.wheels]
    s = replay.snapshot(0.5)
    assert s.wheel_angles[names.index("left")] == pytest.approx(1.0)
    assert s.wheel_angles[names.index("right")] == pytest.approx(0.0)
    assert s.wheel_speeds[names.index("left")] == pytest.approx(2.0)
    assert s.wheel_speeds[names.index("right")] == pytest.approx(-2.0)


def test_an_ackermann_replay_steers_its_front_wheels_along_their_hubs_and_holds_them_at_rest():
    """ackermann: front wheels steer at (0.6, +-0.25) m; on the circle (0.3 m/s, 0, 0.2 rad/s)
    each points along its hub's velocity (0.3 -+ 0.25 * 0.2, 0.6 * 0.2): atan2(0.12, 0.25) and
    atan2(0.12, 0.35); a last interval at rest keeps those angles."""
    robot = load_robot("ackermann")
    description = describe(robot)
    v, w = 0.3, 0.2
    t = np.arange(0.0, 3.0, 0.5)
    poses = np.column_stack([v / w * np.sin(w * t), v / w * (1 - np.cos(w * t)), w * t])
    t = np.append(t, t[-1] + 1.0)
    poses = np.vstack([poses, poses[-1]])  # then a second at rest
    replay = TrackReplay(robot, description, Track("arc", PoseSeries(t, poses), PoseSeries(t, poses)))
    names = [w.name for w in description.wheels]
    for time in (0.2, 1.7, 3.0):  # 3.0 s: in the interval at rest
        s = replay.snapshot(time)
        assert s.steer[names.index("front_left")] == pytest.approx(math.atan2(0.12, 0.25), abs=1e-9)
        assert s.steer[names.index("front_right")] == pytest.approx(math.atan2(0.12, 0.35), abs=1e-9)
        assert all(math.isnan(s.steer[i]) for i, n in enumerate(names) if n not in robot.steer_names)


def test_rollers_and_castors_move_as_the_recorded_motion_makes_them():
    """tomasi-omni3 translating at vx = 0.2 m/s: wheel w_i (drive direction a_i) has its hub
    moving across its drive by n . v = -sin(a_i) vx (n = (-sin a, cos a)), which its rollers
    (radius b at the contact, gamma = 0) take up by spinning at -(n . v) / b = sin(a_i) vx / b;
    a roller angle is that rate times the time. diff-drive driving straight at 0.3 m/s: its
    castor (trail 0.03 m, aligned) keeps its swivel at 0 and rolls v t / 0.03 rad."""
    vx = 0.2
    t = np.arange(0.0, 2.01, 0.5)
    poses = np.column_stack([vx * t, 0 * t, 0 * t])
    robot = load_robot("tomasi-omni3")
    description = describe(robot)
    replay = TrackReplay(robot, description, Track("x", PoseSeries(t, poses), PoseSeries(t, poses)))
    for time in (0.25, 1.0, 1.9):
        s = replay.snapshot(time)
        for i, wheel in enumerate(description.wheels):
            rate = math.sin(wheel.drive) * vx / wheel.rollers.radius
            assert s.roller_speeds[i] == pytest.approx(rate, rel=1e-9, abs=1e-12)
            assert s.roller_angles[i] == pytest.approx(rate * time, rel=1e-9, abs=1e-12)
    v = 0.3
    poses = np.column_stack([v * t, 0 * t, 0 * t])
    robot = load_robot("diff-drive")
    description = describe(robot)
    names = [w.name for w in description.wheels]
    replay = TrackReplay(robot, description, Track("x", PoseSeries(t, poses), PoseSeries(t, poses)))
    s = replay.snapshot(1.3)
    assert s.steer[names.index("castor")] == pytest.approx(0.0, abs=1e-12)
    assert s.wheel_angles[names.index("castor")] == pytest.approx(v * 1.3 / 0.03, rel=1e-9)
