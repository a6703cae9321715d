"""Simulation layer: motion plans and their timing, saturation, error models, simulated runs.

Expected values are derived here, independently of the library: SE(2) motions are
composed with the closed form of constant-twist motion written below, wheel speeds of
tomasi-omni3 use the radial-axle row of docs/conventions.md
(``omega_i = (-sin b_i vx + cos b_i vy + l omega) / r``), and the effect of a single
systematic error is worked out by hand for each case (see each test's docstring).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import OmnikinError, load_robot
from omnikin.motion.limits import MotionLimits, saturate
from omnikin.motion.plans import arc, line, polyline, spin, umbmark_square
from omnikin.motion.timing import sample_plan
from omnikin.simulation.error_models import NOISE, PROFILES, NoiseModel, SystematicErrors, WheelErrors
from omnikin.simulation.kinematic import simulate_kinematic

TOMASI_L, TOMASI_R = 0.113, 0.04125
TOMASI_BETAS = np.radians([0.0, 120.0, 240.0])
DIFF_TRACK, DIFF_R = 0.33, 0.0825
EXACT = NoiseModel(quantise=False)  # no random error at all, ticks not rounded
ROBOTS = ("tomasi-omni3", "diff-drive", "mecanum4")


# --- closed forms written for the tests ---------------------------------------------------------------
def wrap(a):
    return (np.asarray(a, dtype=float) + math.pi) % (2 * math.pi) - math.pi


def twist_motion(xi, s):
    """Pose reached from the origin by moving with body twist ``xi`` per unit progress for progress ``s``."""
    vx, vy, w = (float(v) * s for v in xi)
    if w == 0.0:
        return np.array([vx, vy, 0.0])
    return np.array(
        [(vx * math.sin(w) - vy * (1 - math.cos(w))) / w, (vx * (1 - math.cos(w)) + vy * math.sin(w)) / w, w]
    )


def comp(a, b):
    """Pose a followed by the body-frame motion b (heading not wrapped)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def poses_after_segments(plan, scale=(1.0, 1.0, 1.0)):
    """Pose after each segment of ``plan`` (each segment's twist scaled component-wise)."""
    pose, out = np.zeros(3), []
    for seg in plan.segments:
        pose = comp(pose, twist_motion(np.array(seg.xi) * np.array(scale), seg.length))
        out.append(pose)
    return np.array(out)


def integrate_increments(inc):
    """Exact SE(2) integration of body increments ``(N, 3)`` (constant twist over each); poses ``(N + 1, 3)``."""
    a, b, phi = inc[:, 0], inc[:, 1], inc[:, 2]
    small = np.abs(phi) < 1e-6
    ps = np.where(small, 1.0, phi)
    s_over = np.where(small, 1 - phi**2 / 6, np.sin(ps) / ps)
    c_over = np.where(small, phi / 2 - phi**3 / 24, (1 - np.cos(ps)) / ps)
    lx, ly = s_over * a - c_over * b, c_over * a + s_over * b
    heading = np.concatenate([[0.0], np.cumsum(phi)])
    h0 = heading[:-1]
    wx, wy = np.cos(h0) * lx - np.sin(h0) * ly, np.sin(h0) * lx + np.cos(h0) * ly
    return np.column_stack([np.concatenate([[0.0], np.cumsum(wx)]), np.concatenate([[0.0], np.cumsum(wy)]), heading])


def tomasi_wheel_speeds(t):
    t = np.asarray(t, dtype=float)
    return np.stack(
        [(-math.sin(b) * t[..., 0] + math.cos(b) * t[..., 1] + TOMASI_L * t[..., 2]) / TOMASI_R for b in TOMASI_BETAS],
        axis=-1,
    )


def assert_pose(got, expected, tol):
    got, expected = np.asarray(got, float), np.asarray(expected, float)
    assert np.max(np.abs(got[..., :2] - expected[..., :2])) <= tol, (got, expected)
    assert np.max(np.abs(wrap(got[..., 2] - expected[..., 2]))) <= tol, (got, expected)


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot(name) for name in ROBOTS}


@pytest.fixture(scope="module")
def tomasi_limited(tmp_path_factory):
    """tomasi-omni3 with a wheel max_speed that binds for 0.3 m/s translations and 1 rad/s spins."""
    path = tmp_path_factory.mktemp("robots") / "tomasi-limited.yaml"
    wheels = "\n".join(
        f"  - {{name: w{i + 1}, type: omni, distance: {TOMASI_L}, angle_deg: {a}, radius: {TOMASI_R}, "
        f"encoder: {{ticks_per_rev: 600}}, max_speed: {ms}}}"
        for i, (a, ms) in enumerate(zip((0, 120, 240), (4.0, 4.5, 2.5), strict=True))
    )
    path.write_text(f"omnikin: 1\nname: tomasi-limited\nwheels:\n{wheels}\n", encoding="utf-8")
    return load_robot(path)


# =====================================================================================================
# motion
# =====================================================================================================
CORNERS = {"cw": [(4, 0), (4, -4), (0, -4), (0, 0)], "ccw": [(4, 0), (4, 4), (0, 4), (0, 0)]}


