"""Odometry: exact integration, streaming vs batch, counters, and every bad input."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnikin import Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles, load_robot, se2
from omnikin.errors import OmnikinError
from omnikin.odometry.integration import integrate
from support.kinematics import constant_twist_pose

RAD_PER_TICK = 2 * math.pi / 600  # tomasi-omni3 encoders


def tomasi_angles(twist, t):
    """Wheel angles of tomasi-omni3 under a constant twist, from the closed-form omni row."""
    dist, r = 0.113, 0.04125
    rows = np.array([[-math.sin(b), math.cos(b), dist] for b in np.radians([0, 120, 240])]) / r
    return np.outer(t, rows @ twist)


# --- integration kernel -------------------------------------------------------------------------------
@given(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)), st.integers(1, 50))
def test_exact_integration_composes_for_constant_twist(xi, n):
    """n equal increments reach exp(n xi): the group property exp(a) exp(a) = exp(2a)."""
    poses = integrate(np.tile(xi, (n, 1)))
    expected = se2.exp(n * np.array(xi))
    np.testing.assert_allclose(poses[-1, :2], expected[:2], atol=1e-9 * n)
    assert se2.wrap_angle(poses[-1, 2] - expected[2]) == pytest.approx(0.0, abs=1e-9 * n)


@pytest.mark.parametrize("rate", [1.0, 10.0, 100.0])
def test_exact_odometry_follows_the_closed_form_circle(tomasi, rate):
    """Any sample rate: exact integration of constant wheel speeds lies on the circle."""
    twist = np.array([0.2, 0.1, 0.2])
    t = np.arange(0, 10.0 + 1e-9, 1.0 / rate)
    res = batch_odometry_from_angles(tomasi, t, tomasi_angles(twist, t))
    expected = np.array([constant_twist_pose(twist, tk) for tk in t])
    np.testing.assert_allclose(res.poses[:, :2], expected[:, :2], atol=1e-12)
    np.testing.assert_allclose(np.cos(res.poses[:, 2] - expected[:, 2]), 1.0, atol=1e-12)
    np.testing.assert_allclose(res.twists, np.tile(twist, (len(t) - 1, 1)), atol=1e-12)


def test_euler_and_midpoint_are_approximations(tomasi):
    """Constant twist from the origin: the midpoint polyline is the exact one scaled by
    1/sinc(w dt/2), the Euler polyline is that rotated by -w dt/2 about the start. So after a
    quarter of a 1 m circle (|p| = sqrt 2) the errors are |p| (w dt/2) and |p| (w dt)^2/24."""
    twist = np.array([0.2, 0.0, 0.2])
    dt = 0.1
    t = np.arange(0, math.pi / 2 / 0.2 + 1e-9, dt)
    ang = tomasi_angles(twist, t)
    end = constant_twist_pose(twist, t[-1])
    err = {
        m: np.hypot(*(batch_odometry_from_angles(tomasi, t, ang, method=m).poses[-1, :2] - end[:2]))
        for m in ("exact", "midpoint", "euler")
    }
    p, x = math.hypot(end[0], end[1]), 0.2 * dt
    assert err["exact"] < 1e-13
    assert err["euler"] == pytest.approx(p * x / 2, rel=0.01)
    assert err["midpoint"] == pytest.approx(p * x * x / 24, rel=0.01)


def test_batch_broadcasts_over_trials(tomasi):
    t = np.linspace(0, 2, 41)
    twists = np.array([[0.2, 0, 0.1], [0, 0.3, -0.2], [0.1, 0.1, 0.0]])
    angles = np.stack([tomasi_angles(tw, t) for tw in twists])  # (3, 41, 3)
    res = batch_odometry_from_angles(tomasi, t, angles)
    assert res.poses.shape == (3, 41, 3)
    for k, tw in enumerate(twists):
        np.testing.assert_allclose(res.poses[k, -1, :2], constant_twist_pose(tw, 2.0)[:2], atol=1e-12)


# --- ticks, counters, streaming ---------------------------------------------------------------------------
def quantised_log(twist, t):
    return np.round(tomasi_angles(twist, t) / RAD_PER_TICK).astype(np.int64)


@pytest.mark.parametrize("method", ["exact", "midpoint", "euler"])
def test_streaming_equals_batch(tomasi, method):
    t = np.arange(0, 5, 0.01)
    ticks = quantised_log(np.array([0.3, -0.1, 0.4]), t)
    batch = batch_odometry(tomasi, t, ticks, method=method)
    odo = Odometry(tomasi, method=method)
    for k in range(len(t)):
        pose = odo.update(float(t[k]), [int(v) for v in ticks[k]])
    np.testing.assert_allclose(pose, batch.poses[-1], atol=1e-10)
    np.testing.assert_allclose(odo.twist, batch.twists[-1], atol=1e-9)


def test_ticks_within_quantisation_of_truth(tomasi):
    twist = np.array([0.2, 0.0, 0.2])
    t = np.arange(0, 5, 0.01)
    res = batch_odometry(tomasi, t, quantised_log(twist, t))
    # half a tick on each wheel -> at most |F| * 0.5 tick of displacement
    f = np.abs(tomasi.fk_matrix()) @ np.full(3, 0.5 * RAD_PER_TICK)
    err = res.poses[-1] - constant_twist_pose(twist, t[-1])
    assert abs(err[2]) <= f[2] + 1e-12
    assert np.hypot(err[0], err[1]) <= 2 * math.hypot(f[0], f[1]) + 0.5 * f[2]


@pytest.mark.parametrize("bits", [8, 16, 32])
def test_counter_wrap_around(tomasi, bits):
    t = np.arange(0, 3, 0.01)
    ticks = quantised_log(np.array([0.5, 0.2, 1.0]), t) + 2**bits - 300  # starts near the top
    wrapped = ticks % (2**bits)
    ref = batch_odometry(tomasi, t, ticks)
    res = batch_odometry(tomasi, t, wrapped, counter_bits=bits)
    np.testing.assert_allclose(res.poses, ref.poses, atol=1e-12)
    odo = Odometry(tomasi, counter_bits=bits)
    for k in range(len(t)):
        odo.update(float(t[k]), [int(v) for v in wrapped[k]])
    np.testing.assert_allclose(odo.pose, ref.poses[-1], atol=1e-10)


def test_first_sample_is_the_zero_and_reset(tomasi):
    odo = Odometry(tomasi, start=(1.0, 2.0, 0.5))
    assert odo.update(0.0, [1000, -5000, 77]) == (1.0, 2.0, 0.5)
    odo.update(0.1, [1000, -5000, 77])
    assert odo.pose == (1.0, 2.0, 0.5)
    odo.reset()
    assert odo.pose == (0.0, 0.0, 0.0) and odo.t is None


def test_update_angles_matches_ticks(tomasi):
    a, b = Odometry(tomasi), Odometry(tomasi)
    for k in range(5):
        ticks = [10 * k, -7 * k, 3 * k]
        pa = a.update(0.1 * k, ticks)
        pb = b.update_angles(0.1 * k, [v * RAD_PER_TICK for v in ticks])
    np.testing.assert_allclose(pa, pb, atol=1e-12)


def test_redundant_layout_reports_residual():
    robot = load_robot("omni4")
    odo = Odometry(robot)
    odo.update(0.0, [0, 0, 0, 0])
    odo.update(0.1, [100, 0, 0, 0])  # one wheel slips
    rad = 2 * math.pi / 2048 * 100
    n = np.array([1, -1, 1, -1]) / 2.0  # left null space of J (see kinematics/test_robot.py)
    np.testing.assert_allclose(odo.residual, n * n[0] * rad / 0.1, atol=1e-9)


def test_steerable_odometry_ackermann_circle():
    """Rear wheels encoded, steering measured: the closed-form circle of radius R = v / w."""
    robot = load_robot("ackermann")
    v, w = 1.0, 0.4
    t = np.arange(0, 5, 0.01)
    res_ik = robot.ik([v, 0, w])
    rear = res_ik.wheel_speeds[:2]
    ticks = np.outer(t, rear) / (2 * math.pi / 1024)
    steer = np.tile(res_ik.steer_angles, (len(t), 1))
    res = batch_odometry(robot, t, ticks, steer=steer)
    np.testing.assert_allclose(res.poses[-1, :2], constant_twist_pose([v, 0, w], t[-1])[:2], atol=1e-10)
    odo = Odometry(robot)
    for k in range(len(t)):
        odo.update(float(t[k]), list(ticks[k]), steer[k])
    np.testing.assert_allclose(odo.pose, res.poses[-1], atol=1e-9)


def test_synchro_needs_steering():
    robot = load_robot("synchro")
    with pytest.raises(OmnikinError, match="steering angles"):
        batch_odometry(robot, [0, 1], np.zeros((2, 3)))
    odo = Odometry(robot)
    with pytest.raises(OmnikinError, match="steering angles"):
        odo.update(0.0, [0, 0, 0])


# --- bad input -----------------------------------------------------------------------------------------------------
def test_batch_rejects_time_going_back(tomasi):
    with pytest.raises(OdometryInputError, match=r"sample 2: .*increase strictly"):
        batch_odometry(tomasi, [0.0, 0.1, 0.05], np.zeros((3, 3), int))
    with pytest.raises(OdometryInputError, match=r"sample 1: "):
        batch_odometry(tomasi, [0.0, 0.0, 0.2], np.zeros((3, 3), int))


def test_batch_names_nan_sample_and_wheel(tomasi):
    ticks = np.zeros((4, 3))
    ticks[2, 1] = np.nan
    with pytest.raises(OdometryInputError, match=r"sample 2: .*non-finite reading, wheel 'w2'"):
        batch_odometry(tomasi, [0, 1, 2, 3], ticks)
    with pytest.raises(OdometryInputError, match="sample 1: .*non-finite timestamp"):
        batch_odometry(tomasi, [0, np.nan, 2, 3], np.zeros((4, 3)))


def test_batch_wrong_wheel_count(tomasi):
    with pytest.raises(OdometryInputError, match=r"expected shape \(\.\.\., N, 3\)"):
        batch_odometry(tomasi, [0, 1], np.zeros((2, 4)))
    with pytest.raises(OdometryInputError, match="timestamps to match"):
        batch_odometry(tomasi, [0, 1, 2], np.zeros((2, 3)))


def test_batch_trial_index_in_errors(tomasi):
    t = np.array([[0, 1, 2], [0, 2, 1]], float)
    with pytest.raises(OdometryInputError, match=r"sample 2: .*\(trial \(1,\)\)"):
        batch_odometry(tomasi, t, np.zeros((2, 3, 3)))


def test_counter_range_and_ambiguous_half_jump(tomasi):
    with pytest.raises(
        OdometryInputError, match=r"sample 1: tick reading 70000 outside the range of a 16-bit counter .*, wheel 'w1'"
    ):
        batch_odometry(tomasi, [0, 1], [[0, 0, 0], [70000, 0, 0]], counter_bits=16)
    with pytest.raises(OdometryInputError, match="impossible jump"):
        batch_odometry(tomasi, [0, 1], [[0, 0, 0], [0, 128, 0]], counter_bits=8)  # exactly half: undecidable
    with pytest.raises(OdometryInputError, match="counter_bits"):
        batch_odometry(tomasi, [0, 1], np.zeros((2, 3)), counter_bits=0)


def fast_wheel_robot(tmp_path):
    from omnikin.io.robot_file import load_robot as load

    p = tmp_path / "r.yaml"
    p.write_text(
        "omnikin: 1\nname: limited\nwheels:\n"
        + "".join(
            f"  - {{name: w{i}, type: omni, distance: 0.1, angle_deg: {a}, radius: 0.05, max_speed: 10,"
            f" encoder: {{ticks_per_rev: 1000}}}}\n"
            for i, a in enumerate([0, 120, 240])
        )
    )
    return load(p)


def test_impossible_jump_from_max_speed(tmp_path):
    """10 rad/s and 1000 ticks/rev: at most ~1592 ticks/s; a 5000-tick step in 0.1 s is impossible."""
    robot = fast_wheel_robot(tmp_path)
    ok = [[0, 0, 0], [150, 0, 0]]
    batch_odometry(robot, [0, 0.1], ok)
    with pytest.raises(OdometryInputError, match=r"sample 1: impossible jump of 5000 ticks in 0.1 s, wheel .w0."):
        batch_odometry(robot, [0, 0.1], [[0, 0, 0], [5000, 0, 0]])
    odo = Odometry(robot)
    odo.update(0.0, [0, 0, 0])
    with pytest.raises(OdometryInputError, match="impossible jump of 5000 ticks in 0.1 s, wheel 'w0'"):
        odo.update(0.1, [5000, 0, 0])
    assert odo.pose == (0.0, 0.0, 0.0)  # state unchanged after the error
    odo.update(0.1, [100, 0, 0])  # and the estimator goes on


def test_streaming_errors_name_the_sample(tomasi):
    odo = Odometry(tomasi)
    with pytest.raises(OdometryInputError, match="expected 3 tick readings"):
        odo.update(0.0, [0, 0])
    odo.update(0.0, [0, 0, 0])
    odo.update(0.1, [1, 1, 1])
    with pytest.raises(OdometryInputError, match="sample 2: timestamp 0.05 goes back"):
        odo.update(0.05, [2, 2, 2])
    with pytest.raises(OdometryInputError, match="sample 2: timestamp 0.1 repeats"):
        odo.update(0.1, [2, 2, 2])
    with pytest.raises(OdometryInputError, match="non-finite tick reading nan, wheel 'w3'"):
        odo.update(0.2, [2, 2, float("nan")])
    with pytest.raises(OdometryInputError, match="non-finite timestamp"):
        odo.update(float("nan"), [2, 2, 2])
    with pytest.raises(OdometryInputError, match="expected 3 tick readings"):
        odo.update(0.2, [2, 2, 2, 2])
    with pytest.raises(OmnikinError, match="no steerable wheel"):
        odo.update(0.2, [2, 2, 2], steer=[0.0])
    assert odo.samples == 2


def test_duplicate_sample_is_skipped_with_one_warning(tomasi):
    odo = Odometry(tomasi)
    odo.update(0.0, [0, 0, 0])
    odo.update(0.1, [5, 5, 5])
    pose = odo.pose
    with pytest.warns(RuntimeWarning, match="duplicate sample"):
        odo.update(0.1, [5, 5, 5])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        odo.update(0.1, [5, 5, 5])  # warned only once
    assert odo.duplicates == 2 and odo.pose == pose


def test_odometry_needs_encoders():
    from omnikin import Robot, Wheel

    robot = Robot(
        "no-enc",
        tuple(
            Wheel(f"w{i}", "omni", 0.1 * math.cos(b), 0.1 * math.sin(b), b + math.pi / 2, 0.05)
            for i, b in enumerate(np.radians([0, 120, 240]))
        ),
    )
    with pytest.raises(OmnikinError, match="no wheel has an 'encoder'"):
        Odometry(robot)


def test_unknown_method(tomasi):
    with pytest.raises(OmnikinError, match="unknown integration method 'rk4'"):
        Odometry(tomasi, method="rk4")
