"""Inputs the odometry must refuse rather than misread: containers without the wheels' order
(sets, dicts), text and bytes taken as numbers, absurd start poses and steering angles, and
tick-log times and angles that only Python's float() would read.

Each refusal is one line naming the sample (or file line and column) and leaves a streaming
estimator as it was; what is accepted gives the closed form of tomasi-omni3
(``support.tomasi.tomasi_poses``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import InputError, Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles, load_robot
from omnikin.odometry.integration import integrate
from support.tomasi import assert_poses_close, cli, one_line_error, tomasi_poses


class Readings:
    """An array-like with a defined order (as pandas and other libraries provide)."""

    def __init__(self, values):
        self.values = values

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.values, dtype=dtype)


UNORDERED = {
    "set": {100, -8, 33},
    "frozenset": frozenset({100, -8, 33}),
    "dict": {"w1": 100, "w2": -8, "w3": 33},
    "dict-values": {"w3": 33, "w1": 100, "w2": -8}.values(),
    "bytes": b"\x05\x07\x09",
    "bytearray": bytearray(b"\x05\x07\x09"),
    "str": "579",
}


@pytest.mark.parametrize("name", list(UNORDERED))
def test_streaming_refuses_readings_without_the_wheels_order(tomasi, name):
    """{100, -8, 33} iterates as 33, 100, -8 (wrong wheels); b'\\x05\\x07\\x09' iterates as 5, 7, 9."""
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    before = (o.pose, o.samples)
    for feed in (o.update, o.update_angles):
        with pytest.raises(OdometryInputError) as exc:
            feed(0.05, UNORDERED[name])
        assert exc.value.sample == 1 and "\n" not in str(exc.value)
        assert str(exc.value).startswith("sample 1: ")
    assert (o.pose, o.samples) == before
    fresh = Odometry(tomasi)
    with pytest.raises(OdometryInputError, match="sample 0: "):
        fresh.update(0.0, UNORDERED[name])


def test_streaming_takes_ordered_containers(tomasi):
    expected = tomasi_poses([[100, -8, 33]])[1]
    for row in ([100, -8, 33], (100, -8, 33), np.array([100, -8, 33]), Readings([100, -8, 33]), iter([100, -8, 33])):
        o = Odometry(tomasi)
        o.update(0.0, (0, 0, 0))
        assert_poses_close([o.update(0.05, row)], [expected])


@pytest.mark.parametrize(
    ("rows", "sample"),
    [
        ([[0, 0, 0], {100, -8, 33}], 1),
        ([[0, 0, 0], [1, 1, 1], b"\x05\x07\x09"], 2),
        ([[0, 0, 0], "579"], 1),
        ([[0, 0, 0], {"a": 1, "b": 2, "c": 3}], 1),
        ([[0, 0, 0], [1, {2}, 3]], 1),
        ([[0, 0, 0], [1, 2, 3, 4]], 1),
        ([[0, 0, 0], (v for v in (1, 2, 3))], 1),
    ],
    ids=["set-row", "bytes-row", "str-row", "dict-row", "set-reading", "ragged", "generator-row"],
)
def test_batch_refuses_rows_without_the_wheels_order(tomasi, rows, sample):
    """Before: a set row silently took NumPy's object path or a ValueError traceback."""
    t = [0.1 * k for k in range(len(rows))]
    for run in (
        lambda: batch_odometry(tomasi, t, rows),
        lambda: batch_odometry_from_angles(tomasi, t, rows),
    ):
        with pytest.raises(OdometryInputError) as exc:
            run()
        assert exc.value.sample == sample and "\n" not in str(exc.value)


@pytest.mark.parametrize("ticks", [{(0, 0, 0), (1, 2, 3)}, {0: [0, 0, 0], 1: [1, 2, 3]}, b"abc", iter([[0, 0, 0]])])
def test_batch_refuses_whole_inputs_without_order(tomasi, ticks):
    with pytest.raises(OdometryInputError, match="ticks: "):
        batch_odometry(tomasi, [0.0, 0.1], ticks)


def test_batch_takes_array_likes(tomasi):
    rows = [[0, 0, 0], [100, -8, 33]]
    expected = tomasi_poses([[100, -8, 33]])
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.1], Readings(rows)).poses, expected)
    assert_poses_close(batch_odometry(tomasi, (0.0, 0.1), tuple(map(tuple, rows))).poses, expected)


def test_steering_and_times_without_order_are_refused(synchro, tomasi):
    o = Odometry(synchro)
    o.update(0.0, [0, 0, 0], [0.1, 0.1, 0.1])
    with pytest.raises(OdometryInputError, match="sample 1: steer: a set"):
        o.update(0.1, [1, 1, 1], {0.1, 0.2, 0.3})
    with pytest.raises(OdometryInputError, match="sample 1: steer"):
        batch_odometry(synchro, [0.0, 0.1], [[0] * 3, [1] * 3], steer=[[0.1] * 3, {0.1, 0.2, 0.3}])
    with pytest.raises(OdometryInputError, match="t: a set"):
        batch_odometry(tomasi, {0.0, 0.1}, [[0, 0, 0], [1, 1, 1]])