@pytest.mark.parametrize("mode", ["rotate", "translate"])
@pytest.mark.parametrize("direction", ["cw", "ccw"])
def test_umbmark_square_corners_and_end(direction, mode):
    plan = umbmark_square(direction, 4.0, mode)
    assert_pose(plan.end_pose(), [0, 0, 0], 1e-12)
    poses = poses_after_segments(plan)
    legs = [k for k, s in enumerate(plan.segments) if s.xi[2] == 0.0]
    assert len(legs) == 4
    np.testing.assert_allclose(poses[legs, :2], CORNERS[direction], atol=1e-12)
    turn = -1 if direction == "cw" else 1
    if mode == "rotate":
        # every leg along body x, each followed by a -+90 deg turn in place
        assert len(plan.segments) == 8
        for k in range(4):
            assert plan.segments[2 * k].xi == (1.0, 0.0, 0.0) and plan.segments[2 * k].length == 4.0
            assert plan.segments[2 * k + 1].xi == (0.0, 0.0, turn)
            assert plan.segments[2 * k + 1].length == pytest.approx(math.pi / 2, abs=1e-15)
        np.testing.assert_allclose(wrap(poses[1::2, 2]), wrap(turn * np.pi / 2 * np.arange(1, 5)), atol=1e-12)
        # the first leg runs along +x from the start
        np.testing.assert_allclose(poses[0], [4, 0, 0], atol=1e-15)
    else:
        assert len(plan.segments) == 4
        np.testing.assert_allclose(poses[:, 2], 0.0, atol=0)


def test_umbmark_square_side_scales():
    for direction in ("cw", "ccw"):
        poses = poses_after_segments(umbmark_square(direction, 2.5, "rotate"))[0::2, :2]
        np.testing.assert_allclose(poses, np.array(CORNERS[direction]) * 2.5 / 4, atol=1e-12)


@pytest.mark.parametrize(
    "bad", [dict(direction="left"), dict(mode="slide"), dict(side=0.0), dict(side=-4.0), dict(side=float("nan"))]
)
def test_umbmark_square_bad_arguments(bad):
    with pytest.raises(OmnikinError):
        umbmark_square(**{"direction": "cw", "side": 4.0, "mode": "rotate", **bad})


def test_end_pose_line_spin_arc_polyline():
    assert_pose(line(3.0).end_pose(), [3, 0, 0], 1e-15)
    assert_pose(line(2.0, 0.3).end_pose(), [2 * math.cos(0.3), 2 * math.sin(0.3), 0], 1e-15)
    assert_pose(line(-1.5, 0.7).end_pose(), [-1.5 * math.cos(0.7), -1.5 * math.sin(0.7), 0], 1e-15)
    assert_pose(spin(1.0).end_pose(), [0, 0, 1.0], 1e-15)
    assert_pose(spin(-2.5).end_pose(), [0, 0, -2.5], 1e-15)
    assert_pose(spin(4.0).end_pose(), [0, 0, 4.0 - 2 * math.pi], 1e-12)
    # arc of radius R by angle a: centre (0, R) on the left for a > 0, on the right for a < 0
    for radius, a in ((2.0, 1.0), (0.5, 2.5), (2.0, -1.0), (1.3, -3.0)):
        expected = [radius * math.sin(abs(a)), math.copysign(radius * (1 - math.cos(a)), a), a]
        assert_pose(arc(radius, a).end_pose(), expected, 1e-12)
    # polyline: rotate mode ends with the heading of the last leg, translate mode keeps heading 0
    assert_pose(polyline([(1, 0), (1, 1), (0, 1)], "rotate").end_pose(), [0, 1, math.pi], 1e-12)
    assert_pose(polyline([(1, 0), (1, 1), (0, 1)], "translate").end_pose(), [0, 1, 0], 1e-12)
    assert_pose(polyline([(3, 4)], "rotate").end_pose(), [3, 4, math.atan2(4, 3)], 1e-12)
    assert_pose(polyline([(3, 4), (3, 4), (-1, 1)], "translate").end_pose(), [-1, 1, 0], 1e-12)
    # a plan made of plans: line 2, turn left 90 deg, line 1 -> (2, 1, pi/2)
    assert_pose((line(2.0) + spin(math.pi / 2) + line(1.0)).end_pose(), [2, 1, math.pi / 2], 1e-12)
    with pytest.raises(OmnikinError):
        arc(0.0, 1.0)
    with pytest.raises(OmnikinError):
        polyline([(0, 0)])


def test_end_pose_matches_segment_composition():
    plan = umbmark_square("ccw", 4.0, "translate") + arc(1.0, 1.0) + spin(-2.0) + line(0.5, 0.7) + arc(0.7, -2.0)
    assert_pose(plan.end_pose(), poses_after_segments(plan)[-1], 1e-12)


# --- sampling under limits -----------------------------------------------------------------------------
MIXED = (
    umbmark_square("ccw", 4.0, "translate")
    + umbmark_square("cw", 2.0, "rotate")
    + arc(1.0, 1.0)
    + spin(-2.0)
    + line(0.5, 0.7)
    + arc(0.7, -2.0)
    + line(0.003)
    + spin(0.001)
)


def _sample_twists(sp):
    dt = 1.0 / sp.rate
    return sp.xi[sp.segment] * (sp.progress / dt)[:, None]


