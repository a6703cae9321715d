"""Odometry against a hostile user: exact integers end to end, wrapped counters never silently
misread, estimators that copy and pickle, tick logs written and read back, CLI output policy.

Expected poses come from the closed form of tomasi-omni3 typed in from its geometry
(``support.tomasi.tomasi_poses``: forward kinematics of the per-interval tick increments,
then the SE(2) exponential), never from the code under test.
"""

from __future__ import annotations

import copy
import json
import linecache
import math
import pickle
import traceback
import tracemalloc
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnikin import Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles, load_robot
from omnikin.errors import InputError, RobotFileError
from omnikin.io.logs import read_tick_log, write_tick_log
from omnikin.io.robot_file import robot_to_dict
from support.cli import run_entry_point  # noqa: E402
from support.paths import ROOT  # noqa: E402
from support.tomasi import (
    TOMASI_RPT,
    assert_poses_close,
    cli,
    one_line_error,
    read_csv_traj,
    tomasi_file,
    tomasi_poses,
    write_log,
)

H = ["t", "w1", "w2", "w3"]
TOMASI_R = 0.04125
RIM_RATE = 50.0 / TOMASI_R / TOMASI_RPT  # ticks/s at the default 50 m/s rim-speed bound


def stream(robot, t, rows, **kw):
    o = Odometry(robot, **kw)
    return o, np.array([o.update(t[k], rows[k]) for k in range(len(t))], dtype=float)


# =====================================================================================================
# 1. exact integers end to end
# =====================================================================================================
def test_64_bit_unsigned_counter_log_gives_plus_11_ticks(capsys, tmp_path):
    """18446744073709551610 -> 5 on a 64-bit counter is +11 ticks; through a float both are 1.8e19
    and 5.0 and the increment is lost (0, or a wild jump)."""
    log = write_log(tmp_path / "log.csv", H, [[0.0, 18446744073709551610, 7, -7], [0.1, 5, 7, -7]])
    out = tmp_path / "out.csv"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--counter-bits", 64)
    assert rc == 0, err
    assert_poses_close(read_csv_traj(out)[:, 1:], tomasi_poses([[11, 0, 0]]), atol=1e-9)


def test_readings_beyond_2_53_are_not_rounded(capsys, tmp_path):
    """2**53 + 1 and 2**53 + 12 differ by 11; as floats they are 2**53 and 2**53 + 12 (12 apart)."""
    base = 2**53 + 1
    log = write_log(tmp_path / "log.csv", H, [[0.0, base, base, base], [0.1, base + 11, base - 5, base + 3]])
    out = tmp_path / "out.csv"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out)
    assert rc == 0, err
    assert_poses_close(read_csv_traj(out)[:, 1:], tomasi_poses([[11, -5, 3]]), atol=1e-9)
    parsed = read_tick_log(log, load_robot("tomasi-omni3"))
    assert parsed.ticks.dtype == np.int64 and int(parsed.ticks[1, 0]) == base + 11


def test_uint64_log_is_kept_unsigned_and_exact(tomasi, tmp_path):
    top = 2**64 - 1
    log = write_log(tmp_path / "log.csv", H, [[0.0, top - 3, 0, 0], [0.1, top, 0, 0]])
    parsed = read_tick_log(log, tomasi)
    assert parsed.ticks.dtype == np.uint64 and int(parsed.ticks[1, 0]) == top


@pytest.mark.parametrize(
    "text",
    ["1_0", "\u0661\u0662", "0x10", "1e3", "5.0", "1 0", "+5", "", "--5", "５"],
    ids=[
        "underscore",
        "arabic-indic",
        "hex",
        "exponent",
        "decimal-point",
        "inner-space",
        "plus",
        "empty",
        "double-minus",
        "fullwidth",
    ],
)
def test_log_refuses_anything_but_plain_decimal_integers(capsys, tmp_path, text):
    log = tmp_path / "log.csv"
    log.write_text("t,w1,w2,w3\n0.0,0,0,0\n0.1,5," + text + ",2\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv")
    line = one_line_error(rc, err)
    assert str(log) in line and "line 3" in line and "'w2'" in line
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("text", ["18446744073709551616", "-9223372036854775809", "1" * 5000])
def test_log_refuses_readings_beyond_64_bits(capsys, tmp_path, text):
    log = tmp_path / "log.csv"
    log.write_text(f"t,w1,w2,w3\n0.0,0,0,0\n0.1,{text},0,0\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv")
    line = one_line_error(rc, err)
    assert "line 3" in line and "64-bit" in line and len(line) < 400


