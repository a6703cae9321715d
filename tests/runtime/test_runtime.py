"""The ROS-free runtime: command filter (timeout, limits, validation) and BaseRuntime with SimBackend.

Closed forms used below:

* braking from speed v at deceleration a: time v / a, distance v^2 / (2 a);
* a command that accelerates from rest at a to speed v, cruises and brakes at a covers
  v * T, T the time between the start of the ramp up and the start of the ramp down
  (the two ramps are mirror images).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.errors import OmnikinError
from omnikin.kinematics.encoder import Encoder
from omnikin.kinematics.se2 import compose, exp, wrap_angle
from omnikin.kinematics.se2 import compose_exp_jacobians as _jacobians
from omnikin.motion.limits import MotionLimits
from omnikin.runtime.base import BaseRuntime
from omnikin.runtime.command import CommandFilter
from omnikin.simulation.backend import SimBackend
from omnikin.simulation.error_models import PROFILES, NoiseModel

DT = 1.0 / 128.0  # a power of two: the time grid is exact in binary floating point


@pytest.fixture(scope="module")
def omni3():
    return load_robot("tomasi-omni3")


@pytest.fixture(scope="module")
def diff():
    return load_robot("diff-drive")


@pytest.fixture(scope="module")
def ackermann():
    return load_robot("ackermann")


def run_filter(f: CommandFilter, t0: float, t1: float, dt: float = DT):
    """Update ``f`` on the grid t0, t0 + dt, ... < t1; returns times and twists (n, 3)."""
    n = round((t1 - t0) / dt)
    ts = t0 + dt * np.arange(n)
    out = np.array([f.update(float(t)) for t in ts])
    return ts, out


def parallel(a, b, tol=1e-9):
    """True if the 3-vectors a and b point the same way (b = k a, k > 0)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0 or nb == 0:
        return na == nb
    return np.allclose(a / na, b / nb, atol=tol)


# --- CommandFilter: timeout ----------------------------------------------------------------------
class TestTimeout:
    def test_timeout_brakes_to_zero_within_the_deceleration_limit(self, omni3):
        v, a, timeout = 0.25, 0.5, 1.0  # v / a = 64 DT: the grid resolves the ramp exactly
        f = CommandFilter(omni3, MotionLimits(linear=0.3, linear_accel=a), timeout=timeout)
        f.update(0.0)
        assert f.command((v, 0.0, 0.0), 0.0)
        ts, tw = run_filter(f, DT, 3.0)
        speed = tw[:, 0]
        # reached the commanded speed after v / a, held it until the timeout
        cruising = (ts >= v / a + DT) & (ts <= timeout)
        assert cruising.sum() > 10 and np.allclose(speed[cruising], v)
        assert f.timed_out and f.stats.timeouts == 1
        # braking starts at the first update after the timeout and lasts v / a
        braking = ts > timeout
        t_start = ts[braking][0]
        assert t_start - timeout <= DT
        stopped = ts[(speed == 0.0) & braking]
        assert stopped.size, "the twist never reached zero after the timeout"
        t_stop = stopped[0]
        assert t_stop - t_start == pytest.approx(v / a, abs=1.01 * DT)
        # the deceleration never exceeds the limit
        assert np.all(np.abs(np.diff(speed)) <= a * DT * (1 + 1e-12))
        # braking distance = v^2 / (2 a): the speed falls linearly, so the trapezoid rule is exact
        seg = speed[(ts >= t_start - DT) & (ts <= t_stop)]
        distance = np.trapezoid(seg, dx=DT) if hasattr(np, "trapezoid") else np.trapz(seg, dx=DT)
        assert distance == pytest.approx(v * v / (2 * a), rel=1e-9)
        assert np.all(tw[ts >= t_stop] == 0.0)

    def test_braking_of_a_turn_keeps_its_curvature(self, omni3):
        f = CommandFilter(omni3, MotionLimits(), timeout=0.25)
        f.update(0.0)
        cmd = np.array([0.2, 0.05, 0.6])
        f.command(cmd, 0.0)
        ts, tw = run_filter(f, DT, 2.0)
        after = tw[ts > 0.25]
        moving = after[np.linalg.norm(after, axis=1) > 0]
        assert moving.size and np.all([parallel(cmd, w) for w in moving])

    def test_each_valid_command_restarts_the_timeout(self, omni3):
        f = CommandFilter(omni3, timeout=0.5)
        f.update(0.0)
        for k in range(20):  # 2 s of commands every 0.1 s
            t = 0.1 * k
            f.command((0.1, 0.0, 0.0), t)
            f.update(t)
        assert not f.timed_out and f.stats.timeouts == 0
        assert f.update(1.95)[0] == pytest.approx(0.1)

    def test_a_rejected_command_does_not_restart_the_timeout(self, omni3):
        f = CommandFilter(omni3, timeout=0.5)
        f.update(0.0)
        f.command((0.1, 0.0, 0.0), 0.0)
        f.update(0.4)
        assert not f.command((math.nan, 0.0, 0.0), 0.45)
        f.update(0.55)
        assert f.timed_out and f.stats.timeouts == 1

    def test_a_new_command_after_a_timeout_drives_again(self, omni3):
        f = CommandFilter(omni3, timeout=0.6)
        f.update(0.0)
        f.command((0.1, 0.0, 0.0), 0.0)
        run_filter(f, DT, 2.0)
        assert f.timed_out and np.all(f.current == 0)
        f.command((0.0, 0.1, 0.0), 2.0)
        _, tw = run_filter(f, 2.0, 2.5)
        assert not f.timed_out
        assert tw[-1] == pytest.approx([0.0, 0.1, 0.0])

    def test_zero_disables_the_timeout(self, omni3):
        f = CommandFilter(omni3, timeout=0.0)
        f.update(0.0)
        f.command((0.1, 0.0, 0.2), 0.0)
        _, tw = run_filter(f, DT, 30.0, dt=0.25)
        assert not f.timed_out and f.stats.timeouts == 0
        assert tw[-1] == pytest.approx([0.1, 0.0, 0.2])

    def test_no_command_yet_means_standing_still(self, omni3):
        f = CommandFilter(omni3)
        _, tw = run_filter(f, 0.0, 1.0)
        assert np.all(tw == 0)
        assert f.stats.timeouts == 0

    @pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf])
    def test_invalid_timeout_is_an_error(self, omni3, bad):
        with pytest.raises(OmnikinError, match="cmd_vel_timeout"):
            CommandFilter(omni3, timeout=bad)