def check_sampled(sp, plan, robot, limits, wheel_bounds=None):
    dt = 1.0 / sp.rate
    n = len(sp.progress)
    np.testing.assert_allclose(sp.t, np.arange(n + 1) * dt, rtol=0, atol=1e-9)
    assert sp.segment.shape == (n,) and sp.progress.shape == (n,)
    assert np.all(sp.progress >= 0)
    # segments in order, each a contiguous block of whole samples: no sample spans two segments
    assert np.all(np.diff(sp.segment) >= 0)
    assert set(sp.segment.tolist()) == set(range(len(plan.segments)))
    np.testing.assert_array_equal(sp.xi, np.array([s.xi for s in plan.segments]))
    for k, seg in enumerate(plan.segments):
        assert np.sum(sp.progress[sp.segment == k]) == pytest.approx(seg.length, rel=1e-12, abs=1e-15)

    tw = _sample_twists(sp)
    v = np.hypot(tw[:, 0], tw[:, 1])
    w = np.abs(tw[:, 2])
    tol = 1 + 1e-9
    assert np.all(v <= limits.linear * tol)
    assert np.all(w <= limits.angular * tol)
    if wheel_bounds is not None:
        speeds = np.abs(robot.ik(tw).wheel_speeds)
        assert np.all(speeds <= wheel_bounds * tol), speeds.max(axis=0)
    # acceleration: sample-mean velocities of consecutive samples differ by at most a dt
    # (also across segment boundaries, where the body is at rest)
    padded = np.vstack([np.zeros(3), tw, np.zeros(3)])
    dv = np.diff(padded, axis=0)
    assert np.all(np.hypot(dv[:, 0], dv[:, 1]) <= limits.linear_accel * dt * tol)
    assert np.all(np.abs(dv[:, 2]) <= limits.angular_accel * dt * tol)
    # each segment starts and ends at rest: the first and last sample of a segment cover at most
    # the distance of a start from rest under the acceleration limit (a dt^2 / 2, a dt / 2 in mean speed)
    starts = np.flatnonzero(np.diff(np.concatenate([[-1], sp.segment])))
    ends = np.concatenate([starts[1:] - 1, [n - 1]])
    for idx in (starts, ends):
        assert np.all(v[idx] <= 0.5 * limits.linear_accel * dt * tol)
        assert np.all(w[idx] <= 0.5 * limits.angular_accel * dt * tol)
    # exact integration of the increments reaches the plan's end pose (and every segment's end)
    poses = integrate_increments(sp.increments)
    assert_pose(poses[-1], plan.end_pose(), 1e-9)
    assert_pose(poses[ends + 1], poses_after_segments(plan), 1e-9)
    return tw


@pytest.mark.parametrize("rate", [10.0, 100.0])
def test_sample_plan_keeps_body_limits(robots, rate):
    limits = MotionLimits(linear=0.3, angular=1.0, linear_accel=0.5, angular_accel=2.0)
    sp = sample_plan(MIXED, robots["tomasi-omni3"], rate, limits)
    tw = check_sampled(sp, MIXED, robots["tomasi-omni3"], limits)
    # the limits are reached on the long legs, not undercut
    assert np.max(np.hypot(tw[:, 0], tw[:, 1])) == pytest.approx(0.3, rel=1e-9)
    assert np.max(np.abs(tw[:, 2])) == pytest.approx(1.0, rel=1e-9)


def test_sample_plan_trapezoid_closed_form(robots):
    """A 4 m leg at 0.3 m/s, 0.5 m/s^2: 0.6 s ramps, 12.7333 s cruise -> 13.9333 s = 1394 samples at 100 Hz;
    a 90 deg spin at 1 rad/s, 2 rad/s^2: 0.5 s ramps, (pi/2 - 0.5) s cruise -> 207.08 -> 208 samples."""
    sp = sample_plan(umbmark_square("cw"), robots["tomasi-omni3"], 100.0, MotionLimits())
    counts = np.bincount(sp.segment)
    np.testing.assert_array_equal(counts, [1394, 208] * 4)
    first = sp.progress[sp.segment == 0]
    np.testing.assert_allclose(first[:3], 0.5 * 0.5 * (np.array([1, 4, 9]) - [0, 1, 4]) * 1e-4, rtol=1e-12)


@pytest.mark.parametrize("rate", [10.0, 100.0])
def test_sample_plan_keeps_wheel_max_speed(tomasi_limited, rate):
    limits = MotionLimits(linear=0.3, angular=1.0, linear_accel=0.5, angular_accel=2.0)
    bounds = np.array([4.0, 4.5, 2.5])
    sp = sample_plan(MIXED, tomasi_limited, rate, limits)
    tw = check_sampled(sp, MIXED, tomasi_limited, limits, bounds)
    # the robot's own ik agrees with the closed-form rows of the radial-axle omni wheel
    np.testing.assert_allclose(tomasi_limited.ik(tw).wheel_speeds, tomasi_wheel_speeds(tw), rtol=1e-12, atol=1e-12)
    # on the first (4 m, +x) leg the wheel limit binds and is reached:
    # |omega_i| = |sin b_i| v / r, worst ratio to the bound is w3 (2.5 rad/s) -> v = 2.5 r / sin 60
    leg = tw[sp.segment == 0]
    assert np.max(leg[:, 0]) == pytest.approx(2.5 * TOMASI_R / math.sin(math.radians(60)), rel=1e-9)
    # MotionLimits.wheel applies too, whichever is smaller
    limits2 = MotionLimits(linear=0.3, angular=1.0, linear_accel=0.5, angular_accel=2.0, wheel=3.0)
    sp2 = sample_plan(MIXED, tomasi_limited, rate, limits2)
    check_sampled(sp2, MIXED, tomasi_limited, limits2, np.minimum(bounds, 3.0))