INT_DTYPES = [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64]


@pytest.mark.parametrize("dtype", INT_DTYPES)
def test_counter_range_checked_for_every_integer_dtype(tomasi, dtype):
    """A reading of 20 does not fit a 4-bit counter (-8 .. 15), whatever the array's type."""
    tk = np.array([[0, 0, 0], [5, 0, 0], [10, 0, 0], [20, 0, 0]], dtype=dtype)
    t = [0.0, 1.0, 2.0, 3.0]
    with pytest.raises(OdometryInputError, match="4-bit counter") as batch_err:
        batch_odometry(tomasi, t, tk, counter_bits=4)
    assert batch_err.value.sample == 3
    o = Odometry(tomasi, counter_bits=4)
    for k in range(3):
        o.update(t[k], tk[k])
    before = o.pose
    with pytest.raises(OdometryInputError, match="4-bit counter") as stream_err:
        o.update(t[3], tk[3])
    assert stream_err.value.sample == 3 and o.pose == before


@pytest.mark.parametrize("dtype", INT_DTYPES)
def test_every_integer_dtype_integrates_like_python_ints(tomasi, dtype):
    start = 60 if np.dtype(dtype).kind == "u" else -60
    tk = np.array([[start, 5, 9], [start + 40, 20, 9], [start + 50, 30, 2]], dtype=dtype)
    expected = tomasi_poses([[40, 15, 0], [10, 10, -7]])
    t = [0.0, 0.1, 0.2]
    assert_poses_close(batch_odometry(tomasi, t, tk).poses, expected)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning from NumPy scalar arithmetic
        assert_poses_close(stream(tomasi, t, list(tk))[1], expected)  # NumPy rows
        assert_poses_close(stream(tomasi, t, [list(r) for r in tk])[1], expected)  # lists of NumPy scalars


@given(
    st.lists(st.tuples(*[st.integers(-100, 100)] * 3), min_size=1, max_size=12),
    st.sampled_from([None, 8, 16, 32, 64]),
    st.integers(0, 2**64 - 1),
    st.sampled_from(["python", "numpy"]),
)
def test_any_counter_representation_integrates_the_true_increments(increments, bits, offset, form):
    """Readings = offset + running sum of the increments, stored as the counter stores them
    (unsigned, modulo 2**bits; without a width: plain integers, possibly beyond 64 bits). Batch and
    streaming both give the closed form of the true increments. Samples 0.1 s apart: arbitrary
    increments of up to 100 ticks change the speed by less than the default change-of-speed bound
    (30 m/s^2 at the rim: 694 ticks between two 0.1 s intervals)."""
    tomasi = load_robot("tomasi-omni3")
    true = np.cumsum([[0, 0, 0]] + increments, axis=0, dtype=object) + offset
    readings = true % (1 << bits) if bits else true
    rows = [[int(v) for v in r] for r in readings]
    if form == "numpy" and 0 <= min(min(r) for r in rows) and max(max(r) for r in rows) < 2**64:
        rows = np.array(rows, dtype=np.uint64)
    t = [0.1 * k for k in range(len(rows))]
    expected = tomasi_poses(increments)
    assert_poses_close(batch_odometry(tomasi, t, rows, counter_bits=bits).poses, expected, atol=1e-9)
    assert_poses_close(stream(tomasi, t, list(rows), counter_bits=bits)[1], expected, atol=1e-9)


def test_uint64_beyond_int64_does_not_wrap_through_int64(tomasi):
    """Without a counter width, 0 -> 2**64 - 1 is a jump of 2**64 - 1 ticks (refused), not -1."""
    tk = np.array([[0, 0, 0], [2**64 - 1, 0, 0]], dtype=np.uint64)
    with pytest.raises(OdometryInputError, match="impossible jump of 18446744073709551615 ticks"):
        batch_odometry(tomasi, [0.0, 0.1], tk)
    o = Odometry(tomasi)
    o.update(0.0, tk[0])
    with pytest.raises(OdometryInputError, match="impossible jump of 18446744073709551615 ticks"):
        o.update(0.1, tk[1])
    # on a 64-bit counter the same readings are -1 tick
    expected = tomasi_poses([[-1, 0, 0]])
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.1], tk, counter_bits=64).poses, expected)
    assert_poses_close(stream(tomasi, [0.0, 0.1], list(tk), counter_bits=64)[1], expected)