# --- CommandFilter: acceleration limit ---------------------------------------------------------
class TestAcceleration:
    @pytest.mark.parametrize(
        "start, target",
        [
            ((0, 0, 0), (0.25, 0.1, 0.8)),
            ((0.2, 0.0, 0.0), (-0.2, 0.1, 0.5)),
            ((0.0, 0.0, 0.9), (0.05, 0.0, -0.9)),
            ((0.1, -0.1, 0.0), (0.0, 0.0, 0.0)),
        ],
    )
    def test_the_change_keeps_its_direction_and_respects_both_limits(self, omni3, start, target):
        lim = MotionLimits(linear=0.3, angular=1.0, linear_accel=0.5, angular_accel=2.0)
        f = CommandFilter(omni3, lim, timeout=0.0)
        f.current = np.array(start, dtype=float)
        f.update(0.0)
        f.command(target, 0.0)
        prev = f.current.copy()
        target = np.array(target, dtype=float)
        n = 0
        for k in range(1, 400):
            cur = f.update(k * DT)
            change = cur - prev
            if np.allclose(change, 0):
                break
            n += 1
            # the change points at the target: same direction as target - previous
            assert parallel(target - prev, change), (prev, change)
            lin, ang = math.hypot(change[0], change[1]), abs(change[2])
            assert lin <= lim.linear_accel * DT * (1 + 1e-12)
            assert ang <= lim.angular_accel * DT * (1 + 1e-12)
            prev = cur
        assert np.allclose(prev, target)
        # time to the target = the larger of the two closed-form ramp times
        step = target - np.array(start, float)
        t_need = max(math.hypot(step[0], step[1]) / lim.linear_accel, abs(step[2]) / lim.angular_accel)
        assert n == math.ceil(t_need / DT - 1e-9)

    def test_no_limit_means_an_immediate_change(self, omni3):
        lim = MotionLimits(linear_accel=None, angular_accel=None)
        f = CommandFilter(omni3, lim, timeout=0.0)
        f.update(0.0)
        f.command((0.2, -0.1, 0.5), 0.0)
        assert f.update(0.01) == pytest.approx([0.2, -0.1, 0.5])