def test_sample_plan_diff_drive_and_mecanum(robots):
    limits = MotionLimits(linear=0.4, angular=0.8, linear_accel=0.3, angular_accel=1.5)
    plan = umbmark_square("ccw", 4.0, "rotate") + arc(1.0, 2.0) + arc(0.5, -1.0)
    check_sampled(sample_plan(plan, robots["diff-drive"], 50.0, limits), plan, robots["diff-drive"], limits)
    check_sampled(sample_plan(MIXED, robots["mecanum4"], 50.0, limits), MIXED, robots["mecanum4"], limits)


def test_sample_plan_errors(robots):
    with pytest.raises(OmnikinError):
        sample_plan(line(1.0), robots["tomasi-omni3"], 0.0)
    with pytest.raises(OmnikinError):
        sample_plan(line(1.0), robots["tomasi-omni3"], float("nan"))
    with pytest.raises(OmnikinError, match="speed limit"):
        sample_plan(line(1.0), robots["tomasi-omni3"], 100.0, MotionLimits(linear=None, angular=None))
    with pytest.raises(OmnikinError):
        MotionLimits(linear=-1.0)
    with pytest.raises(OmnikinError, match="positive number of samples per second, got True"):
        sample_plan(line(1.0), robots["tomasi-omni3"], True)  # not 1 Hz


@pytest.mark.parametrize("rate", [True, 0.5, 4.99, 10000.5, 1e5, np.float64(1e9)])
def test_a_simulation_refuses_a_rate_outside_the_range_where_it_starts(robots, rate):
    """simulate(..., rate=True) ran at 1 Hz, and 0.5 Hz or 1e5 Hz were simulated when the call
    came from below the entry points: the one range, 5 Hz to 10 kHz, is checked where every
    simulation starts, also for a plan sampled beforehand."""
    robot = robots["tomasi-omni3"]
    with pytest.raises(OmnikinError, match=r"^rate: the sample rate .*\[5, 10000\] Hz"):
        simulate_kinematic(line(1.0), robot, robot, rate=rate)
    if not isinstance(rate, bool) and rate < 1e6:  # sample_plan itself refuses 1e9 samples by size
        with pytest.raises(OmnikinError, match=r"^rate: the sample rate .*\[5, 10000\] Hz"):
            simulate_kinematic(sample_plan(line(0.1), robot, rate), robot, robot)


def test_a_simulation_takes_the_ends_of_the_rate_range(robots):
    robot = robots["tomasi-omni3"]
    for rate in (5, 10000.0):
        assert simulate_kinematic(line(0.1), robot, robot, rate=rate).sampled.rate == rate


# =====================================================================================================
# limits
# =====================================================================================================
def test_saturate_closed_form_tomasi(robots):
    robot = robots["tomasi-omni3"]
    limits = MotionLimits(linear=0.5, angular=1.5, wheel=8.0)
    rng = np.random.default_rng(3)
    t = rng.normal(size=(600, 3)) * [0.6, 0.6, 2.0]
    t[:50] *= 0.1  # some inside every limit
    t[50:60, 2] = 0.0  # pure translations
    t[60:70, :2] = 0.0  # pure spins
    out = saturate(robot, t, limits)
    assert out.shape == t.shape

    v = np.hypot(t[:, 0], t[:, 1])
    ws = np.max(np.abs(tomasi_wheel_speeds(t)), axis=1)
    with np.errstate(divide="ignore"):
        k_lin = np.where(v > 0, 0.5 / v, np.inf)
        k_ang = np.where(t[:, 2] != 0, 1.5 / np.abs(t[:, 2]), np.inf)
        k_wheel = 8.0 / ws
    k = np.minimum.reduce([np.ones(len(t)), k_lin, k_ang, k_wheel])
    np.testing.assert_allclose(out, t * k[:, None], rtol=1e-12, atol=1e-15)

    # one common factor in (0, 1]: direction and curvature kept
    nonzero = t != 0
    np.testing.assert_array_equal(out[~nonzero], 0.0)
    ratio = np.where(nonzero, out / np.where(nonzero, t, 1.0), np.nan)
    assert np.all(np.nanmax(ratio, axis=1) - np.nanmin(ratio, axis=1) <= 1e-12 * np.nanmax(ratio, axis=1))
    assert np.all(np.nanmax(ratio, axis=1) <= 1.0) and np.all(np.nanmin(ratio, axis=1) > 0)
    cross = out[:, 0] * t[:, 1] - out[:, 1] * t[:, 0]
    assert np.max(np.abs(cross)) <= 1e-14
    moving = v > 0
    np.testing.assert_allclose(
        out[moving, 2] / np.hypot(out[moving, 0], out[moving, 1]), t[moving, 2] / v[moving], rtol=1e-12, atol=1e-15
    )
    # never scales up: twists inside every limit come back unchanged
    inside = k == 1.0
    assert inside.sum() >= 30
    np.testing.assert_array_equal(out[inside], t[inside])
    # every limit holds, and a binding wheel limit is reached
    out_ws = np.max(np.abs(tomasi_wheel_speeds(out)), axis=1)
    assert np.all(out_ws <= 8.0 * (1 + 1e-12))
    assert np.all(np.hypot(out[:, 0], out[:, 1]) <= 0.5 * (1 + 1e-12))
    assert np.all(np.abs(out[:, 2]) <= 1.5 * (1 + 1e-12))
    wheel_binds = (k_wheel < 1) & (k_wheel <= np.minimum(k_lin, k_ang))
    assert wheel_binds.sum() >= 50
    np.testing.assert_allclose(out_ws[wheel_binds], 8.0, rtol=1e-12)


