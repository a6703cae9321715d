"""Counters that wrap without a declared width are refused, not misread; real motion is not.

A counter of ``b`` bits read without its width changes one increment by ``2**b``. The speed
rule (50 m/s at the rim) and the change-of-speed rule (30 m/s^2 at the rim, ``A dt^2 + 4``
ticks between equal intervals ``dt``) of ``docs/conventions.md`` refuse that; the guarantee
(tomasi-omni3: 8 bits from 24 Hz, 12 bits from 6 Hz, 16 bits from 1.5 Hz) is checked at its
boundary with the worst motion the rules allow. Expected poses are the closed form of the
true tick increments (``support.tomasi.tomasi_poses``); the logs come from ``omnikin simulate
--log`` and from ``examples/tick_log.csv``.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnikin import Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles, load_robot
from omnikin.io.logs import read_tick_log, write_tick_log
from omnikin.motion.limits import MotionLimits
from omnikin.motion.plans import line, spin
from omnikin.simulation.error_models import NoiseModel
from omnikin.simulation.kinematic import simulate_kinematic
from support.paths import ROOT, omnikin_env
from support.tomasi import TOMASI_R, TOMASI_RPT, assert_poses_close, cli, one_line_error, read_csv_traj, tomasi_poses

TICKS_PER_M = 1 / (TOMASI_R * TOMASI_RPT)  # 2315 ticks per metre at the rim
ACCEL_TICKS = 30.0 * TICKS_PER_M  # the default change-of-speed bound, ticks/s^2
EXAMPLE = ROOT / "examples" / "tick_log.csv"


def wrap(ticks, bits, offset=0, signed=False):
    """Readings of a ``bits``-bit counter holding ``ticks + offset`` (unsigned, or two's complement)."""
    full = 1 << bits
    r = (np.asarray(ticks, dtype=np.int64) + offset) % full
    return np.where(r >= full // 2, r - full, r) if signed else r


def stream_error(robot, t, rows, **kw):
    """The error the streaming estimator raises on ``rows`` (None if it takes them all)."""
    o = Odometry(robot, **kw)
    try:
        for k in range(len(t)):
            o.update(float(t[k]), [int(v) for v in rows[k]])
    except OdometryInputError as exc:
        return exc
    return None


def batch_error(robot, t, rows, **kw):
    try:
        batch_odometry(robot, t, rows, **kw)
    except OdometryInputError as exc:
        return exc
    return None


def first_wrapped_sample(true, readings):
    """Index of the sample that ends the first interval whose raw increment is not the true one."""
    raw = np.diff(np.asarray(readings, dtype=np.int64), axis=0)
    k = int(np.argmax(np.any(raw != np.diff(true, axis=0), axis=1)))
    return k + 1


@pytest.fixture(scope="module")
def simulated_logs(tmp_path_factory):
    """Tick logs of tomasi-omni3 driving 'square cw rotate 1' with typical errors, written by
    ``omnikin simulate --log`` at several rates (each run in its own process)."""
    folder = tmp_path_factory.mktemp("logs")
    logs = {}
    for rate in (5, 20, 50, 100):
        path = folder / f"log{rate}.csv"
        proc = subprocess.run(
            [sys.executable, "-m", "omnikin.cli.main", "simulate", "tomasi-omni3", "--path", "square cw rotate 1"]
            + ["--rate", str(rate), "--seed", "3", "--log", str(path)],
            capture_output=True,
            text=True,
            timeout=300,
            env=omnikin_env(),
        )
        assert proc.returncode == 0, proc.stderr
        logs[rate] = read_tick_log(path, load_robot("tomasi-omni3"))
    return logs


CASES = [(8, 50), (8, 100), (12, 20), (12, 50), (16, 5), (16, 20)]
"""(width, rate [Hz]) of the simulated logs: each inside the documented guarantee."""


@pytest.mark.parametrize(("bits", "rate"), CASES)
@pytest.mark.parametrize("signed", [False, True])
def test_wrapped_simulated_log_refused_without_width_and_exact_with_it(
    tomasi, simulated_logs, tmp_path, capsys, bits, rate, signed
):
    log = simulated_logs[rate]
    true = log.ticks
    expected = tomasi_poses(np.diff(true, axis=0))
    edge = 1 << (bits - 1 if signed else bits)  # where the stored reading jumps: 2**(b-1) signed, 2**b unsigned
    readings = wrap(true, bits, offset=edge - 40, signed=signed)
    assert np.any(np.diff(readings, axis=0) != np.diff(true, axis=0)), "the counter must wrap in the log"
    path = tmp_path / "wrapped.csv"
    write_tick_log(path, log.t, readings, log.wheel_names)
    # without the width: one line naming the file line of the wrap (or of the next sample) and the wheel
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", path, "-o", tmp_path / "out.csv")
    line = one_line_error(rc, err)
    k = first_wrapped_sample(true, readings)
    assert any(f"line {s + 2}:" in line for s in (k, k + 1)), (k, line)
    assert "wheel 'w" in line and "--counter-bits" in line and f"read as a {bits}-bit counter" in line
    assert not (tmp_path / "out.csv").exists()
    # batch and streaming refuse the same sample
    b, s = batch_error(tomasi, log.t, readings), stream_error(tomasi, log.t, readings)
    assert b is not None and s is not None and b.sample == s.sample and b.detail == s.detail
    # with the width: the closed form of the true increments
    rc, _, err = cli(
        capsys, "odometry", "tomasi-omni3", path, "-o", tmp_path / "out.csv", "--counter-bits", bits, "--force"
    )
    assert rc == 0, err
    assert_poses_close(read_csv_traj(tmp_path / "out.csv")[:, 1:], expected, atol=1e-8)
    o = Odometry(tomasi, counter_bits=bits)
    poses = [o.update(float(log.t[k]), [int(v) for v in readings[k]]) for k in range(len(log.t))]
    assert_poses_close(poses, expected, atol=1e-8)


@pytest.mark.parametrize("bits", range(8, 33))
def test_every_wrap_of_the_shipped_example_is_refused(tomasi, bits):
    """The tester's reproduction: examples/tick_log.csv (20 Hz) with every reading taken modulo
    2**bits (and at other offsets, signed too) is refused without a width, at the same sample in
    batch and streaming, and exact with it."""
    log = read_tick_log(EXAMPLE, tomasi)
    expected = tomasi_poses(np.diff(log.ticks, axis=0))
    rng = np.random.default_rng(bits)
    for offset, signed in [(0, False), (int(rng.integers(1 << bits)), True), (int(rng.integers(1 << bits)), False)]:
        readings = wrap(log.ticks, bits, offset, signed)
        if np.array_equal(np.diff(readings, axis=0), np.diff(log.ticks, axis=0)):
            continue  # this offset never reaches the end of the counter
        b, s = batch_error(tomasi, log.t, readings), stream_error(tomasi, log.t, readings)
        assert b is not None, (bits, offset, signed)
        assert s is not None and s.sample == b.sample
        assert_poses_close(batch_odometry(tomasi, log.t, readings, counter_bits=bits).poses, expected, atol=1e-9)


def test_example_wrapped_to_12_bits_cli(tmp_path, capsys):
    """The reported command: every reading mod 4096, read without --counter-bits: exit 2, one line."""
    lines = EXAMPLE.read_text(encoding="utf-8").splitlines()
    out = []
    for text in lines:
        if text.startswith(("#", "t,")):
            out.append(text)
        else:
            t, *ticks = text.split(",")
            out.append(",".join([t] + [str(int(v) % 4096) for v in ticks]))
    path = tmp_path / "wrap12.csv"
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", path, "-o", "-")
    line = one_line_error(rc, err)
    assert "wrap12.csv: line" in line and "read as a 12-bit counter" in line


def guaranteed_dt(bits):
    """Longest interval [s] at which a wrap of a ``bits``-bit counter is always caught by the
    change-of-speed rule: 2**bits > 2 (A dt^2 + 4) (docs/conventions.md)."""
    return math.sqrt((2 ** (bits - 1) - 4) / ACCEL_TICKS)


@pytest.mark.parametrize("bits", [8, 12, 16])
@pytest.mark.parametrize("direction", [1, -1])
def test_guarantee_holds_for_the_worst_motion_the_rules_allow(tomasi, bits, direction):
    """Just inside the guarantee, the wheel changes its speed by the most the rule allows, in
    the direction that hides the wrap best, while its counter wraps: refused without the width,
    exact with it. The same motion unwrapped is accepted (it is within the rules)."""
    dt = 0.98 * guaranteed_dt(bits)
    change = math.floor(ACCEL_TICKS * dt * dt)  # below A dt^2 + 4 ticks: an allowed change
    first = -direction * (change // 2 - 1)
    increments = [[first, 0, 0], [first + direction * change, 0, 0]]
    full = 1 << bits
    start = full - 1 if direction > 0 else 0  # only the second interval crosses the counter's end
    true = np.cumsum([[start, 0, 0]] + increments, axis=0)
    readings = true % full
    raw = np.diff(readings, axis=0)[:, 0]
    assert raw[0] == increments[0][0] and raw[1] == increments[1][0] - direction * full
    t = [0.0, dt, 2 * dt]
    assert batch_error(tomasi, t, true) is None and stream_error(tomasi, t, true) is None
    b, s = batch_error(tomasi, t, readings), stream_error(tomasi, t, readings)
    assert b is not None and s is not None and b.sample == s.sample == 2 and "impossible change" in b.detail
    assert_poses_close(batch_odometry(tomasi, t, readings, counter_bits=bits).poses, tomasi_poses(increments))


def test_a_wrap_beyond_the_guarantee_can_pass(tomasi):
    """The honest limit (docs/conventions.md): an 8-bit counter sampled at 7 Hz, far below the
    24 Hz of the guarantee, moves 100 then -56 ticks; read without its width that is -156 then
    +200 ticks, a plausible motion at 7 Hz. No rule can tell this wrap from motion."""
    dt = 1 / 7
    true = np.cumsum([[200, 0, 0], [100, 0, 0], [-56, 0, 0]], axis=0)
    readings = true % 256
    assert np.diff(readings, axis=0)[:, 0].tolist() == [-156, 200]
    misread = batch_odometry(tomasi, [0.0, dt, 2 * dt], readings).poses
    assert not np.allclose(misread, tomasi_poses([[100, 0, 0], [-56, 0, 0]]))
    assert_poses_close(misread, tomasi_poses([[-156, 0, 0], [200, 0, 0]]))


# --- no false alarms --------------------------------------------------------------------------------------
def test_shipped_example_and_simulated_logs_are_accepted(tomasi, simulated_logs):
    for log in [read_tick_log(EXAMPLE, tomasi), *simulated_logs.values()]:
        expected = tomasi_poses(np.diff(log.ticks, axis=0))
        assert_poses_close(batch_odometry(tomasi, log.t, log.ticks).poses, expected, atol=1e-9)
        assert stream_error(tomasi, log.t, log.ticks) is None


@pytest.mark.parametrize("rate", [20.0, 100.0, 1000.0])
def test_fast_runs_near_max_speed_and_hard_stops_are_accepted(rate):
    """A robot whose wheels turn at their max_speed (25 rad/s: 1 m/s at the rim), accelerating
    and braking at 1 g (the traction limit), stopping between every segment: the default bounds
    refuse nothing, at 20 Hz, 100 Hz and 1 kHz."""
    robot = _tomasi_with_max_speed(25.0)
    plan = line(2.0) + spin(math.pi) + line(1.0, math.pi / 2) + line(2.0, math.pi) + spin(-math.pi / 2) + line(1.0)
    limits = MotionLimits(linear=10.0, angular=50.0, linear_accel=9.81, angular_accel=200.0)
    run = simulate_kinematic(plan, robot, robot, rate=rate, limits=limits, noise=NoiseModel(), rng=1)
    speeds = np.abs(np.diff(run.ticks, axis=0)) * TOMASI_RPT * rate
    assert speeds.max() > 0.95 * 25.0  # the wheels reach their max_speed
    expected = tomasi_poses(np.diff(run.ticks, axis=0))
    assert_poses_close(batch_odometry(robot, run.t, run.ticks).poses, expected, atol=1e-9)
    assert stream_error(robot, run.t, run.ticks) is None


def _tomasi_with_max_speed(max_speed):
    from dataclasses import replace

    from omnikin import Robot

    r = load_robot("tomasi-omni3")
    return Robot(r.name, tuple(replace(w, max_speed=max_speed) for w in r.wheels))


def test_jittery_timestamps_and_missed_samples_are_accepted(tomasi):
    """Timestamps 20 ms apart with +-3 ms of jitter on the stamps and every tenth sample
    missing, at 1 m/s: the change-of-speed rule takes differing intervals into account."""
    rng = np.random.default_rng(5)
    k = np.arange(2000)
    keep = k % 10 != 9
    t_true = k * 0.02
    ticks = np.round(np.outer(t_true, [1.0, -0.5, -0.5]) * TICKS_PER_M)  # 1 m/s at the rim of w1
    stamps = t_true + rng.uniform(-0.003, 0.003, k.size)
    t, rows = stamps[keep], ticks[keep].astype(np.int64)
    expected = tomasi_poses(np.diff(rows, axis=0))
    assert_poses_close(batch_odometry(tomasi, t, rows).poses, expected, atol=1e-8)
    assert stream_error(tomasi, t, rows) is None


# --- the option -------------------------------------------------------------------------------------------
def test_max_wheel_accel_sets_the_change_bound(tomasi, tmp_path, capsys):
    """An instantaneous stop from 1 m/s at 100 Hz (23 ticks to 0: more than 30 m/s^2 x (10 ms)^2
    + 4 = 10.9 ticks) is refused by default at the same sample in batch and streaming, and
    accepted with max_wheel_accel 1e4 rad/s^2 (--max-wheel-accel) or inf."""
    rows = [[0, 0, 0], [23, 0, 0], [46, 0, 0], [46, 0, 0]]
    t = [0.0, 0.01, 0.02, 0.03]
    b, s = batch_error(tomasi, t, rows), stream_error(tomasi, t, rows)
    assert b is not None and b.sample == s.sample == 3 and "max_wheel_accel" in b.detail
    expected = tomasi_poses(np.diff(rows, axis=0))
    for accel in (1e4, math.inf):
        assert_poses_close(batch_odometry(tomasi, t, rows, max_wheel_accel=accel).poses, expected)
        assert stream_error(tomasi, t, rows, max_wheel_accel=accel) is None
    path = tmp_path / "stop.csv"
    write_tick_log(path, np.array(t), np.array(rows), ["w1", "w2", "w3"])
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", path, "-o", tmp_path / "o.csv")
    assert "line 5:" in one_line_error(rc, err)
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", path, "-o", tmp_path / "o.csv", "--max-wheel-accel", "1e4")
    assert rc == 0, err
    for bad in (0.0, -1.0, math.nan, "fast", True):
        with pytest.raises(OdometryInputError, match="max_wheel_accel"):
            Odometry(tomasi, max_wheel_accel=bad)
        with pytest.raises(OdometryInputError, match="max_wheel_accel"):
            batch_odometry(tomasi, t, rows, max_wheel_accel=bad)


def test_wheel_angles_have_the_change_rule_only_when_asked(tomasi):
    """Wheel angles come unwrapped from drivers: by default only the speed rule applies (a live
    controller must not stop at an impact); with max_wheel_accel batch and streaming refuse
    the same sample."""
    a = [[0.0, 0.0, 0.0], [0.25, 0.0, 0.0], [0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]
    t = [0.0, 0.01, 0.02, 0.03]
    batch_odometry_from_angles(tomasi, t, a)
    o = Odometry(tomasi)
    for k in range(4):
        o.update_angles(t[k], a[k])
    with pytest.raises(OdometryInputError, match="impossible change of speed") as exc:
        batch_odometry_from_angles(tomasi, t, a, max_wheel_accel=100.0)
    assert exc.value.sample == 3
    o = Odometry(tomasi, max_wheel_accel=100.0)
    with pytest.raises(OdometryInputError) as exc2:
        for k in range(4):
            o.update_angles(t[k], a[k])
    assert exc2.value.sample == 3 and exc2.value.detail == exc.value.detail


def test_batch_blocks_link_the_change_rule(tomasi, monkeypatch):
    """Batch odometry checks in blocks; a wrap right after a block boundary is still compared
    with the last increment of the previous block."""
    import omnikin.odometry.batch as odometry

    monkeypatch.setattr(odometry, "CHUNK", 16)
    n = 64
    true = np.cumsum(np.tile([5, -3, -2], (n, 1)), axis=0)
    readings = wrap(true, 8, offset=168)  # w1: 5 (k + 1) + 168 passes 256 from sample 16 to 17
    assert first_wrapped_sample(true, readings) == 17  # the first interval of the second block
    b, s = batch_error(tomasi, np.arange(n) * 0.01, readings), stream_error(tomasi, np.arange(n) * 0.01, readings)
    assert b is not None and s is not None and b.sample == s.sample == 17


def test_documented_guarantee_table_follows_from_the_default_bounds():
    """docs/conventions.md lists, per preset and counter width, the sample rate above which a wrap
    is always caught: max of sqrt(A_ticks / (2**(b-1) - 4)) and V_ticks / (2**(b-1) - 2), with
    A = 30 m/s^2 and V = 50 m/s at the rim over the preset's radius and angle per tick."""
    text = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    head = next(line for line in text.splitlines() if line.strip().startswith("| robot | ticks per m at the rim"))
    widths = [int(cell.split()[0]) for cell in head.strip().strip("|").split("|")[2:]]
    rows = [line.strip().strip("|").split("|") for line in text.splitlines() if line.strip().startswith("| ")]
    checked = 0
    for cells in rows:
        name = cells[0].strip()
        if name in ("robot", "---") or not cells[1].strip().isdigit():
            continue
        w = load_robot(name).encoded[0]
        per_m = 1 / (w.radius * abs(w.encoder.rad_per_tick))
        assert int(cells[1]) == round(per_m)
        for b, cell in zip(widths, cells[2:], strict=True):
            h = 2 ** (b - 1)
            rate = 1 / max(math.sqrt((h - 4) / (30.0 * per_m)), (h - 2) / (50.0 * per_m))
            assert cell.strip() == (f"{rate:.2g}" if rate >= 0.1 else "< 0.1"), (name, b, cell)
        checked += 1
    assert checked >= 5


@given(
    st.lists(
        st.tuples(
            st.sampled_from([0.01, 0.01, 0.01, 0.02, 0.005, 0.0, -0.004]),
            st.tuples(*[st.integers(-30, 30)] * 3),
            st.sampled_from([0, 0, 0, 0, 0, 256, -4096, 65536, 9999, 10**6]),
            st.integers(0, 2),
        ),
        min_size=1,
        max_size=25,
    ),
    st.sampled_from([None, 8, 12, 16]),
    st.booleans(),
)
def test_batch_and_streaming_refuse_the_same_sample(steps, bits, floats):
    """Random logs with wraps, jumps, stops, repeated and backward times: batch and streaming
    accept the same logs (with the same poses) and refuse the same first sample, with the same
    message for the counter rules."""
    tomasi = load_robot("tomasi-omni3")
    t, rows = [0.0], [[100, 200, 300]]
    for dt, inc, jump, wheel in steps:
        row = [r + d for r, d in zip(rows[-1], inc, strict=True)]
        row[wheel] += jump
        if dt == 0.0 and row == rows[-1]:
            row[0] += 1  # not a duplicate (streaming skips those, batch refuses them)
        t.append(t[-1] + dt)
        rows.append(row)
    if bits:
        rows = [[v % (1 << bits) for v in r] for r in rows]
    feed = [[float(v) for v in r] for r in rows] if floats else rows
    b = batch_error(tomasi, t, np.array(feed), counter_bits=bits)
    o = Odometry(tomasi, counter_bits=bits)
    s, poses = None, []
    try:
        for k in range(len(t)):
            poses.append(o.update(t[k], feed[k]))
    except OdometryInputError as exc:
        s = exc
    assert (b is None) == (s is None), (b, s)
    if b is None:
        assert_poses_close(poses, batch_odometry(tomasi, t, np.array(feed), counter_bits=bits).poses, atol=1e-12)
        return
    assert b.sample == s.sample, (b, s)
    if b.detail.startswith(("impossible", "tick reading")):
        assert b.detail == s.detail


@pytest.mark.parametrize("kw", [{"max_wheel_speed": 1e4}, {"max_wheel_accel": 1e308}, {"max_wheel_accel": math.inf}])
def test_huge_bounds_are_bounds_not_crashes(tomasi, kw):
    """A bound that overflows to infinity in ticks (1.5e308 rad/s^2 over 0.0105 rad per tick) was
    written into the generated kernel as 'inf', a NameError on the first update (a wheel speed
    is bounded like a robot file's max_speed, at most 1e4 rad/s)."""
    rows, t = [[0, 0, 0], [1, 1, 1], [5, 1, 1], [6, 1, 1]], [0.0, 0.1, 0.2, 0.3]
    expected = tomasi_poses(np.diff(rows, axis=0))
    o = Odometry(tomasi, **kw)
    assert_poses_close([o.update(t[k], rows[k]) for k in range(4)], expected)
    a = Odometry(tomasi, **kw)
    assert_poses_close([a.update_angles(t[k], [v * TOMASI_RPT for v in rows[k]]) for k in range(4)], expected)
    assert_poses_close(batch_odometry(tomasi, t, rows, **kw).poses, expected)