# --- CommandFilter: saturation -------------------------------------------------------------------
class TestSaturation:
    def settle(self, f, cmd, t_end=10.0):
        f.update(0.0)
        assert f.command(cmd, 0.0)
        _, tw = run_filter(f, DT, t_end, dt=1.0 / 32)
        return tw[-1]

    @pytest.mark.parametrize("cmd", [(1.0, 0.0, 0.0), (0.6, 0.6, 0.5), (0.1, 0.0, 3.0), (-0.5, 0.2, -2.0)])
    def test_keeps_direction_and_curvature_within_body_limits(self, omni3, cmd):
        lim = MotionLimits(linear=0.3, angular=1.0)
        f = CommandFilter(omni3, lim, timeout=0.0)
        out = self.settle(f, cmd)
        cmd = np.array(cmd)
        k = min(
            1.0,
            0.3 / math.hypot(cmd[0], cmd[1]) if cmd[:2].any() else math.inf,
            1.0 / abs(cmd[2]) if cmd[2] else math.inf,
        )
        assert out == pytest.approx(k * cmd, abs=1e-12)
        assert parallel(cmd, out)
        if cmd[:2].any():
            assert out[2] / math.hypot(out[0], out[1]) == pytest.approx(cmd[2] / math.hypot(cmd[0], cmd[1]))
        assert math.hypot(out[0], out[1]) <= 0.3 + 1e-12 and abs(out[2]) <= 1.0 + 1e-12
        assert f.stats.saturated >= 1

    def test_within_limits_is_untouched(self, omni3):
        f = CommandFilter(omni3, MotionLimits(), timeout=0.0)
        out = self.settle(f, (0.1, 0.1, 0.3))
        assert out == pytest.approx([0.1, 0.1, 0.3], abs=1e-15)
        assert f.stats.saturated == 0

    @pytest.mark.parametrize("cmd", [(0.3, 0.0, 0.0), (0.0, 0.2, 0.9), (0.1, -0.2, -1.0)])
    def test_respects_the_wheel_limit_of_the_parameters(self, omni3, cmd):
        lim = MotionLimits(linear=10.0, angular=10.0, wheel=3.0)
        f = CommandFilter(omni3, lim, timeout=0.0)
        out = self.settle(f, cmd)
        speeds = np.abs(omni3.ik(out).wheel_speeds)
        assert speeds.max() == pytest.approx(3.0, rel=1e-9)  # the binding limit is reached ...
        assert np.all(speeds <= 3.0 * (1 + 1e-12))  # ... and never exceeded
        assert parallel(cmd, out)

    def test_respects_each_wheels_max_speed_from_the_robot_file(self, omni3):
        wheels = list(omni3.wheels)
        wheels[1] = replace(wheels[1], max_speed=2.0)  # one slow wheel
        robot = replace(omni3, wheels=tuple(wheels))
        lim = MotionLimits(linear=10.0, angular=10.0, wheel=4.0)
        f = CommandFilter(robot, lim, timeout=0.0)
        cmd = np.array([0.3, 0.2, 0.5])
        out = self.settle(f, cmd)
        speeds = np.abs(robot.ik(out).wheel_speeds)
        bounds = np.array([4.0, 2.0, 4.0])
        assert np.all(speeds <= bounds * (1 + 1e-12))
        assert np.max(speeds / bounds) == pytest.approx(1.0, rel=1e-9)
        assert parallel(cmd, out)

    def test_diff_drive_wheel_limit_keeps_the_curvature(self, diff):
        lim = MotionLimits(linear=5.0, angular=5.0, wheel=2.0)
        f = CommandFilter(diff, lim, timeout=0.0)
        cmd = np.array([0.5, 0.0, 1.5])
        out = self.settle(f, cmd)
        assert parallel(cmd, out)
        assert np.abs(diff.ik(out).wheel_speeds).max() == pytest.approx(2.0, rel=1e-9)