def test_saturate_shapes_zero_and_robot_max_speed(robots, tomasi_limited):
    robot = robots["tomasi-omni3"]
    limits = MotionLimits(linear=0.5, angular=1.5, wheel=8.0)
    t = np.random.default_rng(4).normal(size=(2, 5, 3))
    out = saturate(robot, t, limits)
    assert out.shape == (2, 5, 3)
    np.testing.assert_allclose(out.reshape(-1, 3), saturate(robot, t.reshape(-1, 3), limits), rtol=0, atol=0)
    np.testing.assert_array_equal(saturate(robot, [0.0, 0.0, 0.0], limits), [0.0, 0.0, 0.0])
    # robot-file max_speed alone (no body limits): vx = 1 m/s -> w3 is the binding wheel
    # (|sin 240| / r against 2.5 rad/s): k = 2.5 r / sin 60
    out = saturate(tomasi_limited, [1.0, 0.0, 0.0], MotionLimits(linear=None, angular=None))
    np.testing.assert_allclose(out, [2.5 * TOMASI_R / math.sin(math.radians(60)), 0, 0], rtol=1e-12)
    # the smaller of max_speed and MotionLimits.wheel
    out = saturate(tomasi_limited, [0.0, 0.0, 10.0], MotionLimits(linear=None, angular=None, wheel=2.0))
    np.testing.assert_allclose(out, [0, 0, 2.0 * TOMASI_R / TOMASI_L], rtol=1e-12)


def test_saturate_mecanum_general(robots):
    """mecanum4 rows from docs/conventions.md: drive 0, roller +-45 deg: omega = (vx -+ vy - (x -+ y)... ) / r;
    checked through the robot's ik, which kinematics/test_robot.py verifies against the closed form."""
    robot = robots["mecanum4"]
    limits = MotionLimits(linear=None, angular=None, wheel=10.0)
    t = np.random.default_rng(5).normal(size=(200, 3))
    out = saturate(robot, t, limits)
    ws_in = np.max(np.abs(robot.ik(t).wheel_speeds), axis=1)
    ws_out = np.max(np.abs(robot.ik(out).wheel_speeds), axis=1)
    np.testing.assert_allclose(ws_out, np.minimum(ws_in, 10.0), rtol=1e-12)
    k = ws_out / ws_in
    np.testing.assert_allclose(out, t * k[:, None], rtol=1e-12, atol=1e-15)


# =====================================================================================================
# errors
# =====================================================================================================
def _draws(robot, n, seed):
    rng = np.random.default_rng(seed)
    return [PROFILES["typical"].sample(robot, rng) for _ in range(n)]


def test_error_profile_reproducible(robots):
    robot = robots["tomasi-omni3"]
    a = PROFILES["typical"].sample(robot, 11).as_dict()
    b = PROFILES["typical"].sample(robot, 11).as_dict()
    c = PROFILES["typical"].sample(robot, 12).as_dict()
    assert a == b
    assert a != c
    g = np.random.default_rng(11)
    first, second = PROFILES["typical"].sample(robot, g).as_dict(), PROFILES["typical"].sample(robot, g).as_dict()
    assert first == a and second != first
    assert PROFILES["none"].sample(robot, 1).as_dict() == {n: dict.fromkeys(a["w1"], 0.0) for n in a}


def test_error_profile_std_swedish(robots):
    """tomasi-omni3, 'typical': radius sigma 0.5 %, radial hub shift 1 mm, hub angle 0.5 deg (tangential
    shift l * 0.5 deg), drive 0.5 deg; no roller or tick error (sigma 0)."""
    robot = robots["tomasi-omni3"]
    draws = _draws(robot, 3000, 7)
    r, drive, radial, tangential = [], [], [], []
    for d in draws:
        for name, b in zip(("w1", "w2", "w3"), TOMASI_BETAS, strict=True):
            e = d.wheels[name]
            r.append(e.radius)
            drive.append(e.drive)
            radial.append(math.cos(b) * e.dx + math.sin(b) * e.dy)
            tangential.append(-math.sin(b) * e.dx + math.cos(b) * e.dy)
            assert e.roller == 0.0 and e.ticks == 0.0
    n = len(r)
    for values, sigma in (
        (r, 0.005),
        (drive, math.radians(0.5)),
        (radial, 0.001),
        (tangential, TOMASI_L * math.radians(0.5)),
    ):
        values = np.array(values)
        assert np.std(values) == pytest.approx(sigma, rel=0.05)
        assert abs(np.mean(values)) < 4 * sigma / math.sqrt(n)