def test_int64_extremes_without_width_are_a_jump_not_a_wrap(tomasi):
    tk = np.array([[-(2**63), 0, 0], [2**63 - 1, 0, 0]], dtype=np.int64)
    with pytest.raises(OdometryInputError, match="impossible jump of 18446744073709551615 ticks"):
        batch_odometry(tomasi, [0.0, 0.1], tk)


def test_python_lists_of_huge_ints_stay_exact(tomasi):
    """np.asarray would make these float64 (rounded); the increments must stay +11 and -4."""
    rows = [[18446744073709551610, 2**63 + 3, 1], [18446744073709551610 + 5, 2**63 - 1, 1]]
    expected = tomasi_poses([[5, -4, 0]])
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.1], rows).poses, expected)
    big = [[10**30, -(10**30), 0], [10**30 + 5, -(10**30) - 4, 0]]  # beyond 64 bits
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.1], big).poses, expected)
    assert_poses_close(stream(tomasi, [0.0, 0.1], big)[1], expected)
    # floats among integers beyond 2**53: every reading as the exact number it is (+3, +1.5, 0)
    mixed = [[2**60, 0.5, 0], [2**60 + 3, 2.0, 0]]
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.1], mixed).poses, tomasi_poses([[3, 1.5, 0]]))


def test_streaming_python_and_numpy_scalars_of_64_bit_counter(tomasi):
    expected = tomasi_poses([[11, 0, 0]])
    for first, second in (
        (18446744073709551610, 5),
        (np.uint64(18446744073709551610), np.uint64(5)),
        (-6, np.int64(5)),
    ):
        assert_poses_close(stream(tomasi, [0.0, 0.1], [[first, 0, 0], [second, 0, 0]], counter_bits=64)[1], expected)


def test_numpy_inputs_take_the_generated_kernel(tomasi):
    """NumPy rows, NumPy scalars, np.float64 times and wheel angles are handled by the kernel itself,
    not the (slow) general path: calling it directly gives a new state (from the third sample on:
    the second has no previous speed for the change-of-speed test and takes the general path)."""
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    o.update(0.1, [3, 4, 5])
    for t, row in (
        (np.float64(0.2), np.array([6, 8, 10])),
        (0.2, [np.int32(6), np.uint64(8), 10]),
        (0.2, (6, 8, 10)),
        (1, np.array([6, 8, 10], dtype=np.uint16)),
    ):
        assert o._step_ticks(o._state, t, row) is not None, (t, row)
    a = Odometry(tomasi)
    a.update_angles(0.0, [0.0, 0.0, 0.0])
    for row in ([0.1, 0.2, 0.3], np.array([0.1, 0.2, 0.3]), [np.float32(0.1), 0, np.float64(0.3)]):
        assert a._step_angles(a._state, 0.1, row) is not None


def test_readings_from_an_iterator_are_read_once(tomasi):
    o = Odometry(tomasi)
    o.update(0.0, iter([0, 0, 0]))
    pose = o.update(0.1, (v for v in [11, -5, 3]))
    assert_poses_close([pose], tomasi_poses([[11, -5, 3]])[1:])


def test_bools_and_floats_in_numpy_rows_are_not_ticks(tomasi):
    o = Odometry(tomasi, counter_bits=16)
    o.update(0.0, [0, 0, 0])
    with pytest.raises(OdometryInputError, match="bool"):
        o.update(0.1, np.array([True, False, True]))
    with pytest.raises(OdometryInputError, match="not a number"):
        o.update(0.1, [np.True_, 0, 0])
    assert o.samples == 1


# =====================================================================================================
# 2. wrapped counters are never silently misread
# =====================================================================================================
def wrapped_16_bit(n=30, per_sample=(3000, -2000, 1000)):
    k = np.arange(n + 1)[:, None]
    true = k * np.array(per_sample)
    return np.arange(n + 1) * 0.1, true % 65536, [per_sample] * n


