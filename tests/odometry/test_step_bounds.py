"""No interval may move the robot beyond the bounds of a pose, and no option may switch the
physical rules off: batch and streaming odometry refuse the same sample with one line.

A rotation of 1e15 rad in one interval has no digit left modulo 2 pi (integrated, it gives a
heading of noise, different noise in batch and streaming); a displacement of 1e14 m swallows
every later increment; ``max_wheel_speed=1e300`` would let any jump through; integers beyond the
float range must give one line, not a raw OverflowError. Expected values come from the closed
form of tomasi-omni3 (equal wheel angles ``w`` turn it by ``R w / L`` on the spot; wheel angles
``(0, -sin 120, -sin 240) a / R`` move it by ``a`` along its x axis), typed in from its geometry.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles, load_robot
from support.tomasi import TOMASI_L, TOMASI_R, TOMASI_RPT


def spin_ticks(phi: float) -> int:
    """Ticks of each tomasi-omni3 wheel that turn the body by ``phi`` [rad] on the spot."""
    return round(TOMASI_L * phi / (TOMASI_R * TOMASI_RPT))


def run_both(robot, t, rows, **kw):
    """(streaming error or poses, batch error or poses) for the same log."""
    o = Odometry(robot, **kw)
    try:
        stream = [o.update(tk, r) for tk, r in zip(t, rows, strict=True)]
    except OdometryInputError as exc:
        stream = exc
    try:
        batch = batch_odometry(robot, t, rows, **kw).poses
    except OdometryInputError as exc:
        batch = exc
    return stream, batch


def assert_same_refusal(stream, batch, sample: int, words: str) -> None:
    assert isinstance(stream, OdometryInputError) and isinstance(batch, OdometryInputError), (stream, batch)
    assert stream.sample == batch.sample == sample
    assert stream.detail == batch.detail
    assert words in stream.detail and "\n" not in str(stream) and len(str(stream)) < 300, stream


def test_a_rotation_beyond_the_heading_bound_in_one_interval_is_refused_at_its_sample(tomasi):
    """1.5e6 rad in 1e4 s is within the speed rule (1212 rad/s per wheel) but beyond 1e6 rad: the
    4th sample (the generated kernel is active by then) is refused by both."""
    d = spin_ticks(1.5e6)
    t = [0.0, 0.01, 0.02, 1e4 + 0.02]
    rows = [[0, 0, 0], [1, 1, 1], [2, 2, 2], [2 + d, 2 + d, 2 + d]]
    stream, batch = run_both(tomasi, t, rows)
    assert_same_refusal(stream, batch, 3, "rotation of 1.5e+06 rad, beyond +-1e+06 rad")


def test_a_rotation_within_the_heading_bound_is_integrated(tomasi):
    d = spin_ticks(0.9e6)
    phi = TOMASI_R * d * TOMASI_RPT / TOMASI_L
    heading = (phi + math.pi) % (2 * math.pi) - math.pi
    stream, batch = run_both(tomasi, [0.0, 1e4], [[0, 0, 0], [d, d, d]])
    for poses in (np.asarray(stream), batch):
        assert np.allclose(poses[-1], [0.0, 0.0, heading], atol=1e-6), poses


def test_a_displacement_beyond_the_position_bound_in_one_interval_is_refused(tomasi):
    """2e8 m along x in 1e7 s (20 m/s): beyond the 1e8 m a pose may hold."""
    a = 2e8
    w = [0.0, -math.sin(math.radians(120)) * a / TOMASI_R, -math.sin(math.radians(240)) * a / TOMASI_R]
    rows = [[0, 0, 0], [round(v / TOMASI_RPT) for v in w]]
    stream, batch = run_both(tomasi, [0.0, 1e7], rows)
    assert_same_refusal(stream, batch, 1, "displacement along the body x axis of 2e+08 m, beyond +-1e+08 m")


def test_the_attack_log_of_a_1e17_s_interval_is_refused(tmp_path):
    """diff-drive, t = 0, 1e17, 2e17 s, left = 0, 9e18, 1.8e19 ticks: integrated, these give
    headings of noise."""
    robot = load_robot("diff-drive")
    t, rows = [0.0, 1e17, 2e17], [[0, 0], [9 * 10**18, 0], [18 * 10**18, 0]]
    stream, batch = run_both(robot, t, rows)
    assert_same_refusal(stream, batch, 1, "rotation of")


@pytest.mark.parametrize("speed", [1e300, 1e5, 0.0, 1e-9, math.inf, math.nan])
def test_a_wheel_speed_bound_outside_the_robot_file_range_is_refused(tomasi, speed):
    """max_speed in a robot file lies in [1e-3, 1e4] rad/s (95 000 rpm): so does the option."""
    for make in (
        lambda: Odometry(tomasi, max_wheel_speed=speed),
        lambda: batch_odometry(tomasi, [0.0, 1.0], [[0, 0, 0], [1, 1, 1]], max_wheel_speed=speed),
    ):
        with pytest.raises(OdometryInputError, match="max_wheel_speed must") as exc:
            make()
        assert "\n" not in str(exc.value)


def test_the_largest_wheel_speed_bound_lets_a_fast_wheel_through(tomasi):
    """1e4 rad/s x 1.5 over 0.01 s is 150 rad: 14 000 ticks pass."""
    stream, batch = run_both(tomasi, [0.0, 0.01], [[0, 0, 0], [14000, 0, 0]], max_wheel_speed=1e4)
    assert not isinstance(stream, Exception) and not isinstance(batch, Exception)


def test_a_jump_bound_that_lets_a_wheel_turn_beyond_the_angle_bound_is_refused(tomasi):
    """1e20 ticks of 2 pi / 600 rad is 1e18 rad in one interval; 1e6 ticks (1e4 rad) is a bound."""
    with pytest.raises(OdometryInputError, match="max_jump=1e\\+20 ticks would let wheel 'w1' turn 1.0472e\\+18 rad"):
        Odometry(tomasi, max_jump=1e20)
    with pytest.raises(OdometryInputError, match="max_jump"):
        batch_odometry(tomasi, [0.0, 1.0], [[0, 0, 0], [1, 1, 1]], max_jump=1e20)
    Odometry(tomasi, max_jump=1e6)


def test_integer_readings_beyond_the_float_range_are_refused_at_their_sample():
    """10**400 has no float: refused in one line, never a raw OverflowError (batch: from converting
    the increments before the exact jump test; angles: from converting the readings; streaming:
    from float(d) after a speed rule that a 1e305 s interval passes)."""
    robot = load_robot("diff-drive")
    rows = [[0, 0], [10**400, 0]]
    for t in ([0.0, 1.0], [0.0, 1e305]):
        stream, batch = run_both(robot, t, rows)
        assert isinstance(stream, OdometryInputError) and stream.sample == 1, stream
        assert isinstance(batch, OdometryInputError) and batch.sample == 1, batch
        assert "\n" not in str(batch) and len(str(batch)) < 300
    with pytest.raises(OdometryInputError) as exc:
        batch_odometry_from_angles(robot, [0.0, 1.0], rows)
    assert exc.value.sample == 1 and "non-finite wheel angle" in exc.value.detail
    o = Odometry(robot)
    o.update_angles(0.0, [0, 0])
    with pytest.raises(OdometryInputError) as exc:
        o.update_angles(1.0, [10**400, 0])
    assert exc.value.sample == 1 and "non-finite wheel angle" in exc.value.detail


def test_a_wrap_hint_never_names_a_width_the_readings_do_not_fit(tomasi):
    """0 then 2**64 is 0 modulo 2**64, but 2**64 is no reading of a 64-bit counter (its range ends
    at 2**64 - 1): no width is offered. 0 then 2**64 - 1 is -1 tick on a 64-bit counter."""
    for last, hint in ((2**64, None), (2**64 - 1, "read as a 64-bit counter it is -1 ticks")):
        stream, batch = run_both(tomasi, [0.0, 0.01], [[0, 0, 0], [last, 0, 0]])
        assert_same_refusal(stream, batch, 1, "impossible jump")
        if hint is None:
            assert "read as" not in stream.detail
        else:
            assert hint in stream.detail


def test_a_refused_step_leaves_the_streaming_estimator_as_it_was(tomasi):
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    o.update(0.01, [1, 1, 1])
    before = (o.pose, o.samples, o.t, o.twist)
    d = spin_ticks(2e6)
    with pytest.raises(OdometryInputError):
        o.update(1e4, [d, d, d])
    assert (o.pose, o.samples, o.t, o.twist) == before


def test_the_kernel_and_the_general_path_take_the_same_steps_around_the_bounds(tomasi):
    """Each wheel at nearly its top speed for intervals from 100 s to 1e5 s: a rotation from about
    4e4 rad to 4e7 rad. The generated kernel hands the long intervals to the general path; both
    accept and refuse the same samples, and what they accept is the same to the bit."""
    from omnikin.odometry.streaming import _decline

    outcomes = set()
    for dt in np.geomspace(100.0, 1e5, 60):
        rule = Odometry(tomasi).rules[0]
        d = int(rule.limit(float(dt)) * 0.999)
        t = [0.0, 0.01, 0.02, 0.02 + float(dt)]
        rows = [[0, 0, 0], [1, 1, 1], [2, 2, 2], [2 + d, 2 + d, 2 + d]]
        results = []
        for general in (False, True):
            o = Odometry(tomasi, max_wheel_accel=math.inf)
            if general:
                o._step_ticks = _decline
            try:
                results.append([o.update(tk, r) for tk, r in zip(t, rows, strict=True)])
            except OdometryInputError as exc:
                results.append((exc.sample, exc.detail))
        assert results[0] == results[1], dt
        outcomes.add(isinstance(results[0], tuple))
    assert outcomes == {True, False}  # some accepted, some refused