def test_error_profile_std_fixed_wheels(robots):
    """diff-drive: fixed standard wheels (drive along +x, axle along y) get a radius error and a
    displacement along the axle only (dy; radial sigma 1 mm as the hubs sit on the y axis)."""
    robot = robots["diff-drive"]
    draws = _draws(robot, 3000, 8)
    for name in ("left", "right"):
        es = [d.wheels[name] for d in draws]
        assert all(e.drive == 0.0 and e.roller == 0.0 and e.dx == 0.0 for e in es)
        r = np.array([e.radius for e in es])
        dy = np.array([e.dy for e in es])
        assert np.std(r) == pytest.approx(0.005, rel=0.05)
        assert np.std(dy) == pytest.approx(0.001, rel=0.05)
        assert abs(np.mean(r)) < 4 * 0.005 / math.sqrt(len(r))
        # the as-built robot keeps a feasible rigid axle: both wheels still drive along +x
        true = draws[0].apply(robot)
        assert true.wheel(name).drive == robot.wheel(name).drive


def test_systematic_errors_apply_moves_only_named_wheel(robots):
    robot = robots["tomasi-omni3"]
    e = WheelErrors(radius=0.01, dx=0.002, dy=-0.001, drive=0.01, ticks=0.02)
    true = SystematicErrors({"w2": e}).apply(robot)
    for name in ("w1", "w3"):
        assert true.wheel(name) == robot.wheel(name)
    w, w0 = true.wheel("w2"), robot.wheel("w2")
    assert w.radius == pytest.approx(w0.radius * 1.01, rel=1e-15)
    assert (w.x, w.y) == pytest.approx((w0.x + 0.002, w0.y - 0.001), abs=1e-15)
    assert w.drive == pytest.approx(w0.drive + 0.01, abs=1e-15)
    assert w.encoder.ticks_per_rev == pytest.approx(600 * 1.02, rel=1e-15)
    assert w.type == w0.type and w.roller == w0.roller
    assert [x.name for x in true.wheels] == [x.name for x in robot.wheels]
    # the nominal robot is untouched
    assert robot.wheel("w2").radius == TOMASI_R


def test_systematic_errors_unknown_wheel(robots):
    with pytest.raises(OmnikinError, match="w4"):
        SystematicErrors({"w4": WheelErrors(radius=0.01)}).apply(robots["tomasi-omni3"])
    with pytest.raises(OmnikinError):
        WheelErrors(radius=float("nan"))
    with pytest.raises(OmnikinError):
        WheelErrors(radius=-1.0)


# =====================================================================================================
# simulate
# =====================================================================================================
@pytest.mark.parametrize("rate", [10.0, 50.0, 100.0, 250.0])
@pytest.mark.parametrize("name", ROBOTS)
def test_perfect_knowledge_closes(robots, name, rate):
    robot = robots[name]
    modes = ("rotate", "translate") if robot.mobility.holonomic else ("rotate",)
    for mode in modes:
        for direction in ("cw", "ccw"):
            plan = umbmark_square(direction, 4.0, mode)
            for noise in (NOISE["none"], NoiseModel(), EXACT):
                sim = simulate_kinematic(plan, robot, robot, rate=rate, noise=noise, trials=2, rng=0)
                if noise.quantise and not robot.encoded[0].counts_close_loop:
                    # steppers turn exactly as commanded; whole ticks only measure them: the truth
                    # closes, the odometry within its quantisation (a few mm on the 16 m square)
                    assert_pose(sim.truth[:, -1], np.zeros((2, 3)), 1e-9)
                    assert np.max(np.abs(sim.epsilon)) < 0.01, (mode, direction, noise)
                    continue
                assert np.max(np.abs(sim.epsilon[:, :2])) < 1e-9, (mode, direction, noise)
                assert np.max(np.abs(sim.epsilon[:, 2])) < 1e-9
                if not noise.quantise:
                    assert_pose(sim.odometry[-1], [0, 0, 0], 1e-9)
                    assert_pose(sim.truth[:, -1], np.zeros((2, 3)), 1e-9)


def test_perfect_knowledge_quantised_odometry_is_near_the_plan(robots):
    """With whole ticks the odometry ends within a few ticks' worth of the plan end (not exactly).
    tomasi-omni3's steppers turn the commanded angles, and the ticks are those angles over the
    angle per tick, rounded: the truth is the plan, the odometry reads it to whole ticks. A dc
    motor's loop holds the counts at the rounded command: the truth is what those counts say."""
    robot = robots["tomasi-omni3"]
    plan = umbmark_square("cw")
    sim = simulate_kinematic(plan, robot, robot, noise=NoiseModel(), rng=0)
    exact = simulate_kinematic(plan, robot, robot, noise=EXACT)
    assert np.issubdtype(sim.ticks.dtype, np.integer)
    np.testing.assert_array_equal(sim.ticks, np.round(exact.ticks))
    np.testing.assert_allclose(sim.truth[0], exact.truth[0], atol=1e-9)
    assert np.hypot(*sim.odometry[-1, :2]) < 0.01
    assert 1e-6 < np.max(np.abs(sim.truth[0, :, :2] - sim.odometry[:, :2])) < 0.01
    dc = with_motor(robot, "dc")
    sim = simulate_kinematic(plan, dc, dc, noise=NoiseModel(), rng=0)
    np.testing.assert_allclose(sim.truth[0], sim.odometry, atol=1e-9)


def with_motor(robot, motor):
    """``robot`` with every encoded wheel driven by ``motor``."""
    from dataclasses import replace

    return replace(robot, wheels=tuple(replace(w, motor=motor) if w.encoder else w for w in robot.wheels))