def test_wrapped_log_without_width_refused_with_hint(tomasi):
    t, wrapped, _ = wrapped_16_bit()
    with pytest.raises(OdometryInputError, match=r"counter_bits, --counter-bits or encoder\.counter_bits") as exc:
        batch_odometry(tomasi, t, wrapped)
    assert "\n" not in str(exc.value)
    o = Odometry(tomasi)
    with pytest.raises(OdometryInputError, match="counter width"):
        for k in range(len(t)):
            o.update(t[k], [int(v) for v in wrapped[k]])


def test_counter_bits_from_the_robot_file(tmp_path, capsys):
    """encoder.counter_bits in the robot file: batch, streaming and the CLI use it; the pose is the
    closed form of the true increments."""
    robot_path = tomasi_file(tmp_path, ", counter_bits: 16")
    robot = load_robot(robot_path)
    assert [w.encoder.counter_bits for w in robot.wheels] == [16, 16, 16]
    t, wrapped, inc = wrapped_16_bit()
    expected = tomasi_poses(inc)
    assert_poses_close(batch_odometry(robot, t, wrapped).poses, expected, atol=1e-9)
    assert_poses_close(stream(robot, t, [list(map(int, r)) for r in wrapped])[1], expected, atol=1e-9)
    log = write_log(tmp_path / "log.csv", H, [[f"{a:.1f}", *r] for a, r in zip(t, wrapped.tolist(), strict=True)])
    out = tmp_path / "out.csv"
    rc, _, err = cli(capsys, "odometry", robot_path, log, "-o", out)
    assert rc == 0, err
    assert_poses_close(read_csv_traj(out)[:, 1:], expected, atol=1e-8)
    # an explicit width that agrees is fine; one that contradicts the file is refused
    assert cli(capsys, "odometry", robot_path, log, "-o", out, "--force", "--counter-bits", 16)[0] == 0
    rc, _, err = cli(capsys, "odometry", robot_path, log, "-o", out, "--force", "--counter-bits", 32)
    line = one_line_error(rc, err)
    assert "counter_bits=32" in line and "16" in line and "'w1'" in line
    with pytest.raises(InputError, match="contradicts"):
        Odometry(robot, counter_bits=32)


def test_counter_bits_per_wheel(tmp_path):
    """One 8-bit wheel among plain counters: only that wheel wraps."""
    p = tmp_path / "mixed.yaml"
    p.write_text(
        "omnikin: 1\nname: mixed\nwheels:\n"
        "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125,"
        " encoder: {ticks_per_rev: 600, counter_bits: 8}}\n"
        "  - {name: w2, type: omni, distance: 0.113, angle_deg: 120, radius: 0.04125,"
        " encoder: {ticks_per_rev: 600}}\n"
        "  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125,"
        " encoder: {ticks_per_rev: 600}}\n",
        encoding="utf-8",
    )
    robot = load_robot(p)
    rows = [[250, 250, -3], [4, 260, -3]]  # w1: 250 -> 4 is +10 on 8 bits; w2 +10 plainly
    expected = tomasi_poses([[10, 10, 0]])
    assert_poses_close(batch_odometry(robot, [0.0, 0.1], rows).poses, expected)
    assert_poses_close(stream(robot, [0.0, 0.1], rows)[1], expected)


@pytest.mark.parametrize("value", ["1", "65", "16.0", "true", "'16'", "-8", "1e1"])
def test_robot_file_counter_bits_validated(tmp_path, value):
    with pytest.raises(RobotFileError, match=r"'w1' \(#1\): field 'encoder.counter_bits'"):
        load_robot(tomasi_file(tmp_path, f", counter_bits: {value}"))


def test_robot_file_counter_bits_round_trip(tmp_path):
    robot = load_robot(tomasi_file(tmp_path, ", counter_bits: 32"))
    assert robot_to_dict(robot)["wheels"][0]["encoder"]["counter_bits"] == 32
    assert "counter_bits" not in robot_to_dict(load_robot("tomasi-omni3"))["wheels"][0]["encoder"]


