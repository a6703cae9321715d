"""Regression tests for the review findings (one focused test per item).

Expected values are derived independently of the code under test: closed forms typed in
from the geometry (tomasi-omni3 Jacobian, SE(2) exponential), least squares computed here
with NumPy, or the *batch* odometry as reference for the *streaming* estimator (and a
fresh estimator fed only the valid samples as reference for "state unchanged").
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import omnikin
from omnikin import (Encoder, OdometryInputError, OmnikinError, Odometry, Robot, RobotFileError, Wheel,
                     batch_odometry, batch_odometry_from_angles, load_robot)
from omnikin.cli.main import main

# --- tomasi-omni3 typed in from its robot file (docs/conventions.md rolling row) ------------------------------
TOM_L, TOM_R = 0.113, 0.04125
TOM_RPT = 2 * math.pi / 600
TOM_BETAS = np.radians([0.0, 120.0, 240.0])
TOM_J = np.array([[-math.sin(b), math.cos(b), TOM_L] for b in TOM_BETAS]) / TOM_R
TOM_F = np.linalg.inv(TOM_J)


def se2_step(pose, inc):
    """Pose after the body increment ``inc = (a, b, phi)`` at constant twist (SE(2) exponential)."""
    x, y, th = pose
    a, b, phi = inc
    if abs(phi) < 1e-12:
        k, h = 1.0, th
    else:
        k, h = math.sin(phi / 2) / (phi / 2), th + phi / 2
    th2 = th + phi
    th2 = th2 - 2 * math.pi * math.floor((th2 + math.pi) / (2 * math.pi))
    return (x + k * (math.cos(h) * a - math.sin(h) * b), y + k * (math.sin(h) * a + math.cos(h) * b), th2)


def tomasi_poses(tick_increments):
    """Closed-form poses from the origin for a list of per-interval tick increments (3 wheels)."""
    poses = [(0.0, 0.0, 0.0)]
    for d in tick_increments:
        poses.append(se2_step(poses[-1], TOM_F @ (np.asarray(d, float) * TOM_RPT)))
    return np.array(poses)


def assert_poses_close(actual, expected, atol=1e-12):
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    assert actual.shape == expected.shape
    d = actual - expected
    d[..., 2] = (d[..., 2] + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(d)) <= atol, (actual, expected)


def stream(robot, t, ticks, steer=None, **kw):
    o = Odometry(robot, **kw)
    poses = [o.update(t[k], ticks[k], None if steer is None else steer[k]) for k in range(len(t))]
    return o, np.array(poses, dtype=float)


@pytest.fixture(scope="module")
def tom():
    return load_robot("tomasi-omni3")


@pytest.fixture(scope="module")
def syn():
    return load_robot("synchro")


# --- 1: narrow and unsigned integer readings ---------------------------------------------------------------------
T3 = [0.0, 0.01, 0.02]
INC = [[10, -5, 3], [10, -5, 3]]


@pytest.mark.parametrize("dtype, bits", [(np.int32, 32), (np.int16, 16), (np.int64, 32), (np.int64, None)])
def test_01_narrow_int_readings_batch_and_stream(tom, dtype, bits):
    expected = tomasi_poses(INC)
    tk = np.array([[0, 0, 0], [10, -5, 3], [20, -10, 6]], dtype=dtype)
    assert_poses_close(batch_odometry(tom, T3, tk, counter_bits=bits).poses, expected)
    _, ps = stream(tom, T3, list(tk), counter_bits=bits)   # rows of numpy integer scalars
    assert_poses_close(ps, expected)


@pytest.mark.parametrize("dtype, bits", [(np.int32, 32), (np.int16, 16)])
def test_01_narrow_int_readings_wrap_at_type_limit(tom, dtype, bits):
    """Counters stored in their own width wrap from the largest to the smallest value."""
    top = 2 ** (bits - 1) - 1
    tk = np.array([[top - 4, 0, 0], [-top + 4, -5, 3]], dtype=dtype)   # +10 ticks through the wrap
    expected = tomasi_poses([[10, -5, 3]])
    assert_poses_close(batch_odometry(tom, T3[:2], tk, counter_bits=bits).poses, expected)
    _, ps = stream(tom, T3[:2], list(tk), counter_bits=bits)
    assert_poses_close(ps, expected)


SIGNED = np.array([[5] * 3, [3] * 3, [1] * 3], dtype=np.int64)


@pytest.mark.parametrize("bits", [None, 32])
def test_01_uint32_readings_same_as_signed_batch(tom, bits):
    expected = tomasi_poses([[-2] * 3, [-2] * 3])
    assert_poses_close(batch_odometry(tom, T3, SIGNED, counter_bits=bits).poses, expected)
    assert_poses_close(batch_odometry(tom, T3, SIGNED.astype(np.uint32), counter_bits=bits).poses, expected)


@pytest.mark.parametrize("bits", [None, 32])
def test_01_uint32_readings_same_as_signed_stream(tom, bits):
    expected = tomasi_poses([[-2] * 3, [-2] * 3])
    _, ps = stream(tom, T3, list(SIGNED), counter_bits=bits)
    assert_poses_close(ps, expected)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # numpy overflow warnings of the open bug
        _, ps = stream(tom, T3, list(SIGNED.astype(np.uint32)), counter_bits=bits)
    assert_poses_close(ps, expected)


def test_01_stream_int16_scalars_without_bits_large_span(tom):
    """Without counter_bits readings are plain integers: -30000 -> 30000 is +60000 ticks (over 10 s:
    100 rev in 0.01 s would be an impossible jump)."""
    tk = np.array([[-30000, 0, 0], [30000, 0, 0]], dtype=np.int16)
    expected = tomasi_poses([[60000, 0, 0]])
    assert_poses_close(batch_odometry(tom, [0.0, 10.0], tk).poses, expected, atol=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)   # no overflow in int16 arithmetic
        _, ps = stream(tom, [0.0, 10.0], list(tk))
    assert_poses_close(ps, expected, atol=1e-9)


# --- 2: exactly half the counter range ---------------------------------------------------------------------------
MAXSPEED_YAML = """\
omnikin: 1
name: m
wheels:
  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125, max_speed: 30.0, encoder: {ticks_per_rev: 600}}
  - {name: w2, type: omni, distance: 0.113, angle_deg: 120, radius: 0.04125, max_speed: 30.0, encoder: {ticks_per_rev: 600}}
  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125, max_speed: 30.0, encoder: {ticks_per_rev: 600}}