def test_all_radii_one_percent_large_line_and_spin(robots):
    """Common radius scale (1 + e): every wheel rolls (1 + e) times the commanded distance, so the
    body twist is (1 + e) times the commanded one: line 4 m -> 4.04 m, spin pi/2 -> 1.01 pi/2."""
    robot = robots["tomasi-omni3"]
    true = SystematicErrors({n: WheelErrors(radius=0.01) for n in ("w1", "w2", "w3")}).apply(robot)
    sim = simulate_kinematic(line(4.0), true, robot, noise=EXACT)
    assert_pose(sim.measured[0], [4.04, 0, 0], 1e-9)
    assert_pose(sim.odometry[-1], [4.0, 0, 0], 1e-9)
    assert_pose(sim.epsilon[0], [0.04, 0, 0], 1e-9)
    sim = simulate_kinematic(spin(math.pi / 2), true, robot, noise=EXACT)
    assert_pose(sim.measured[0], [0, 0, 1.01 * math.pi / 2], 1e-9)
    # the whole rotate-mode square: every leg 4.04 m, every corner 90.9 deg
    for direction in ("cw", "ccw"):
        plan = umbmark_square(direction)
        sim = simulate_kinematic(plan, true, robot, noise=EXACT)
        expected = poses_after_segments(plan, scale=(1.01, 1.01, 1.01))[-1]
        assert_pose(sim.epsilon[0], expected, 1e-9)
        assert np.hypot(*expected[:2]) > 0.1
        # the translate square closes exactly: legs scaled, heading held
        sim = simulate_kinematic(umbmark_square(direction, 4.0, "translate"), true, robot, noise=EXACT)
        assert_pose(sim.epsilon[0], [0, 0, 0], 1e-9)
    # mecanum4: the same argument holds for any layout
    mec = robots["mecanum4"]
    true = SystematicErrors({w.name: WheelErrors(radius=0.01) for w in mec.rolling}).apply(mec)
    assert_pose(
        simulate_kinematic(line(4.0, 0.5), true, mec, noise=EXACT).measured[0],
        [4.04 * math.cos(0.5), 4.04 * math.sin(0.5), 0],
        1e-9,
    )


@pytest.mark.parametrize("motor", ["stepper", "dc"])
def test_encoder_ticks_error(robots, motor):
    """ticks_per_rev (1 + e) on every wheel: each tick is 1/(1 + e) of the assumed angle. A stepper
    turns the commanded angle (truth 4 m) and its encoders count (1 + e) times the ticks the model
    expects (odometry 4 (1 + e) m); a dc motor's loop holds the counts at the command (odometry
    4 m), so the wheels turn 1/(1 + e) of it (truth 4/(1 + e) m)."""
    robot = with_motor(robots["tomasi-omni3"], motor)
    true = SystematicErrors({n: WheelErrors(ticks=0.02) for n in ("w1", "w2", "w3")}).apply(robot)
    sim = simulate_kinematic(line(4.0), true, robot, noise=EXACT)
    truth, odometry = (4.0, 4.0 * 1.02) if motor == "stepper" else (4.0 / 1.02, 4.0)
    assert_pose(sim.measured[0], [truth, 0, 0], 1e-9)
    assert_pose(sim.odometry[-1], [odometry, 0, 0], 1e-9)


@pytest.mark.parametrize("e", [0.001, 0.01, -0.005])
def test_diff_drive_right_wheel_larger_curves_left(robots, e):
    """Right radius r (1 + e): on a commanded straight line of L both wheels turn L / r, the right
    wheel rolls L (1 + e), the left L; the body follows an arc with heading change L e / b and arc
    length L (1 + e/2): x = s sin(dth) / dth, y = s (1 - cos dth) / dth. Left turn for e > 0."""
    robot = robots["diff-drive"]
    true = SystematicErrors({"right": WheelErrors(radius=e)}).apply(robot)
    length = 4.0
    dth = length * e / DIFF_TRACK
    s = length * (1 + e / 2)
    expected = [s * math.sin(dth) / dth, s * (1 - math.cos(dth)) / dth, dth]
    for rate in (10.0, 100.0):
        sim = simulate_kinematic(line(length), true, robot, rate=rate, noise=EXACT)
        assert_pose(sim.measured[0], expected, 1e-9)
    assert (sim.measured[0, 2] > 0) == (e > 0)


def test_diff_drive_track_error_on_spin(robots):
    """Left wheel d further out (true track b + d): a commanded spin by phi rolls the wheels -+ b phi / 2;
    the body turns by b phi / (b + d) about the wheels' midpoint (0, d/2): the origin ends at
    (d/2 sin dth, d/2 (1 - cos dth)). Symmetric track error (+-d/2): turns in place by b phi / (b + d)."""
    robot = robots["diff-drive"]
    d, phi = 0.004, math.pi / 2
    true = SystematicErrors({"left": WheelErrors(dy=d)}).apply(robot)
    dth = DIFF_TRACK * phi / (DIFF_TRACK + d)
    sim = simulate_kinematic(spin(phi), true, robot, noise=EXACT)
    assert_pose(sim.measured[0], [d / 2 * math.sin(dth), d / 2 * (1 - math.cos(dth)), dth], 1e-9)
    true = SystematicErrors({"left": WheelErrors(dy=d / 2), "right": WheelErrors(dy=-d / 2)}).apply(robot)
    sim = simulate_kinematic(spin(-phi), true, robot, noise=EXACT)
    assert_pose(sim.measured[0], [0, 0, -dth], 1e-9)