def test_default_bound_is_50_m_s_at_the_rim(tomasi):
    """Largest accepted jump over dt: 50 m/s / r / rad_per_tick * dt + 2 ticks, in batch and
    streaming alike (the streaming kernel leaves a sample that close to the limit to the exact rule)."""
    dt = 0.01
    limit = RIM_RATE * dt + 2.0
    ok, bad = math.floor(limit), math.floor(limit) + 1
    assert ok <= limit < bad
    assert_poses_close(batch_odometry(tomasi, [0.0, dt], [[0, 0, 0], [ok, 0, 0]]).poses, tomasi_poses([[ok, 0, 0]]))
    assert_poses_close(stream(tomasi, [0.0, dt], [[0, 0, 0], [0, -ok, 0]])[1], tomasi_poses([[0, -ok, 0]]))
    with pytest.raises(OdometryInputError, match=f"impossible jump of {bad} ticks"):
        batch_odometry(tomasi, [0.0, dt], [[0, 0, 0], [bad, 0, 0]])
    with pytest.raises(OdometryInputError, match=f"impossible jump of -{bad} ticks"):
        stream(tomasi, [0.0, dt], [[0, 0, 0], [0, 0, -bad]])


def test_max_wheel_speed_sets_the_bound(tomasi, tmp_path, capsys):
    """max_wheel_speed 10 rad/s: 1.5 x 10 / rad_per_tick x 0.1 s + 2 = 145.2 ticks in 0.1 s."""
    limit = 1.5 * 10.0 / TOMASI_RPT * 0.1 + 2.0
    assert 145 < limit < 146
    rows, t = [[0, 0, 0], [146, 0, 0]], [0.0, 0.1]
    for run in (
        lambda: batch_odometry(tomasi, t, rows, max_wheel_speed=10.0),
        lambda: stream(tomasi, t, rows, max_wheel_speed=10.0),
    ):
        with pytest.raises(OdometryInputError, match="max_wheel_speed"):
            run()
    assert_poses_close(
        batch_odometry(tomasi, t, [[0, 0, 0], [145, 0, 0]], max_wheel_speed=10.0).poses, tomasi_poses([[145, 0, 0]])
    )
    log = write_log(tmp_path / "log.csv", H, [[0.0, 0, 0, 0], [0.1, 146, 0, 0]])
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv", "--max-wheel-speed", 10)
    assert "line 3" in one_line_error(rc, err)
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(OdometryInputError, match="max_wheel_speed"):
            Odometry(tomasi, max_wheel_speed=bad)


def test_wheel_angles_have_the_same_physical_bound(tomasi):
    bound_rad = 50.0 / TOMASI_R * 0.1 + 2.0 * TOMASI_RPT  # 0.1 s
    rows = [[0.0, 0.0, 0.0], [bound_rad * 1.01, 0.0, 0.0]]
    with pytest.raises(OdometryInputError, match="impossible jump .* rad"):
        batch_odometry_from_angles(tomasi, [0.0, 0.1], rows)
    o = Odometry(tomasi)
    o.update_angles(0.0, rows[0])
    with pytest.raises(OdometryInputError, match="impossible jump .* rad"):
        o.update_angles(0.1, rows[1])


# =====================================================================================================
# 3. estimator structure: copy, pickle, tracebacks, failed updates change nothing
# =====================================================================================================
def drive(o, ks, bits=None):
    """Feed samples k of a smooth log (ticks wrapped to ``bits`` when given)."""
    out = None
    for k in ks:
        row = [13 * k, -7 * k + k * k % 5, 3 * k]
        if bits:
            row = [v % (1 << bits) for v in row]
        out = o.update(0.01 * k, row)
    return out


@pytest.mark.parametrize("kw", [{}, {"counter_bits": 8}, {"method": "euler"}], ids=["plain", "8-bit", "euler"])
def test_deepcopy_gives_an_independent_estimator(tomasi, kw):
    bits = kw.get("counter_bits")
    o = Odometry(tomasi, **kw)
    drive(o, range(20), bits)
    pose = o.pose
    c = copy.deepcopy(o)
    drive(c, range(20, 40), bits)
    assert o.pose == pose and o.samples == 20  # the copy moved, the original did not
    drive(o, range(20, 40), bits)
    assert o.pose == c.pose and o.samples == c.samples == 40  # and both continue identically
    ref = Odometry(tomasi, **kw)
    assert drive(ref, range(40), bits) == o.pose