# --- CommandFilter: malformed commands ----------------------------------------------------------
class TestValidation:
    @pytest.mark.parametrize(
        "bad",
        [
            (math.nan, 0.0, 0.0),
            (0.0, math.inf, 0.0),
            (0.0, 0.0, -math.inf),
            (1e9, 0.0, 0.0),
            (0.0, -1e9, 0.0),
            (0.0, 0.0, 1e9),
            (31.0, 0.0, 0.0),
            "fast",
            (0.1, 0.2),
            None,
        ],
    )
    def test_rejected_counted_and_the_previous_target_kept(self, omni3, bad):
        f = CommandFilter(omni3, MotionLimits(linear=0.3, angular=1.0), timeout=0.0)
        f.update(0.0)
        assert f.command((0.1, 0.0, 0.2), 0.0)
        assert f.command(bad, 0.1) is False
        assert f.stats.rejected == 1 and f.stats.accepted == 1
        assert f.stats.last_reject_reason
        assert f.target == pytest.approx([0.1, 0.0, 0.2])
        _, tw = run_filter(f, DT, 2.0)
        assert np.all(np.isfinite(tw))
        assert tw[-1] == pytest.approx([0.1, 0.0, 0.2])

    def test_just_below_the_reject_threshold_is_accepted_and_saturated(self, omni3):
        f = CommandFilter(omni3, MotionLimits(linear=0.3, angular=1.0), timeout=0.0, reject_above=100.0)
        assert f.command((29.0, 0.0, 0.0), 0.0)
        f.update(0.0)
        assert f.update(5.0)[0] == pytest.approx(0.3)

    def test_diff_drive_vy_is_projected_away_and_counted(self, diff):
        f = CommandFilter(diff, MotionLimits(), timeout=0.0)
        assert f.command((0.1, 0.2, 0.3), 0.0)
        assert f.stats.projected == 1 and f.stats.accepted == 1
        assert f.target == pytest.approx([0.1, 0.0, 0.3], abs=1e-12)
        assert f.command((0.1, 0.0, 0.3), 0.1)
        assert f.stats.projected == 1
        f.update(0.1)
        tw = f.update(3.0)
        assert tw == pytest.approx([0.1, 0.0, 0.3], abs=1e-12)
        assert diff.ik(tw).feasible

    def test_pure_sideways_command_of_a_diff_drive_becomes_standing_still(self, diff):
        f = CommandFilter(diff, MotionLimits(), timeout=0.0)
        assert f.command((0.0, 0.2, 0.0), 0.0)
        assert f.stats.projected == 1
        assert f.target == pytest.approx([0, 0, 0], abs=1e-12)

    @pytest.mark.parametrize("cmd", [(0.1, 0.0, 1.0), (0.0, 0.0, 0.5), (-0.1, 0.0, 0.8)])
    def test_ackermann_steering_beyond_limits_is_rejected(self, ackermann, cmd):
        f = CommandFilter(ackermann, MotionLimits(), timeout=0.0)
        assert f.command((0.2, 0.0, 0.1), 0.0)  # R = 2 m: about 17 deg, feasible
        assert f.command(cmd, 0.1) is False
        assert f.stats.rejected == 1
        assert "steering" in f.stats.last_reject_reason
        assert f.target == pytest.approx([0.2, 0.0, 0.1])

    def test_ackermann_tightest_feasible_turn_is_accepted(self, ackermann):
        # wheelbase 0.6 m, inner wheel at 35 deg: R_inner = 0.6 / tan 35deg, R = R_inner + 0.25
        r_min = 0.6 / math.tan(math.radians(35)) + 0.25
        f = CommandFilter(ackermann, MotionLimits(), timeout=0.0)
        assert f.command((0.2, 0.0, 0.2 / (r_min * 1.01)), 0.0)
        assert not f.command((0.2, 0.0, 0.2 / (r_min * 0.99)), 0.0)


# --- BaseRuntime with SimBackend -------------------------------------------------------------------
SQUARE_AND_ARCS = [
    ((0.2, 0.0, 0.0), 3.0),
    ((0.0, 0.0, 0.0), 0.6),
    ((0.0, 0.0, 0.8), 2.0),
    ((0.0, 0.0, 0.0), 0.8),
    ((0.2, 0.0, 0.0), 3.0),
    ((0.0, 0.0, -0.8), 2.0),
    ((0.15, 0.0, 0.4), 3.0),
    ((0.2, 0.0, -0.6), 2.5),
    ((0.0, 0.0, 0.0), 1.0),
]
HOLONOMIC = [((0.0, 0.2, 0.0), 2.0), ((0.15, -0.15, 0.3), 2.0), ((0.0, 0.0, 0.0), 1.0)]
ACKERMANN = [
    ((0.2, 0.0, 0.0), 2.0),
    ((0.25, 0.0, 0.15), 3.0),
    ((0.2, 0.0, -0.1), 3.0),
    ((0.1, 0.0, 0.0), 1.0),
    ((0.0, 0.0, 0.0), 1.0),
]


def drive(runtime: BaseRuntime, script, dt: float = 0.04, t0: float = 0.0, every=None):
    """Run ``script`` [(twist, duration)] through ``runtime``; ``every(result)`` after each step."""
    t = t0
    for twist, duration in script:
        assert runtime.command(twist, t), runtime.filter.stats.last_reject_reason
        for _ in range(round(duration / dt)):
            res = runtime.step(t)
            if every is not None:
                every(res)
            t += dt
    return t


def pose_error(a, b):
    e = np.asarray(a, float) - np.asarray(b, float)
    e[..., 2] = wrap_angle(e[..., 2])
    return e


VILLASENOR = [((0.2, 0.0, 0.0), 2.0), ((0.0, 0.15, 0.0), 2.0), ((0.15, 0.1, 0.1), 3.0), ((0.0, 0.0, 0.0), 1.0)]