"""


@pytest.fixture
def maxspeed_robot(tmp_path):
    p = tmp_path / "m.yaml"
    p.write_text(MAXSPEED_YAML)
    return load_robot(p)


@pytest.mark.parametrize("which", ["preset", "max_speed"])
@pytest.mark.parametrize("dt", [0.01, 10.0])
def test_02_half_range_increment_refused(tom, maxspeed_robot, which, dt):
    robot = tom if which == "preset" else maxspeed_robot
    t, tk = [0.0, dt], [[0, 0, 0], [128, 0, 0]]
    with pytest.raises(OdometryInputError):
        batch_odometry(robot, t, tk, counter_bits=8)
    o = Odometry(robot, counter_bits=8)
    o.update(0.0, [0, 0, 0])
    with pytest.raises(OdometryInputError):
        o.update(dt, [128, 0, 0])
    assert o.pose == (0.0, 0.0, 0.0) and o.samples == 1


def test_02_just_below_half_range_accepted(maxspeed_robot):
    """127 ticks in 10 s is within max_speed and below half the 8-bit range: integrated as +127."""
    t, tk = [0.0, 10.0], [[0, 0, 0], [127, 0, 0]]
    expected = tomasi_poses([[127, 0, 0]])
    assert_poses_close(batch_odometry(maxspeed_robot, t, tk, counter_bits=8).poses, expected)
    _, ps = stream(maxspeed_robot, t, tk, counter_bits=8)
    assert_poses_close(ps, expected)


# --- 3: non-finite timestamp in streaming ------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [math.inf, -math.inf, math.nan, np.float64("inf")])
def test_03_stream_nonfinite_time_refused_and_estimator_usable(tom, bad):
    o = Odometry(tom)
    o.update(0.0, [0, 0, 0])
    o.update(0.1, [1, 1, 1])
    before = (o.pose, o.t, o.samples)
    with pytest.raises(OdometryInputError):
        o.update(bad, [2, 2, 2])
    assert (o.pose, o.t, o.samples) == before
    p = o.update(0.2, [2, 2, 2])
    ref = batch_odometry(tom, [0.0, 0.1, 0.2], [[0, 0, 0], [1, 1, 1], [2, 2, 2]]).poses[-1]
    assert_poses_close(p, ref)


# --- 4: steering with extra axes (streaming, steerable) ----------------------------------------------------------
def test_04_stream_steer_extra_axes_refused_state_unchanged(syn):
    o = Odometry(syn)
    o.update(0.0, [0, 0, 0], [0, 0, 0])
    with pytest.raises(OdometryInputError):
        o.update(0.1, [10, 10, 10], [[0, 0, 0], [0.1, 0.1, 0.1]])
    assert o.samples == 1 and o.t == 0.0 and o.pose == (0.0, 0.0, 0.0)
    p = o.update(0.2, [20, 20, 20], [0, 0, 0])
    fresh = Odometry(syn)
    fresh.update(0.0, [0, 0, 0], [0, 0, 0])
    assert p == fresh.update(0.2, [20, 20, 20], [0, 0, 0])
    assert o.residual == fresh.residual


def test_04_stream_steer_extra_axes_refused_at_first_sample(syn):
    o = Odometry(syn)
    with pytest.raises(OdometryInputError):
        o.update(0.0, [0, 0, 0], [[0, 0, 0], [0, 0, 0]])
    assert o.samples == 0 and o.t is None
    o.update(0.0, [0, 0, 0], [0.1, 0.1, 0.1])
    p = o.update(0.1, [10, 10, 10], [0.1, 0.1, 0.1])
    fresh = Odometry(syn)
    fresh.update(0.0, [0, 0, 0], [0.1, 0.1, 0.1])
    assert p == fresh.update(0.1, [10, 10, 10], [0.1, 0.1, 0.1])


# --- 5: same time and ticks, different steering ------------------------------------------------------------------
def test_05_stream_same_t_ticks_different_steer_is_error(syn):
    o = Odometry(syn)
    o.update(0.0, [0, 0, 0], [0, 0, 0])
    o.update(0.1, [10, 10, 10], [0, 0, 0])
    pose = o.pose
    with pytest.raises(OdometryInputError):
        o.update(0.1, [10, 10, 10], [0.5, 0.5, 0.5])
    assert o.duplicates == 0 and o.pose == pose
    with pytest.warns(RuntimeWarning):   # the same steering too: a true duplicate
        o.update(0.1, [10, 10, 10], [0, 0, 0])
    assert o.duplicates == 1


# --- 6: non-numeric readings -------------------------------------------------------------------------------------
@pytest.mark.parametrize("bits", [None, 16])
def test_06_string_readings_at_first_sample_refused(tom, bits):
    o = Odometry(tom, counter_bits=bits)
    with pytest.raises(OdometryInputError):
        o.update(0.0, ["1", "2", "3"])
    assert o.samples == 0 and o.t is None
    o.update(0.0, [1, 2, 3])
    assert_poses_close(o.update(0.01, [11, -3, 6]), tomasi_poses([[10, -5, 3]])[-1])


@pytest.mark.parametrize("bits", [None, 16])
@pytest.mark.parametrize("true", [True, np.bool_(True)], ids=["bool", "np.bool_"])
def test_06_bool_readings_refused_at_first_sample(tom, bits, true):
    o = Odometry(tom, counter_bits=bits)
    with pytest.raises(OdometryInputError):
        o.update(0.0, [true, 0, 0])
    assert o.samples == 0


@pytest.mark.parametrize("bits", [None, 16])
@pytest.mark.parametrize("true", [True, np.bool_(True)], ids=["bool", "np.bool_"])
def test_06_bool_readings_refused_after_first_sample(tom, bits, true):
    o = Odometry(tom, counter_bits=bits)
    o.update(0.0, [0, 0, 0])
    with pytest.raises(OdometryInputError):
        o.update(0.1, [true, 1, 1])
    assert o.samples == 1 and o.pose == (0.0, 0.0, 0.0)


def test_06_batch_bool_readings_refused(tom):
    with pytest.raises(OdometryInputError):
        batch_odometry(tom, [0.0, 0.1], np.array([[False] * 3, [True] * 3]))


# --- 7: max_jump validation --------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [math.inf, math.nan, -1, 0, 0.0, True])
def test_07_bad_max_jump_refused_at_construction(tom, bad):
    with pytest.raises(OmnikinError):
        Odometry(tom, max_jump=bad)


@pytest.mark.parametrize("bad", [math.inf, math.nan, -1, 0])
def test_07_batch_bad_max_jump_refused(tom, bad):
    with pytest.raises(OmnikinError):
        batch_odometry(tom, [0, 0.1], [[0, 0, 0], [10 ** 9, 1, 1]], max_jump=bad)


# --- 8: residual parity streaming vs batch -----------------------------------------------------------------------
def omni4_rows():
    betas = np.radians([45, 135, 225, 315])
    return np.array([[-math.sin(b), math.cos(b), 0.2] for b in betas]) / 0.05


def lstsq_residual(a, b):
    x = np.linalg.lstsq(a, b, rcond=None)[0]
    return b - a @ x


def test_08_omni4_float_ticks_counter_bits_residual_parity():
    o4 = load_robot("omni4")
    t, tk = [0.0, 0.1], [[0.0, 0, 0, 0], [100.0, 0, 0, 0]]
    rpt = 2 * math.pi / 2048
    expected = lstsq_residual(omni4_rows(), np.array([100.0, 0, 0, 0]) * rpt / 0.1)
    assert np.max(np.abs(expected)) > 0.1   # one wheel turning alone is inconsistent
    b = batch_odometry(o4, t, tk, counter_bits=16)
    np.testing.assert_allclose(b.residual[-1], expected, rtol=1e-9, atol=1e-9)
    o, ps = stream(o4, t, tk, counter_bits=16)
    np.testing.assert_allclose(o.residual, b.residual[-1], rtol=1e-12, atol=1e-12)
    assert_poses_close(ps, b.poses)


def dd_side_robot():
    enc = Encoder(1000)
    return Robot("dd+omni", (
        Wheel("left", "standard", 0.0, 0.165, 0.0, 0.08, encoder=enc),
        Wheel("right", "standard", 0.0, -0.165, 0.0, 0.08, encoder=enc),
        Wheel("side", "omni", 0.3, 0.0, math.pi / 2, 0.03, encoder=enc)))


@pytest.mark.parametrize("ticks", [[0, 0, 50], [10, 30, -20]])
def test_08_diff_drive_plus_side_omni_residual_parity(ticks):
    r = dd_side_robot()
    t, tk = [0.0, 0.1], [[0, 0, 0], ticks]
    rates = np.array(ticks) * (2 * math.pi / 1000) / 0.1
    # vy = 0 imposed by the fixed wheels; unknowns (vx, omega); rows typed in from the geometry
    a = np.array([[1 / 0.08, -0.165 / 0.08], [1 / 0.08, 0.165 / 0.08], [0.0, 0.3 / 0.03]])
    expected = lstsq_residual(a, rates)
    assert np.max(np.abs(expected)) > 0.1
    b = batch_odometry(r, t, tk)
    np.testing.assert_allclose(b.residual[-1], expected, rtol=1e-9, atol=1e-9)
    o, ps = stream(r, t, tk)
    np.testing.assert_allclose(o.residual, expected, rtol=1e-9, atol=1e-9)
    assert_poses_close(ps, b.poses)


# --- 9: off-centred steering without a steady angle ----------------------------------------------------------------
def test_09_villasenor_pure_rotation_returned_as_infeasible():
    v = load_robot("villasenor-omni3")
    # a pure rotation about the origin has no steady swivel angle where offset > |p| (hub too slow)
    expected = [w.offset > math.hypot(w.x, w.y) for w in v.steerable]
    assert any(expected)
    res = v.ik([0, 0, 1.0], on_infeasible="return")
    assert not bool(res.feasible)
    assert res.steer_limited.tolist() == expected
    with pytest.raises(omnikin.InfeasibleTwistError):
        v.ik([0, 0, 1.0])


def test_09_cli_villasenor_allow_infeasible(capsys):
    assert main(["ik", "villasenor-omni3", "0", "0", "1", "--allow-infeasible", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["feasible"] is False
    v = load_robot("villasenor-omni3")
    assert data["steer_limited"] == [w.offset > math.hypot(w.x, w.y) for w in v.steerable]


# --- 10: Ackermann steering limits named as the cause ----------------------------------------------------------------
def test_10_cli_ackermann_spin_json(capsys):
    assert main(["ik", "ackermann", "0", "0", "1", "--allow-infeasible", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["feasible"] is False
    # front hubs at (0.6, +-0.25) move along (-+0.25, 0.6): 67.4 deg off the axis either way, limit 35 deg
    assert data["steer_names"] == ["front_left", "front_right"]
    assert data["steer_limited"] == [True, True]
    # the rear axle sits at the centre of rotation: no side slip
    assert np.allclose(data["violation"], 0.0, atol=1e-12)


def test_10_cli_ackermann_spin_text_names_steering(capsys):
    assert main(["ik", "ackermann", "0", "0", "1", "--allow-infeasible"]) == 0
    out = capsys.readouterr().out
    verdict = [ln for ln in out.splitlines() if ln.startswith("infeasible")]
    assert len(verdict) == 1
    assert "steering" in verdict[0] and "front_left" in verdict[0] and "front_right" in verdict[0]
    assert "slide" not in out and "side slip" not in out


# --- 11: 1-D steering in batch -----------------------------------------------------------------------------------------
def test_11_batch_1d_steer_refused_with_shape_message(syn):
    with pytest.raises(OdometryInputError, match=r"steer.*shape"):
        batch_odometry(syn, [0, 0.1], [[0, 0, 0], [1, 1, 1]], steer=[0, 0, 0])


# --- 12: steering for a robot without steerable wheels ---------------------------------------------------------------
def test_12_steer_on_non_steerable_robot_refused(tom):
    with pytest.raises(OmnikinError):
        batch_odometry(tom, [0, 0.1], [[0, 0, 0], [1, 1, 1]], steer=[[0.0], [0.0]])
    with pytest.raises(OmnikinError):
        batch_odometry(tom, [0, 0.1], [[0, 0, 0], [1, 1, 1]], steer=[[np.nan]])
    with pytest.raises(OmnikinError):
        tom.fk([1, 2, 3], steer=[0.0, 1.0])
    with pytest.raises(OmnikinError):
        tom.ik([1, 0, 0], steer_hint=[0.0])
    with pytest.raises(OmnikinError):
        tom.ik([1, 0, 0], steer_hint=[np.nan] * 7)


# --- 13: angle inputs of the wrong length ---------------------------------------------------------------------------
def test_13_batch_from_angles_timestamps_must_match(tom):
    with pytest.raises(OdometryInputError):
        batch_odometry_from_angles(tom, [0, 0.1, 0.2, 0.3, 0.4], [[0, 0, 0], [1, 1, 1], [2, 2, 2]])


def test_13_update_angles_wrong_count(tom):
    o = Odometry(tom)
    with pytest.raises(OdometryInputError):
        o.update_angles(0.0, [0, 0, 0, 99])
    assert o.samples == 0
    o.update_angles(0.0, [0.0, 0.0, 0.0])
    with pytest.raises(OdometryInputError):
        o.update_angles(0.1, [1.0, 1.0, 1.0, 123.0])
    assert o.samples == 1


# --- 14: CLI line numbers after skipped duplicate rows -------------------------------------------------------------
def test_14_cli_names_file_line_after_duplicates(tmp_path, capsys):
    log = tmp_path / "log.csv"
    lines = [
        "t,w1,w2,w3",          # 1
        "# logger v1",         # 2
        "0.0,0,0,0",           # 3
        "0.1,10,10,10",        # 4
        "0.1,10,10,10",        # 5 duplicate
        "",                    # 6
        "0.1,10,10,10",        # 7 duplicate
        "0.2,20,20,20",        # 8
        "0.15,30,30,30",       # 9 time goes back
    ]
    log.write_text("\n".join(lines) + "\n")
    rc = main(["odometry", "tomasi-omni3", str(log), "-o", str(tmp_path / "out.csv")])
    assert rc == 2
    err = capsys.readouterr().err
    error_lines = [ln for ln in err.splitlines() if ln.startswith("omnikin: error:")]
    assert len(error_lines) == 1
    assert "line 9" in error_lines[0]
    for wrong in ("line 5", "line 6", "line 7", "line 8"):
        assert wrong not in error_lines[0]


# --- 15: wheel validation ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kw", [{"radius": 0.0}, {"x": math.nan}, {"type": "omny"}, {"radius": 1e-320},
                                {"radius": -0.05}, {"y": math.inf}])
def test_15_wheel_validation(kw):
    args = {"name": "a", "type": "omni", "x": 0.1, "y": 0.0, "drive": math.pi / 2, "radius": 0.05}
    args.update(kw)
    with pytest.raises(OmnikinError):
        Wheel(**args)


@pytest.mark.parametrize("first", ["x: 0.1, y: 0, radius: 1.0e-320", "x: 1.0e+308, y: 1.0e+308, radius: 0.05"])
def test_15_show_extreme_robot_file_one_line_error(tmp_path, capsys, first):
    p = tmp_path / "r.yaml"
    p.write_text("omnikin: 1\nname: r\nwheels:\n"
                 f"  - {{name: a, type: omni, {first}, encoder: {{ticks_per_rev: 100}}}}\n"
                 "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 0.05}\n"
                 "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n")
    assert main(["show", str(p)]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("omnikin: error:")
    assert "Traceback" not in cap.err


# --- 16: 64-bit counters ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("before, after", [(2 ** 60, 2 ** 60 + 1), (2 ** 63 - 1, -(2 ** 63))])
def test_16_counter_bits_64_single_tick(tom, before, after):
    expected = tomasi_poses([[1, 0, 0]])
    tk = np.array([[before, 7, -7], [after, 7, -7]], dtype=np.int64)
    assert_poses_close(batch_odometry(tom, T3[:2], tk, counter_bits=64).poses, expected)
    _, ps = stream(tom, T3[:2], [[before, 7, -7], [after, 7, -7]], counter_bits=64)   # Python ints
    assert_poses_close(ps, expected)
    _, ps = stream(tom, T3[:2], list(tk), counter_bits=64)                             # numpy int64 scalars
    assert_poses_close(ps, expected)


# --- 17: robot-file parsing ----------------------------------------------------------------------------------------------
def test_17_duplicate_key_yaml_refused(tmp_path):
    p = tmp_path / "dup.yaml"
    p.write_text("omnikin: 1\nname: r\nwheels:\n"
                 "  - {name: a, type: omni, x: 0.1, y: 0, radius: 0.05, radius: -1}\n"
                 "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 0.05}\n"
                 "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n")
    with pytest.raises(RobotFileError, match=r"duplicate key.*radius"):
        load_robot(p)


def test_17_duplicate_key_json_refused(tmp_path):
    p = tmp_path / "dup.json"
    p.write_text('{"omnikin": 1, "name": "r", "wheels": [{"name": "a", "type": "omni", "x": 0.1, "y": 0,'
                 ' "radius": 0.05, "radius": 0.06}]}')
    with pytest.raises(RobotFileError, match=r"duplicate key.*radius"):
        load_robot(p)


def test_17_yaml_exponent_without_dot_is_a_number(tmp_path):
    p = tmp_path / "exp.yaml"
    p.write_text("omnikin: 1\nname: r\nwheels:\n"
                 "  - {name: a, type: omni, distance: 1e-1, angle_deg: 0, radius: 5e-2}\n"
                 "  - {name: b, type: omni, distance: 0.1, angle_deg: 120, radius: 5E-2}\n"
                 "  - {name: c, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n")
    r = load_robot(p)
    assert [w.radius for w in r.wheels] == [0.05, 0.05, 0.05]
    assert r.wheels[0].x == 0.1


# --- 18: heading exactly one ulp below -pi ----------------------------------------------------------------------------
@pytest.mark.parametrize("bits", [None, 16], ids=["fast-path", "general-path"])
def test_18_stream_heading_one_ulp_below_minus_pi_wraps_into_range(tom, bits):
    target = np.nextafter(-math.pi, -math.inf)     # -pi - 1 ulp
    tk = [[0.0, 0.0, 0.0], [-0.3, -0.3, -0.3]]     # pure rotation, phi ~ -1e-3 rad (float ticks)
    probe = Odometry(tom, counter_bits=bits)       # the exact float phi this estimator computes
    probe.update(0.0, tk[0])
    phi = probe.update(0.1, tk[1])[2]
    assert -0.01 < phi < 0.0
    th0 = target - phi
    for _ in range(8):                             # start heading whose sum with phi lands on target
        if th0 + phi == target:
            break
        th0 = np.nextafter(th0, -math.inf) if th0 + phi > target else np.nextafter(th0, math.inf)
    if th0 + phi != target:
        pytest.skip("no start heading lands exactly on -pi - 1 ulp")
    o = Odometry(tom, counter_bits=bits, start=(0.0, 0.0, float(th0)))
    assert o.pose[2] == th0
    o.update(0.0, tk[0])
    th = o.update(0.1, tk[1])[2]
    assert -math.pi <= th < math.pi
    assert abs(th - math.pi) < 1e-15            # -pi - 1 ulp is the same direction as pi - 1 ulp


# --- second review: runtime, ROS parameters, bags and CLI ------------------------------------------------
from omnikin.cli.main import main as cli_main  # noqa: E402


def run_cli(capsys, *argv):
    rc = cli_main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.parametrize("content, fragment", [
    (b"\xff\xfe", "not a UTF-8 text file"),
    (b"omnikin_base: {ros__parameters: 5}\n", "ros__parameters must be a mapping"),
    (b"publish_rate: 0.0\n", "publish_rate"),
    (b"reject_above: -1.0\n", "reject_above"),
    (b"bogus: 1\n", "unknown parameter 'bogus'"),
])
def test_ros_parameter_files_bad(tmp_path, content, fragment):
    from omnikin.ros.params import load_params

    p = tmp_path / "p.yaml"
    p.write_bytes(content)
    with pytest.raises(OmnikinError, match=fragment):
        load_params(p)


def test_ros_parameter_exponent_floats(tmp_path):
    """YAML 1.1 reads 2e-4 as a string; the documented default must load as a number."""
    from omnikin.ros.params import load_params

    p = tmp_path / "p.yaml"
    p.write_text("wheel_slip: 2e-4\nlinear:\n  x:\n    max_velocity: 5E-1\n")
    values = load_params(p)
    assert values["wheel_slip"] == 2e-4 and values["linear.x.max_velocity"] == 0.5


def test_ros_serial_only_options_with_sim_backend(capsys):
    rc, _, err = run_cli(capsys, "ros", "tomasi-omni3", "--port", "/dev/ttyUSB0")
    assert rc == 2 and "apply only to --backend serial" in err


def test_simulate_refuses_absurd_plans_and_stamps(capsys, tmp_path):
    pytest.importorskip("rosbags")
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--path", "spin 1e300", "--bag", tmp_path / "a.bag")
    assert rc == 2 and "samples" in err
    rc, _, err = run_cli(capsys, "simulate", "tomasi-omni3", "--start", "3e9", "--bag", tmp_path / "b.bag")
    assert rc == 2 and "int32" in err


def test_bag_topic_names_are_checked(capsys, tmp_path):
    pytest.importorskip("rosbags")
    rc, _, err = run_cli(capsys, "bag", "odometry", "tomasi-omni3", tmp_path / "in.bag", "-o", tmp_path / "o.bag",
                         "--odom-topic", "bad topic!!")
    assert rc == 2 and "not a valid ROS 2 topic name" in err


def test_borenstein_degenerate_input_is_an_error():
    from omnikin.evaluation.umbmark import borenstein

    with pytest.raises(OmnikinError, match="undefined"):
        borenstein(-1.0, 1.0, 1e-300, 0.33)


def test_lever_is_the_displacement_component_along_its_direction():
    """The lever is the hub displacement along (-sin a, cos a), a = drive + roller; the calibrate
    table shows that component (it used to show a magnitude with the sign of dx)."""
    import math as _m

    from omnikin.evaluation.calibration import errors_from_vector, parameter_names

    robot = load_robot("tomasi-omni3")
    names = parameter_names(robot)
    p = np.zeros(len(names))
    p[names.index("w1.lever")] = -0.0004
    e = errors_from_vector(robot, p).wheels["w1"]
    w = robot.wheel("w1")
    a = w.drive + w.roller
    assert -_m.sin(a) * e.dx + _m.cos(a) * e.dy == pytest.approx(-0.0004, abs=1e-15)


def test_metrics_messages_show_plain_numbers():
    from omnikin.evaluation.metrics import check_trajectory

    with pytest.raises(OmnikinError) as exc:
        check_trajectory([0.0, 1.0, 1.0], np.zeros((3, 3)))
    assert "np.float64" not in str(exc.value)


# =====================================================================================================
# third review (runtime speed-up, link re-arm, bag tools)
# =====================================================================================================
def test_halt_then_command_keeps_the_acceleration_limit():
    """After halt() (link re-armed after an outage) a command must ramp up from rest at the
    acceleration limit, not jump across the outage as one long time step."""
    from omnikin.runtime.command import CommandFilter
    from omnikin.limits import MotionLimits

    f = CommandFilter(load_robot("tomasi-omni3"), MotionLimits(linear=1.0, linear_accel=0.5), timeout=0.0)
    f.command((0.2, 0.0, 0.0), 0.0)
    for k in range(1, 100):
        f.update(0.01 * k)                       # up to speed
    f.halt()                                     # the link was lost at t = 0.99 and re-armed at 2.0
    f.command((0.2, 0.0, 0.0), 2.0)
    first = f.update(2.0)
    second = f.update(2.01)
    assert first[0] == 0.0
    assert second[0] == pytest.approx(0.5 * 0.01, abs=1e-12)     # a_max * dt, from rest


def test_replaced_limits_apply_to_the_current_command():
    from dataclasses import replace

    from omnikin.runtime.command import CommandFilter
    from omnikin.limits import MotionLimits

    f = CommandFilter(load_robot("tomasi-omni3"), MotionLimits(linear=1.0, linear_accel=None), timeout=0.0)
    f.command((0.8, 0.0, 0.0), 0.0)
    assert f.update(0.0)[0] == pytest.approx(0.8)
    f.limits = replace(f.limits, linear=0.3)
    assert f.update(0.01)[0] == pytest.approx(0.3)


def test_copied_robot_cannot_corrupt_cached_matrices():
    """Pickle and deepcopy drop the read-only caches; the copy rebuilds its own, still read-only."""
    import copy
    import pickle

    robot = load_robot("omni4")
    robot.jacobian(), robot.fk_matrix(), robot.fk_matrix(None, ["w1", "w2", "w3"])
    for clone in (copy.deepcopy(robot), pickle.loads(pickle.dumps(robot))):
        jac = clone.jacobian()
        with pytest.raises(ValueError):
            jac *= 2
        with pytest.raises(ValueError):
            clone.fk_matrix()[0, 0] = 1.0
        np.testing.assert_array_equal(clone.jacobian(), robot.jacobian())


def test_fk_matrix_accepts_any_iterable_of_wheel_names():
    robot = load_robot("omni4")
    ref = np.linalg.pinv(robot.jacobian()[:3])
    np.testing.assert_allclose(robot.fk_matrix(None, (n for n in ["w1", "w2", "w3"])), ref, atol=1e-12)
    np.testing.assert_allclose(robot.fk_matrix(None, np.array(["w1", "w2", "w3"])), ref, atol=1e-12)


def test_zero_wheel_limit_with_zero_twist_is_not_nan():
    from omnikin.limits import MotionLimits, saturate, speed_scale

    wheels = tuple(Wheel(f"w{i}", "omni", 0.1 * math.cos(a), 0.1 * math.sin(a), a + math.pi / 2, 0.03,
                         max_speed=0.0 if i == 0 else None) for i, a in enumerate(TOM_BETAS))
    robot = Robot("zero-limit", wheels)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert speed_scale(robot, [0.0, 0.0, 0.0], MotionLimits()) == np.inf
        np.testing.assert_array_equal(saturate(robot, [0.0, 0.0, 0.0], MotionLimits()), [0.0, 0.0, 0.0])


def test_reconnect_after_close_is_refused(tmp_path):
    pytest.importorskip("serial")
    from omnikin.runtime.fake_controller import FakeController
    from omnikin.runtime.serial_backend import SerialBackend

    robot = load_robot("tomasi-omni3")
    with FakeController.for_robot(robot) as fake:
        backend = SerialBackend(robot, fake.path)
        backend.close()
        with pytest.raises(OmnikinError, match="closed"):
            backend.reconnect()


def test_metrics_of_one_kitti_file_against_itself(tmp_path, capsys):
    from omnikin.io.trajectories import write_trajectory

    t = np.arange(20) * 0.1
    write_trajectory(tmp_path / "a.kitti", t, np.column_stack([t, t, 0 * t]), "kitti")
    assert main(["metrics", str(tmp_path / "a.kitti"), str(tmp_path / "a.kitti"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ate"]["translation"]["rmse"] == 0.0


def test_round_off_is_not_written_as_negative_zero(tmp_path):
    from omnikin.io.trajectories import trajectory_lines

    poses = [[-1e-12, -4e-10, -1e-14], [1.0, 0.0, 0.0]]
    for fmt in ("csv", "tum"):
        text = "\n".join(trajectory_lines([0.0, 1.0], poses, fmt))
        assert "-0.000" not in text, (fmt, text)