def test_pickle_round_trip_continues_identically(tomasi):
    o = Odometry(tomasi, counter_bits=16)
    drive(o, range(25), 16)
    p = pickle.loads(pickle.dumps(o))
    assert p.pose == o.pose and p.t == o.t and p.samples == o.samples
    assert drive(p, range(25, 60), 16) == drive(o, range(25, 60), 16)
    assert p.twist == o.twist and p.residual == o.residual


def test_pickle_of_a_steerable_estimator(tmp_path):
    robot = load_robot("synchro")
    o = Odometry(robot)
    o.update(0.0, [0, 0, 0], [0.1, 0.1, 0.1])
    o.update(0.1, [5, 5, 5], [0.1, 0.1, 0.1])
    p = pickle.loads(pickle.dumps(o))
    assert p.update(0.2, [9, 9, 9], [0.2, 0.2, 0.2]) == o.update(0.2, [9, 9, 9], [0.2, 0.2, 0.2])
    assert p.residual == o.residual


def test_update_is_a_method_not_an_instance_closure(tomasi):
    o = Odometry(tomasi)
    assert "update" not in vars(o) and "update_angles" not in vars(o)
    assert Odometry.update.__qualname__ == "Odometry.update"


def test_generated_kernel_lines_appear_in_tracebacks(tomasi):
    step = Odometry(tomasi)._step_ticks
    filename = step.__code__.co_filename
    assert linecache.getline(filename, step.__code__.co_firstlineno).startswith("def step_ticks(")
    try:
        step(None, 0.0, [1, 2, 3])  # not a state: fails at its first line
    except TypeError:
        text = traceback.format_exc()
    else:
        pytest.fail("a None state must not unpack")
    assert filename in text and "= state" in text  # the source line itself is shown


def bad_samples():
    return [
        (0.35, [1, 2]),
        (0.35, [1, 2, "3"]),
        (0.35, [1, 2, float("nan")]),
        (float("inf"), [1, 2, 3]),
        (0.1, [1, 2, 3]),
        (0.3, [1, 2, 3]),
        (0.35, [10**9, 0, 0]),
        (0.35, [True, 0, 0]),
        (0.35, np.array([True, False, True])),
        (0.35, [1, 2, 3, 4]),
        ("0.4", [1, 2, 3]),
        (0.35, None),
    ]


@pytest.mark.parametrize("bits", [None, 16])
def test_a_failed_update_changes_nothing(tomasi, bits):
    o = Odometry(tomasi, counter_bits=bits)
    drive(o, range(31), bits)
    before = pickle.dumps(o.__getstate__())
    for t, row in bad_samples():
        if bits and isinstance(row, list) and row[:1] == [10**9]:
            row = [40000, 0, 0]
        with pytest.raises(InputError):
            o.update(t, row)
        assert pickle.dumps(o.__getstate__()) == before, (t, row)