def test_typical_noise_scatter_about_10_mm(robots):
    """'typical' noise: run-to-run scatter of the return positions on the 4 m square ~ 10 mm."""
    robot = robots["tomasi-omni3"]
    for direction in ("cw", "ccw"):
        sim = simulate_kinematic(
            umbmark_square(direction), robot, robot, noise=NOISE["typical"], trials=200, rng=2024, keep_truth=False
        )
        e = sim.epsilon[:, :2]
        rms = math.sqrt(np.mean(np.sum((e - e.mean(axis=0)) ** 2, axis=1)))
        assert 0.005 <= rms <= 0.020, rms
        # no systematic error: the centre of gravity is at the origin within its own scatter
        assert np.hypot(*e.mean(axis=0)) < 4 * rms / math.sqrt(200)


def test_measurement_noise_alone(robots):
    """Only measurement noise (sigma 2 mm, 1 deg): the truth closes, the measured end scatters with those sigmas."""
    robot = robots["tomasi-omni3"]
    noise = NoiseModel(quantise=False, measurement=0.002, measurement_theta=math.radians(1.0))
    sim = simulate_kinematic(umbmark_square("cw"), robot, robot, noise=noise, trials=2000, rng=5, keep_truth=False)
    assert_pose(sim.truth[:, -1], np.zeros((2000, 3)), 1e-9)
    std = sim.epsilon.std(axis=0)
    np.testing.assert_allclose(std, [0.002, 0.002, math.radians(1.0)], rtol=0.06)


def test_simulate_reproducible_with_seed(robots):
    robot = robots["tomasi-omni3"]
    true = PROFILES["typical"].sample(robot, 3).apply(robot)
    plan = umbmark_square("ccw")
    a = simulate_kinematic(plan, true, robot, noise=NOISE["typical"], trials=4, rng=42)
    b = simulate_kinematic(plan, true, robot, noise=NOISE["typical"], trials=4, rng=42)
    c = simulate_kinematic(plan, true, robot, noise=NOISE["typical"], trials=4, rng=43)
    np.testing.assert_array_equal(a.truth, b.truth)
    np.testing.assert_array_equal(a.measured, b.measured)
    np.testing.assert_array_equal(a.ticks, b.ticks)
    assert np.all(a.measured != c.measured)
    # trials differ from each other
    assert len({tuple(m) for m in a.measured}) == 4
    # keeping only the end draws the same random numbers
    d = simulate_kinematic(plan, true, robot, noise=NOISE["typical"], trials=4, rng=42, keep_truth=False)
    np.testing.assert_allclose(d.truth[:, 0], a.truth[:, -1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(d.measured, a.measured, rtol=0, atol=1e-12)


def test_trial_axis_shapes(robots):
    robot = robots["tomasi-omni3"]
    plan = umbmark_square("cw")
    sp = sample_plan(plan, robot, 100.0)
    n = len(sp.progress)
    sim = simulate_kinematic(plan, robot, robot, noise=NOISE["typical"], trials=7, rng=1)
    assert sim.t.shape == (n + 1,)
    assert sim.ticks.shape == (n + 1, 3)
    assert sim.steer is None
    assert sim.odometry.shape == (n + 1, 3)
    assert sim.truth.shape == (7, n + 1, 3)
    assert sim.measured.shape == (7, 3)
    assert sim.epsilon.shape == (7, 3)
    np.testing.assert_array_equal(sim.truth[:, 0], 0.0)
    sim = simulate_kinematic(plan, robot, robot, noise=NOISE["typical"], trials=7, rng=1, keep_truth=False)
    assert sim.truth.shape == (7, 1, 3) and sim.measured.shape == (7, 3)
    # noise-free trials are all the same, with the same shapes
    sim = simulate_kinematic(plan, robot, robot, noise=NOISE["none"], trials=3, rng=1)
    assert sim.truth.shape == (3, n + 1, 3)
    np.testing.assert_array_equal(sim.truth[0], sim.truth[2])
    # diff-drive: two encoded wheels (the castor has no encoder)
    dd = robots["diff-drive"]
    sim = simulate_kinematic(plan, dd, dd, trials=2, rng=1, rate=20.0)
    assert sim.ticks.shape[1] == 2 and sim.epsilon.shape == (2, 3)
    # a sampled plan is accepted as is
    sim = simulate_kinematic(sp, robot, robot, trials=1)
    assert sim.t.shape == (n + 1,)
    for bad in (0, -1, 2.0):
        with pytest.raises(OmnikinError):
            simulate_kinematic(plan, robot, robot, trials=bad)


def test_simulate_refuses_plans_the_command_model_cannot_drive(robots):
    dd = robots["diff-drive"]
    with pytest.raises(OmnikinError):
        simulate_kinematic(umbmark_square("cw", 4.0, "translate"), dd, dd)


def test_a_robot_built_without_errors_is_the_robot_itself_by_its_name():
    from omnikin.simulation.error_models import SystematicErrors, WheelErrors

    robot = load_robot("tomasi-omni3")
    assert SystematicErrors({}).apply(robot) is robot
    assert SystematicErrors({"w1": WheelErrors()}).apply(robot) is robot
    built = SystematicErrors({"w1": WheelErrors(radius=0.01)}).apply(robot)
    assert built.name == "tomasi-omni3 (as built)" and built.wheel("w1").radius == robot.wheel("w1").radius * 1.01