# --- start poses ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "pose",
    [[0, 0, 1e308], [0, 0, 1.0e7], [1e300, 0, 0], [0, -1e9, 0], [0, 0, math.nan], {0.0, 1.0, 2.0}, [True, 0, 0]],
)
def test_absurd_start_poses_are_refused_everywhere(tomasi, pose):
    """1e308 rad has no digit left modulo 2 pi (the estimator started at theta 0); 1e300 m
    swallows every increment. Headings are bounded like every heading the core takes (1e6 rad)."""
    o = Odometry(tomasi)
    with pytest.raises(InputError, match="pose"):
        o.reset(pose)
    with pytest.raises(InputError, match="start"):
        Odometry(tomasi, start=pose)
    with pytest.raises(InputError, match="start"):
        batch_odometry(tomasi, [0.0, 0.1], [[0, 0, 0], [1, 1, 1]], start=pose)
    with pytest.raises(InputError, match="start"):
        integrate(np.zeros((2, 3)), start=pose)


def test_large_but_real_start_poses_are_kept(tomasi):
    """A UTM northing (5.8e6 m) and a heading of two turns are fine; the heading is wrapped."""
    start = (431_000.25, 5_800_000.5, 4 * math.pi - 0.5)
    o = Odometry(tomasi, start=start)
    assert o.pose == (431_000.25, 5_800_000.5, pytest.approx(-0.5, abs=1e-12))
    res = batch_odometry(tomasi, [0.0, 0.1], [[0, 0, 0], [0, 0, 0]], start=start)
    assert res.poses[-1, :2].tolist() == [431_000.25, 5_800_000.5]


# --- steering angles ----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("robot", "bad", "why"),
    [
        ("synchro", 3.6e17, "beyond +-1e+06 rad"),
        ("synchro", math.inf, "non-finite"),
        ("ackermann", 0.8, "outside its limits [-35, 35] deg"),
    ],
)
def test_steering_angles_the_model_refuses_are_refused_at_their_sample(robot, bad, why):
    """A steering angle beyond the wheel's limits (or +-1e6 rad for a wheel that turns all the way
    round) is refused by batch and streaming at its sample, before the speed rules look at that
    sample, rather than deep in the kinematics without a sample."""
    r = load_robot(robot)
    n, m = len(r.encoded), len(r.steerable)
    t = [0.0, 0.1, 0.2]
    ticks = [[0] * n, [10] * n, [20] * n]
    steer = [[0.2] * m, [0.2] * (m - 1) + [bad], [0.2] * m]
    with pytest.raises(OdometryInputError) as b:
        batch_odometry(r, t, ticks, steer=steer)
    o = Odometry(r)
    with pytest.raises(OdometryInputError) as s:
        for k in range(3):
            o.update(t[k], ticks[k], steer[k])
    assert b.value.sample == s.value.sample == 1
    assert b.value.detail == s.value.detail and r.steer_names[-1] in b.value.detail and why in b.value.detail


# --- tick logs ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ["0_1", "\u0660.\u0661", "\uff10.1", "inf", "nan", "0x1p-3", "1e999", " "], ids=repr)
def test_tick_log_time_must_be_a_plain_decimal(tmp_path, capsys, text):
    log = tmp_path / "log.csv"
    log.write_text(f"t,w1,w2,w3\n0.0,0,0,0\n{text},1,1,1\n0.2,2,2,2\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv")
    line = one_line_error(rc, err)
    assert "line 3" in line and "column 't'" in line


def test_tick_log_plain_decimals_are_read(tmp_path, capsys):
    log = tmp_path / "log.csv"
    log.write_text("t,w1,w2,w3\n+0,0,0,0\n.05,1,1,1\n1e-1,2,2,2\n0.15E0,3,3,3\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv")
    assert rc == 0, err


@pytest.mark.parametrize(
    ("robot", "text", "why"),
    [("synchro", "3.6e17", "beyond +-1e+06 rad"), ("synchro", "1_0", "not a number"), ("ackermann", "40", "limits")],
)
def test_tick_log_steering_angles_are_checked(tmp_path, capsys, robot, text, why):
    """A steering angle is a plain decimal within what the model takes (not 3.6e17 deg), or one
    line names the file line and the wheel."""
    r = load_robot(robot)
    n, m = len(r.encoded), len(r.steerable)
    header = "t," + ",".join(w.name for w in r.encoded) + "," + ",".join(f"{name}_steer_deg" for name in r.steer_names)
    rows = [f"{0.1 * k:.1f}," + ",".join([str(k)] * n) + "," + ",".join(["5"] * m) for k in range(3)]
    rows[1] = rows[1].rsplit(",", 1)[0] + "," + text
    log = tmp_path / "log.csv"
    log.write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", robot, log, "-o", tmp_path / "o.csv")
    line = one_line_error(rc, err)
    assert "line 3" in line and r.steer_names[-1] in line and why in line