def test_ticks_and_angles_are_not_mixed(tomasi):
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    with pytest.raises(InputError, match="reset"):
        o.update_angles(0.1, [0.0, 0.0, 0.0])
    o.reset()
    o.update_angles(0.0, [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="reset"):
        o.update(0.1, [1, 1, 1])


def test_update_angles_works_with_counter_widths(tmp_path):
    """Wheel angles never wrap: a robot file with counter_bits must not stop update_angles."""
    robot = load_robot(tomasi_file(tmp_path, ", counter_bits: 16"))
    o = Odometry(robot)
    o.update_angles(0.0, [0.0, 0.0, 0.0])
    pose = o.update_angles(0.1, [11 * TOMASI_RPT, 0.0, 0.0])
    assert_poses_close([pose], tomasi_poses([[11, 0, 0]])[1:])


def test_errors_carry_the_sample(tomasi):
    with pytest.raises(OdometryInputError) as exc:
        batch_odometry(tomasi, [0.0, 0.1, 0.05], np.zeros((3, 3), int))
    assert exc.value.sample == 2 and "sample" not in exc.value.detail
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    with pytest.raises(OdometryInputError) as exc:
        o.update(0.1, [10**6, 0, 0])
    assert exc.value.sample == 1 and exc.value.detail.startswith("impossible jump")


def test_batch_does_not_copy_int64_ticks(tomasi):
    """Peak memory of batch odometry on int64 ticks stays below the arrays it returns (poses,
    increments; the residual of a square layout takes none) plus a fraction of its input: no
    full-size copy or temporary of the readings."""
    n = 400_000
    ticks = np.zeros((n, 3), dtype=np.int64)
    ticks[:, 0] = np.arange(n)
    t = np.arange(n) * 0.01
    batch_odometry(tomasi, t[:10], ticks[:10])  # imports and caches outside the measurement
    tracemalloc.start()
    res = batch_odometry(tomasi, t, ticks)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    returned = res.poses.nbytes + res.increments.nbytes
    assert res.residual.base is not None and not res.residual.flags.writeable  # zeros, no memory
    assert peak < returned + ticks.nbytes // 2, (peak, returned, ticks.nbytes)


# =====================================================================================================
# 5. tick logs out: write_tick_log, simulate --log, the shipped example
# =====================================================================================================
def test_write_tick_log_round_trip_is_exact(tomasi, tmp_path):
    t = np.array([0.0, 0.01, 0.02])
    ticks = np.array([[2**64 - 2, 5, 0], [1, 6, 0], [4, 7, 1]], dtype=np.uint64)
    path = tmp_path / "log.csv"
    write_tick_log(path, t, ticks, tomasi.encoded_names, comment="made by a test")
    text = path.read_text(encoding="utf-8").splitlines()
    assert text[0] == "# made by a test" and text[1] == "t,w1,w2,w3" and text[2].endswith(",18446744073709551614,5,0")
    log = read_tick_log(path, tomasi)
    assert log.ticks.tolist() == ticks.tolist() and log.t.tolist() == t.tolist()


def test_write_tick_log_with_steering(tmp_path):
    robot = load_robot("synchro")
    steer = np.radians([[10.0, 20.0, -30.0], [11.0, 21.0, -31.0]])
    path = tmp_path / "s.csv"
    write_tick_log(path, [0.0, 0.1], [[0, 0, 0], [5, 5, 5]], robot.encoded_names, steer, steer_names=robot.steer_names)
    log = read_tick_log(path, robot)
    np.testing.assert_allclose(log.steer, steer, atol=1e-12)


def test_write_tick_log_refuses_fractional_ticks(tomasi, tmp_path):
    with pytest.raises(InputError, match="whole-number"):
        write_tick_log(tmp_path / "x.csv", [0.0, 0.1], [[0.5, 0, 0], [1, 0, 0]], tomasi.encoded_names)
    assert not (tmp_path / "x.csv").exists()


def run_omnikin(*args, cwd):
    """The command line in a fresh process, importing this checkout's omnikin."""
    return run_entry_point(*args, cwd=cwd, timeout=300)


def test_simulate_log_then_odometry_as_written(tmp_path):
    """`omnikin simulate tomasi-omni3 --log log.csv && omnikin odometry tomasi-omni3 log.csv -o traj.csv`:
    the odometry of the log ends where the simulator's own odometry of the same ticks ended."""
    sim = run_omnikin(
        "simulate",
        "tomasi-omni3",
        "--path",
        "square cw rotate 1",
        "--rate",
        "20",
        "--log",
        "log.csv",
        "--json",
        cwd=tmp_path,
    )
    assert sim.returncode == 0, sim.stderr
    odo = run_omnikin("odometry", "tomasi-omni3", "log.csv", "-o", "traj.csv", cwd=tmp_path)
    assert odo.returncode == 0, odo.stderr
    end = read_csv_traj(tmp_path / "traj.csv")[-1, 1:]
    np.testing.assert_allclose(end, json.loads(sim.stdout)["odometry_end"], atol=2e-9)
    again = run_omnikin("simulate", "tomasi-omni3", "--log", "log.csv", cwd=tmp_path)
    assert again.returncode == 2 and "--force" in again.stderr and "Traceback" not in again.stderr


def test_shipped_example_is_what_its_comment_says(tmp_path):
    """examples/tick_log.csv: a few hundred rows made by the command in its first line."""
    example = ROOT / "examples" / "tick_log.csv"
    lines = example.read_text(encoding="utf-8").splitlines()
    assert 200 <= len(lines) <= 1000
    command = lines[0].split("written by: ", 1)[1]
    argv = command.split()
    assert argv[:2] == ["omnikin", "simulate"]
    args = [a.strip("'") for a in " ".join(argv[2:]).replace("'square cw rotate 1'", "SQUARE").split()]
    args = ["square cw rotate 1" if a == "SQUARE" else a for a in args]
    args[args.index("--log") + 1] = "again.csv"
    proc = run_omnikin("simulate", *args, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "again.csv").read_text(encoding="utf-8").splitlines()[1:] == lines[1:]
    assert read_tick_log(example, load_robot("tomasi-omni3")).ticks.dtype == np.int64


# =====================================================================================================
# 6. the odometry command: file lines, --force, standard output
# =====================================================================================================
GOOD = [[0.0, 0, 0, 0], [0.1, 5, -3, 2], [0.2, 10, -6, 4]]


def test_output_exists_needs_force(capsys, tmp_path):
    log = write_log(tmp_path / "log.csv", H, GOOD)
    out = tmp_path / "traj.csv"
    out.write_text("precious\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out)
    assert "--force" in one_line_error(rc, err) and out.read_text(encoding="utf-8") == "precious\n"
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--force")[0] == 0
    assert read_csv_traj(out).shape == (3, 4)


def test_output_never_overwrites_the_log(capsys, tmp_path):
    log = write_log(tmp_path / "log.csv", H, GOOD)
    before = log.read_bytes()
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", log, "--force")
    assert "input" in one_line_error(rc, err) and log.read_bytes() == before


def test_output_dash_writes_the_trajectory_to_stdout(capsys, tmp_path):
    log = write_log(tmp_path / "log.csv", H, GOOD)
    rc, out, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", "-")
    assert rc == 0
    lines = out.strip().splitlines()
    assert lines[0] == "t,x,y,theta" and len(lines) == 4
    assert_poses_close(
        np.array([r.split(",") for r in lines[1:]], float)[:, 1:], tomasi_poses([[5, -3, 2], [5, -3, 2]]), atol=1e-9
    )
    assert "final pose" in err
    rc, out, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", "-", "--json")
    assert "standard output" in one_line_error(rc, err) and out == ""


def test_cli_names_the_file_line_of_a_bad_sample(capsys, tmp_path):
    """Comments, blank lines and skipped duplicates before the bad sample: the line is the file's."""
    log = tmp_path / "log.csv"
    log.write_text(
        "# bench run\nt,w1,w2,w3\n\n0.0,0,0,0\n0.0,0,0,0\n# note\n0.01,5,5,5\n0.02,9000,5,5\n", encoding="utf-8"
    )
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.csv")
    assert rc == 2 and "Traceback" not in err
    warning, line = err.strip().splitlines()
    assert "skipped 1 row" in warning and "line 5" in warning
    assert f"{log}: line 8: impossible jump of 8995 ticks" in line and "sample" not in line


def test_batch_results_do_not_change_when_the_input_changes_afterwards(tomasi):
    """The result is computed at the call: mutating the caller's ticks later changes nothing
    (the readings are not copied, so nothing may be read from them lazily)."""
    t = np.arange(50) * 0.01
    ticks = np.cumsum(np.tile(np.array([4, -2, -2], dtype=np.int64), (50, 1)), axis=0)
    res = batch_odometry(tomasi, t, ticks)
    before = (res.increments.copy(), res.twists.copy(), np.array(res.residual))
    ticks[:] = 0
    np.testing.assert_array_equal(res.increments, before[0])
    np.testing.assert_array_equal(res.twists, before[1])
    np.testing.assert_array_equal(res.residual, before[2])
    omni4 = load_robot("omni4")  # redundant: a real residual
    ticks4 = np.cumsum(np.tile(np.array([4, -2, -2, 1], dtype=np.int64), (50, 1)), axis=0)
    res4 = batch_odometry(omni4, t, ticks4)
    kept = np.array(res4.residual)
    assert np.abs(kept).max() > 0
    ticks4[:] = 0
    np.testing.assert_array_equal(res4.residual, kept)