def script_for(robot):
    if robot.name == "villasenor-omni3":  # legs trail more than their distance: no turn in place
        return VILLASENOR
    if robot.steerable and robot.fixed:
        return ACKERMANN
    if robot.mobility.holonomic:
        return SQUARE_AND_ARCS + HOLONOMIC
    return SQUARE_AND_ARCS


ENCODED_PRESETS = [
    "tomasi-omni3",
    "garcia-sillas-omni3",
    "villasenor-omni3",
    "diff-drive",
    "omni4",
    "mecanum4",
    "ackermann",
    "synchro",
    "xr4000",
]


class TestPerfectKnowledge:
    @pytest.mark.parametrize("name", ENCODED_PRESETS)
    def test_odometry_equals_the_truth(self, name):
        robot = load_robot(name)
        backend = SimBackend(robot, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
        worst = [0.0]

        def check(res):
            assert res.pose == pytest.approx(tuple(rt.odometry.pose))
            worst[0] = max(worst[0], float(np.abs(pose_error(res.pose, backend.truth)).max()))

        drive(rt, script_for(robot), every=check)
        travelled = np.abs(backend.truth[:2]).max() + abs(backend.truth[2])
        assert travelled > 0.3  # the script did move the robot
        assert worst[0] < 1e-9, f"{name}: odometry left the truth by {worst[0]:.3g}"

    def test_wheel_commands_are_the_inverse_kinematics_of_the_filtered_twist(self, omni3):
        backend = SimBackend(omni3, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(omni3, backend, cmd_vel_timeout=0.0)
        rt.command((0.1, 0.05, 0.3), 0.0)
        for k in range(50):
            res = rt.step(k * 0.02)
            assert res.wheel_speeds == pytest.approx(omni3.ik(res.command).wheel_speeds)
        assert res.command == pytest.approx([0.1, 0.05, 0.3])
        # the measured twist follows the command once the ramp is over
        assert res.twist == pytest.approx((0.1, 0.05, 0.3), abs=1e-9)

    def test_the_timeout_stops_the_simulated_robot(self, omni3):
        backend = SimBackend(omni3, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(omni3, backend, limits=MotionLimits(linear_accel=0.5), cmd_vel_timeout=0.5)
        rt.command((0.2, 0.0, 0.0), 0.0)
        t = 0.0
        for _ in range(200):
            rt.step(t)
            t += DT
        # ramp up from t = 0, ramp down from the timeout (mirror images): x = v * timeout,
        # up to the control grid
        assert rt.filter.timed_out and rt.filter.stats.timeouts == 1
        assert rt.pose[0] == pytest.approx(0.2 * 0.5, abs=0.2 * DT)
        assert rt.pose[0] == pytest.approx(backend.truth[0], abs=1e-12)
        assert rt.odometry.twist == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)


class TestSystematicErrors:
    @pytest.mark.parametrize("name", ["tomasi-omni3", "diff-drive", "omni4"])
    def test_typical_errors_make_the_odometry_drift(self, name):
        robot = load_robot(name)
        true = PROFILES["typical"].sample(robot, np.random.default_rng(7)).apply(robot)
        backend = SimBackend(robot, true, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
        errors = []
        drive(rt, SQUARE_AND_ARCS, every=lambda r: errors.append(np.abs(pose_error(r.pose, backend.truth))))
        errors = np.array(errors)
        assert errors[-1, :2].max() > 1e-4 or errors[-1, 2] > 1e-4
        # the drift grows along the run
        assert errors[len(errors) // 4 :].max() > 3 * errors[: len(errors) // 10].max()


# --- covariance ---------------------------------------------------------------------------------------
def fine_encoders(robot, ticks=10_000_000):
    """The robot with encoders so fine that quantisation is negligible next to slip."""
    wheels = [replace(w, encoder=Encoder(ticks)) if w.encoder is not None else w for w in robot.wheels]
    return replace(robot, wheels=tuple(wheels))


def is_psd(m, rel=1e-12):
    m = np.asarray(m)
    if not np.allclose(m, m.T, rtol=0.0, atol=1e-12 * np.abs(m).max()):
        return False
    ev = np.linalg.eigvalsh(m)
    return ev.min() >= -rel * max(ev.max(), 1e-300)


class TestCovariance:
    @pytest.mark.parametrize("name", ["tomasi-omni3", "diff-drive", "omni4", "ackermann"])
    def test_symmetric_psd_and_growing_with_distance(self, name):
        robot = load_robot(name)
        backend = SimBackend(robot, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
        covs = []

        def check(res):
            assert is_psd(res.pose_covariance), res.pose_covariance
            assert is_psd(res.twist_covariance), res.twist_covariance
            covs.append(res.pose_covariance)

        drive(rt, script_for(robot), every=check)
        covs = np.array(covs)
        # no measurement of the world: the heading variance and det P (det A = 1) never shrink
        assert np.all(np.diff(covs[:, 2, 2]) >= -1e-15 * covs[:, 2, 2].max())
        dets = np.linalg.det(covs)
        assert np.all(np.diff(dets) >= -1e-12 * np.abs(dets).max())
        assert np.trace(covs[-1]) > 10 * np.trace(covs[10])
        assert np.all(np.linalg.eigvalsh(rt.pose_covariance) > 0)

    def test_grows_with_distance_not_while_standing_still(self, omni3):
        backend = SimBackend(omni3, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(omni3, backend, cmd_vel_timeout=0.0)
        t = drive(rt, [((0.2, 0.0, 0.3), 3.0), ((0.0, 0.0, 0.0), 1.0)], dt=0.02)
        moving = rt.pose_covariance.copy()
        assert np.trace(moving) > 0
        t = drive(rt, [((0.0, 0.0, 0.0), 20.0)], t0=t, dt=0.02)  # 20 s standing still at 50 Hz
        still = rt.pose_covariance
        growth = np.sqrt(np.diag(still)) - np.sqrt(np.diag(moving))
        assert np.all(growth <= 1e-3 * np.sqrt(np.diag(moving))), (
            f"standing still for 20 s grew the pose sigma from {np.sqrt(np.diag(moving))} to {np.sqrt(np.diag(still))}"
        )

    def test_does_not_depend_on_the_sample_rate(self, omni3):
        """Slip is distance-proportional: the same drive sampled at 20 Hz and 100 Hz, same covariance."""
        covs = []
        for dt in (0.05, 0.01):
            backend = SimBackend(omni3, noise=NoiseModel(quantise=False))
            rt = BaseRuntime(
                omni3, backend, cmd_vel_timeout=0.0, limits=MotionLimits(linear_accel=None, angular_accel=None)
            )
            rt.step(drive(rt, [((0.2, 0.0, 0.0), 5.0), ((0.0, 0.2, 0.5), 5.0)], dt=dt))  # up to t = 10 s
            covs.append(rt.pose_covariance)
        sig = [np.sqrt(np.diag(c)) for c in covs]
        assert sig[1] == pytest.approx(sig[0], rel=0.1), f"sigma at 20 Hz {sig[0]}, at 100 Hz {sig[1]}"

    def test_slip_part_is_rate_independent_with_fine_encoders(self, omni3):
        robot = fine_encoders(omni3)
        covs = []
        for dt in (0.05, 0.01):
            rt = BaseRuntime(
                robot,
                SimBackend(robot),
                cmd_vel_timeout=0.0,
                limits=MotionLimits(linear_accel=None, angular_accel=None),
            )
            rt.step(drive(rt, [((0.2, 0.0, 0.0), 5.0), ((0.0, 0.2, 0.5), 5.0)], dt=dt))  # up to t = 10 s
            covs.append(rt.pose_covariance)
        assert covs[1] == pytest.approx(covs[0], rel=0.02, abs=1e-3 * np.abs(covs[0]).max())

    def test_zero_slip_and_fine_encoders_give_almost_no_covariance(self, omni3):
        robot = fine_encoders(omni3)
        rt = BaseRuntime(robot, SimBackend(robot), cmd_vel_timeout=0.0, wheel_slip=0.0)
        drive(rt, [((0.2, 0.0, 0.3), 3.0)])
        assert np.abs(rt.pose_covariance).max() < 1e-10

    def test_twist_covariance_is_the_increment_covariance_over_dt_squared(self, omni3):
        robot = fine_encoders(omni3)
        rt = BaseRuntime(robot, SimBackend(robot), cmd_vel_timeout=0.0)
        res = []
        drive(rt, [((0.2, 0.0, 0.0), 1.0)], dt=0.02, every=res.append)
        r2 = []
        rt2 = BaseRuntime(robot, SimBackend(robot), cmd_vel_timeout=0.0)
        drive(rt2, [((0.2, 0.0, 0.0), 1.0)], dt=0.04, every=r2.append)
        # constant speed: Sigma_xi ~ distance ~ dt, so Sigma_twist ~ 1/dt
        assert np.trace(r2[-1].twist_covariance) == pytest.approx(0.5 * np.trace(res[-1].twist_covariance), rel=1e-6)

    @pytest.mark.parametrize("theta", [0.0, 0.7, -2.9, math.pi / 2])
    @pytest.mark.parametrize(
        "inc",
        [
            (0.01, 0.0, 0.0),
            (0.02, -0.01, 0.3),
            (-0.05, 0.03, -1.2),
            (0.0, 0.0, 0.0),
            (0.01, 0.004, 1e-7),
            (0.3, 0.1, 2.5),
            (0.0, 0.0, 2e-4),
        ],
    )
    def test_jacobians_match_finite_differences_of_the_exact_update(self, theta, inc):
        inc = np.array(inc, dtype=float)
        x0 = np.array([0.3, -1.2, theta])
        a_mat, b_mat = _jacobians(theta, inc)

        def update(x, xi):
            out = compose(x, exp(xi))
            out[2] = x[2] + xi[2]  # unwrapped heading: a smooth function
            return out

        h = 1e-6
        a_num, b_num = np.empty((3, 3)), np.empty((3, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = h
            a_num[:, j] = (update(x0 + e, inc) - update(x0 - e, inc)) / (2 * h)
            b_num[:, j] = (update(x0, inc + e) - update(x0, inc - e)) / (2 * h)
        assert a_mat == pytest.approx(a_num, abs=1e-8)
        assert b_mat == pytest.approx(b_num, abs=1e-8)

    def test_jacobians_are_continuous_across_the_small_angle_branch(self):
        inc = np.array([0.02, -0.01, 0.0])
        for phi in (1.999e-4, 2.001e-4):  # the branch at |phi / 2| = 1e-4
            inc[2] = phi
            a1, b1 = _jacobians(0.4, inc)
            inc2 = inc.copy()
            inc2[2] = phi * (1 + 1e-9)
            a2, b2 = _jacobians(0.4, inc2)
            assert b1 == pytest.approx(b2, abs=1e-12) and a1 == pytest.approx(a2, abs=1e-12)


class TestMonteCarlo:
    SLIP = 5e-3  # sqrt(m): large, so that 400 trials resolve it; linear regime still
    SCRIPT = (((0.2, 0.0, 0.0), 2.0), ((0.1, 0.1, 0.6), 2.0), ((0.0, 0.2, -0.4), 2.0), ((0.0, 0.0, 0.0), 0.4))
    DT = 0.2  # the propagation is exact in the step count: coarse steps, fast trials

    @pytest.mark.parametrize("name, trials", [("tomasi-omni3", 400), ("diff-drive", 300)])
    def test_propagated_covariance_matches_the_sample_covariance(self, name, trials):
        robot = fine_encoders(load_robot(name))
        script = (
            self.SCRIPT
            if robot.mobility.holonomic
            else [((0.2, 0.0, 0.0), 2.0), ((0.15, 0.0, 0.6), 2.0), ((0.2, 0.0, -0.4), 2.0), ((0.0, 0.0, 0.0), 0.4)]
        )
        # one run of the runtime: the commands and the propagated covariance (slip does not
        # reach the encoder readings of SimBackend, so the odometry is the same in every trial)
        backend = SimBackend(robot, noise=NoiseModel(slip=self.SLIP, quantise=False), rng=0)
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0, wheel_slip=self.SLIP)
        writes = []
        real_write = backend.write
        backend.write = lambda t, s, steer=None: (writes.append((t, np.array(s), steer)), real_write(t, s, steer))
        drive(rt, script, dt=self.DT)
        t_end = writes[-1][0] + self.DT
        backend.read(t_end)
        rt.step(t_end)
        odom = np.array(rt.pose)
        p = rt.pose_covariance
        errs = []
        for seed in np.random.SeedSequence(12345).spawn(trials):
            b = SimBackend(robot, noise=NoiseModel(slip=self.SLIP, quantise=False), rng=seed)
            for t, speeds, steer in writes:
                b.read(t)
                b.write(t, speeds, steer)
            b.read(t_end)
            errs.append(pose_error(b.truth, odom))
        errs = np.array(errs)
        assert np.abs(errs.mean(axis=0)).max() < 4 * np.sqrt(np.diag(p)).max() / math.sqrt(trials) + 1e-4
        s = np.cov(errs.T)
        # whitened sample covariance: identity if the propagation is right
        w = np.linalg.inv(np.linalg.cholesky(p))
        ev = np.linalg.eigvalsh(w @ s @ w.T)
        assert ev.min() > 0.7 and ev.max() < 1.3, (ev, np.sqrt(np.diag(s)), np.sqrt(np.diag(p)))
        assert np.sqrt(np.diag(s)) == pytest.approx(np.sqrt(np.diag(p)), rel=0.15)


class TestResidual:
    def test_exact_layout_has_no_residual(self, omni3):
        backend = SimBackend(omni3, noise=NoiseModel(slip=1e-2, quantise=False), rng=3)
        rt = BaseRuntime(omni3, backend, cmd_vel_timeout=0.0)
        out = []
        drive(rt, SQUARE_AND_ARCS, every=out.append)
        assert max(np.abs(r.residual).max() for r in out) < 1e-9

    def test_ground_slip_is_invisible_to_ideal_speed_control(self):
        """The simulated wheels track their commands exactly: ground slip moves the truth but the
        encoders still read mutually consistent angles, so the residual stays zero."""
        robot = load_robot("omni4")
        backend = SimBackend(robot, noise=NoiseModel(slip=1e-2, quantise=False), rng=3)
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
        out = []
        drive(rt, SQUARE_AND_ARCS, every=out.append)
        assert np.abs(pose_error(rt.pose, backend.truth)).max() > 1e-3  # slip did happen
        assert max(np.linalg.norm(r.residual) for r in out) < 1e-9

    def test_a_wheel_that_spins_out_shows_in_the_residual(self):
        """One omni4 wheel turns 0.5 rad more than the others allow: the residual is that excess
        projected on the left null space of J, n = (1, -1, 1, -1)/2 (see kinematics/test_robot.py), per second."""
        robot = load_robot("omni4")
        excess = np.array([0.5, 0.0, 0.0, 0.0])
        rt = BaseRuntime(robot, _ScriptedBackend([(np.zeros(4), None), (excess, None)]), cmd_vel_timeout=0.0)
        rt.step(0.0)
        res = rt.step(0.1)
        n = np.array([1.0, -1.0, 1.0, -1.0]) / 2.0
        np.testing.assert_allclose(res.residual, n * (n @ excess) / 0.1, atol=1e-9)

    def test_redundant_layout_without_slip_has_no_residual(self):
        robot = load_robot("omni4")
        backend = SimBackend(robot, noise=NoiseModel(quantise=False))
        rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
        out = []
        drive(rt, SQUARE_AND_ARCS, every=out.append)
        assert max(np.linalg.norm(r.residual) for r in out) < 1e-9


def test_invalid_wheel_slip_is_an_error(omni3):
    with pytest.raises(OmnikinError, match="wheel_slip"):
        BaseRuntime(omni3, SimBackend(omni3), wheel_slip=-1.0)


class _ScriptedBackend:
    """A back-end that replays given wheel states (positions [rad], steering [rad])."""

    def __init__(self, states):
        self.states = list(states)
        self.writes = []

    def read(self, t):
        from omnikin.runtime.backends import WheelState

        pos, steer = self.states.pop(0)
        pos = np.asarray(pos, float)
        return WheelState(float(t), pos, np.zeros_like(pos), None if steer is None else np.asarray(steer, float))

    def write(self, t, speeds, steer=None):
        self.writes.append((t, speeds, steer))

    def stats(self):
        return {}

    def close(self):
        pass


def test_covariance_uses_the_circular_mean_of_the_steering_across_pi():
    """Conventions: an interval's steering is the circular mean of its end samples, in the
    covariance as in the odometry. Wheel w1 turns from pi - 0.01 to -pi + 0.01 (its interval
    angle is pi; the arithmetic mean, 0, points the wheel the other way). The same motion
    reported without the wrap (pi - 0.01 to pi + 0.01) must give the same pose and covariance."""
    robot = load_robot("synchro")
    d = np.array([0.4, 0.1, -0.2])  # wheel angle increments [rad]
    s0 = np.array([math.pi - 0.01, 0.3, -0.2])
    results = []
    for w1_end in (-math.pi + 0.01, math.pi + 0.01):
        s1 = np.array([w1_end, 0.3, -0.2])
        rt = BaseRuntime(robot, _ScriptedBackend([(np.zeros(3), s0), (d, s1)]), cmd_vel_timeout=0.0)
        rt.step(0.0)
        rt.step(0.1)
        results.append((np.array(rt.pose), rt.pose_covariance.copy(), rt.twist_covariance.copy()))
    (pose_a, p_a, t_a), (pose_b, p_b, t_b) = results
    mid = np.array([math.pi, 0.3, -0.2])
    inc = robot.fk_matrix(mid, rt.encoded)[:, :3] @ d
    assert pose_a == pytest.approx(exp(inc), abs=1e-12)  # the odometry uses the circular mean
    assert pose_b == pytest.approx(exp(inc), abs=1e-12)
    assert np.abs(p_a).max() > 0
    assert p_a == pytest.approx(p_b, rel=1e-9, abs=1e-18), "pose covariance depends on how the steering wraps"
    assert t_a == pytest.approx(t_b, rel=1e-9, abs=1e-18), "twist covariance depends on how the steering wraps"
