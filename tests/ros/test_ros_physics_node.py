"""``omnikin ros ROBOT --backend physics`` on a real ROS 2 graph: the node steps the MuJoCo
model to the wall clock, answers ``cmd_vel`` and publishes ``ground_truth`` beside ``odom``.

Closed form (``tests/ros/test_ros_node.py``): accelerating at a to v and braking at a are
mirror images, so a forward command held from ``first`` to ``last`` and then left to time out
covers ``v (last - first + cmd_vel_timeout)`` along +x. The physics adds the wheel servos' lag,
which is the same on both ramps, and roller contact (0.04 % of the distance for tomasi-omni3,
docs/physics.md); the tolerance covers the command's delivery jitter (a few ms at v).

With ``--errors`` the model is the robot as built while the odometry is the nominal robot's:
the truth is the odometry's increments through the drawn robot's kinematics
(:func:`truth_from_odometry`).
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics back-end needs MuJoCo (extra 'physics')")

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402 (after the importorskips)
from test_ros_node import (  # noqa: E402 (after the importorskips there and above)
    RELIABLE_ALL,
    Odometry,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    start,
    wait_for,
    yaw_of,
)

from support.kinematics import constant_twist_pose  # noqa: E402 (after the importorskip above)
from support.ros_status import running  # noqa: E402 (after the importorskip above)

pytestmark = pytest.mark.ros

V = 0.2  # commanded forward speed [m/s] (below linear.x.max_velocity 0.3)
TIMEOUT = 0.5  # cmd_vel_timeout [s], the default
TOLERANCE = 0.01  # [m] on the closed-form distance


def xy_yaw(msg) -> np.ndarray:
    p = msg.pose.pose
    return np.array([p.position.x, p.position.y, yaw_of(p.orientation)])


class Truth:
    """The test side's subscription to ``ground_truth``."""

    def __init__(self, graph):
        self.lock = threading.Lock()
        self.msgs: list = []  # (receive time [monotonic s], msg)
        graph.node.create_subscription(Odometry, "ground_truth", self._on, RELIABLE_ALL)

    def _on(self, msg):
        with self.lock:
            self.msgs.append((time.monotonic(), msg))

    def last(self):
        with self.lock:
            return self.msgs[-1][1] if self.msgs else None


def settled(graph, truth, settle: float = 0.3, timeout: float = 10.0):
    """Wait until odometry and truth move less than 0.1 mm over ``settle`` s; their last messages."""

    def still():
        now = time.monotonic()
        with graph.lock, truth.lock:
            recent = [xy_yaw(m) for t, m in graph.odom if t > now - settle]
            recent_truth = [xy_yaw(m) for t, m in truth.msgs if t > now - settle]
        return (
            len(recent) >= 5
            and len(recent_truth) >= 5
            and np.ptp(recent, axis=0)[:2].max() < 1e-4
            and np.ptp(recent_truth, axis=0)[:2].max() < 1e-4
        )

    assert wait_for(still, timeout), "the robot did not come to rest"
    return graph.last_odom(), truth.last()


def test_the_physics_node_drives_forward_publishes_truth_and_stops_after_the_timeout(tmp_path):
    proc, graph = start(tmp_path, ["tomasi-omni3", "--backend", "physics", "--errors", "none"])
    try:
        truth = Truth(graph)
        assert wait_for(lambda: truth.last() is not None, 10.0), f"no ground_truth\n{proc.stderr()}"
        odom0, truth0 = settled(graph, truth)
        assert truth0.header.frame_id == "odom" and truth0.child_frame_id == "base_link"
        first, last = graph.drive(vx=V, duration=1.5)
        assert wait_for(lambda: graph.last_odom().twist.twist.linear.x > 0.5 * V, 2.0), "the node did not answer"
        odom1, truth1 = settled(graph, truth)
        expected = V * (last - first + TIMEOUT)
        d_odom = xy_yaw(odom1) - xy_yaw(odom0)
        d_truth = xy_yaw(truth1) - xy_yaw(truth0)
        print(
            f"physics node: closed form {expected:.4f} m (T = {last - first:.3f} s); odom dx {d_odom[0]:.4f} "
            f"dy {d_odom[1]:.5f} m; truth dx {d_truth[0]:.4f} dy {d_truth[1]:.5f} m dtheta {d_truth[2]:.5f} rad"
        )
        for what, d in (("odom", d_odom), ("ground_truth", d_truth)):
            assert d[0] == pytest.approx(expected, abs=TOLERANCE), (what, d, expected)
            assert abs(d[1]) < 0.01 * expected and abs(d[2]) < 0.01, (what, d)
        # stopped: nothing moves any more, the truth's twist is zero
        time.sleep(0.5)
        assert xy_yaw(graph.last_odom())[:2] == pytest.approx(xy_yaw(odom1)[:2], abs=1e-4)
        assert xy_yaw(truth.last())[:2] == pytest.approx(xy_yaw(truth1)[:2], abs=1e-4)
        tw = truth.last().twist.twist
        assert math.hypot(tw.linear.x, tw.linear.y) < 1e-3
        _, _, values, _ = graph.next_diag()
        print(
            "physics node diagnostics: "
            + ", ".join(
                f"{k} {values[k]}" for k in ("loop_overruns", "loop_time_max_ms", "link_time_dropped", "loop_rate_hz")
            )
        )
        assert values["link_backend"] == "physics"
        assert int(values["command_timeouts"]) >= 1
        assert float(values["link_sim_time"]) > 2.0
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        rc, took = proc.terminate()
        assert rc == 0, proc.stderr()


SLOW_NODE = """\
import pathlib
import sys
import time

from omnikin import load_robot
from omnikin.cli.ros import PHYSICS_MAX_LAG
from omnikin.physics.backend import PhysicsBackend
from omnikin.ros.node import run
from omnikin.ros.params import load_params


class SlowPhysics(PhysicsBackend):
    \"\"\"The physics back-end of the node, whose read takes 0.4 s while the file 'slow' exists.\"\"\"

    def read(self, t):
        if pathlib.Path("slow").exists():
            time.sleep(0.4)
        return super().read(t)


robot = load_robot("tomasi-omni3")
sys.exit(run(robot, SlowPhysics(robot, max_lag=PHYSICS_MAX_LAG), load_params(None)))
"""


def test_a_slow_physics_step_is_counted_and_the_simulation_drops_time_instead_of_falling_behind(tmp_path):
    """Cycles of 0.4 s at 50 Hz: each overruns the period; the next one would have 0.42 s to catch
    up, beyond max_lag 0.25 s, so about 0.17 s is dropped per cycle. /diagnostics says both (WARN),
    the node keeps publishing, and it runs on as before once the cycles are fast."""
    script = tmp_path / "slow_node.py"
    script.write_text(SLOW_NODE)
    proc, graph = start(tmp_path, [], script=script)
    try:
        (tmp_path / "slow").write_text("")
        t_slow = time.monotonic()
        n = graph.n_odom()
        time.sleep(2.5)
        assert graph.n_odom() > n, "no odometry while the cycles are slow"
        warned = [d for d in graph.diags if d[0] > t_slow + 1.0]
        assert warned, "no /diagnostics while the cycles are slow"
        _, _, values, status = warned[-1]
        print(
            f"slow physics: {status.message!r}; {values['loop_overruns']} overruns, longest cycle "
            f"{values['loop_time_max_ms']} ms, {values['link_time_dropped']} s dropped"
        )
        assert status.level == DiagnosticStatus.WARN
        assert "control cycle(s) overran the period" in status.message and "behind real time" in status.message
        assert int(values["loop_overruns"]) >= 2 and float(values["loop_time_max_ms"]) >= 400.0
        assert float(values["link_time_dropped"]) > 0.1 and int(values["link_lag_events"]) >= 1
        (tmp_path / "slow").unlink()
        t_fast = time.monotonic()
        # running again: no 0.4 s cycle since the previous status (a busy machine may still
        # make a fast cycle overrun the 20 ms period, which the status may warn of)
        assert wait_for(
            lambda: (
                graph.last_diag()[0] > t_fast + 1.5
                and running(graph.last_diag()[3])
                and float(graph.last_diag()[2]["loop_time_max_ms"]) < 400.0
            ),
            5.0,
        ), graph.last_diag()[3].message
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        proc.close()


# --- the robot as built on the physics: odometry drifts from ground_truth by what the errors imply -----
def relative(a, b) -> np.ndarray:
    """Pose ``b`` in the frame of pose ``a`` (both ``(x, y, theta)`` in one world frame)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], 2 * math.pi)])


def compose(a, b) -> np.ndarray:
    """Pose ``b`` (given in the frame of ``a``) in ``a``'s world frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def twist_of(pose) -> np.ndarray:
    """The body twist that, held for one second, moves the robot by ``pose`` (SE(2) logarithm):
    ``(x, y) = V (vx, vy)`` with ``V = [[s/th, -(1-c)/th], [(1-c)/th, s/th]]``."""
    x, y, th = pose
    if abs(th) < 1e-12:
        return np.array([x, y, th])
    s, c = math.sin(th), math.cos(th)
    v = np.array([[s / th, -(1 - c) / th], [(1 - c) / th, s / th]])
    return np.array([*np.linalg.solve(v, [x, y]), th])


def truth_from_odometry(odom_poses, to_true) -> np.ndarray:
    """The true robot's motion implied by the odometry's: every increment between two odometry
    poses is a body twist ``xi`` of the nominal model; the wheels turned ``J xi`` (nominal
    Jacobian ``J``), and the robot as built, rolling without slip, moved by
    ``J_true^-1 S^-1 J xi`` (``S``: its encoders' scale against the nominal); ``to_true`` is that
    matrix. The increments composed from the start, in the start's body frame."""
    pose = np.zeros(3)
    for a, b in zip(odom_poses[:-1], odom_poses[1:], strict=True):
        pose = compose(pose, constant_twist_pose(to_true @ twist_of(relative(a, b)), 1.0))
    return pose


DRIVE = 4.0  # [s] of forward commands at V: about 0.9 m


@pytest.mark.parametrize("errors", ["typical", "none"])
def test_the_physics_node_with_errors_drifts_from_ground_truth_by_what_the_robot_as_built_implies(tmp_path, errors):
    """``--errors typical --seed 1``: the robot as built is the draw ``omnikin simulate`` makes
    for seed 1 (wheels' radii, hub positions, drive directions off by 0.1-1 %); the nominal
    odometry then drifts from ``ground_truth`` by the kinematics of that robot (a few mm and
    mrad over 0.9 m, :func:`truth_from_odometry`). ``--errors none``: they agree within the
    encoder quantisation and the contacts' sink (0.05 % of the distance, docs/physics.md)."""
    from omnikin import load_robot
    from omnikin.api.common import as_built

    nominal = load_robot("tomasi-omni3")
    true, _ = as_built(nominal, None, errors, np.random.SeedSequence(1).spawn(2)[0])
    scale = nominal.rad_per_tick(nominal.encoded_names) / true.rad_per_tick(nominal.encoded_names)
    to_true = np.linalg.solve(true.jacobian(), nominal.jacobian() / scale[:, None])
    # odometry quantisation: each reading within half a tick q/2 of the wheel's angle
    half_tick = np.abs(np.linalg.pinv(nominal.jacobian())) @ (nominal.rad_per_tick() / 2)

    proc, graph = start(tmp_path, ["tomasi-omni3", "--backend", "physics", "--errors", errors, "--seed", "1"])
    try:
        truth = Truth(graph)
        assert wait_for(lambda: truth.last() is not None, 10.0), f"no ground_truth\n{proc.stderr()}"
        _, truth0 = settled(graph, truth)
        with graph.lock:
            i0 = len(graph.odom) - 1
        graph.drive(vx=V, duration=DRIVE)
        _, truth1 = settled(graph, truth)
        with graph.lock:
            odom_poses = [xy_yaw(m) for _, m in graph.odom[i0:]]
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        rc, _ = proc.terminate()
        assert rc == 0, proc.stderr()

    odom = relative(odom_poses[0], odom_poses[-1])
    seen = relative(xy_yaw(truth0), xy_yaw(truth1))
    expected = truth_from_odometry(odom_poses, to_true)
    distance = float(np.hypot(*odom[:2]))
    # the quantisation's heading error turns the path: up to half_tick[2] * distance sideways
    tol_xy = float(np.hypot(*half_tick[:2])) + half_tick[2] * distance + 5e-4 * distance
    tol_th = half_tick[2] + 1e-3
    print(
        f"--errors {errors}: odometry {odom}, ground truth {seen}, implied by the robot as built {expected}; "
        f"tolerance {tol_xy * 1e3:.2f} mm, {tol_th * 1e3:.2f} mrad"
    )
    assert distance > 0.8
    assert np.hypot(*(seen[:2] - expected[:2])) < tol_xy, (seen, expected)
    assert abs(seen[2] - expected[2]) < tol_th, (seen, expected)
    drift = np.hypot(*(expected[:2] - odom[:2]))
    if errors == "none":
        assert drift < 1e-9
    else:  # the drift the test finds is well beyond its tolerance: without the errors it fails
        assert drift > 3 * tol_xy and abs(expected[2] - odom[2]) > 3 * tol_th, (drift, expected, odom)


# --- a robot that falls over: the node reports it and its wheels stay stopped ---------------------
PUSHED_NODE = """\
import pathlib
import sys

from omnikin import load_robot
from omnikin.cli.ros import PHYSICS_MAX_LAG
from omnikin.physics.backend import PhysicsBackend
from omnikin.ros.node import run
from omnikin.ros.params import load_params


class PushedPhysics(PhysicsBackend):
    \"\"\"The physics back-end of the node, its chassis pushed over (1.5 N m about world x) while
    the file 'push' exists.\"\"\"

    def read(self, t):
        self.sim.data.xfrc_applied[self.sim._chassis, 3] = 1.5 if pathlib.Path("push").exists() else 0.0
        return super().read(t)


robot = load_robot("tomasi-omni3")
sys.exit(run(robot, PushedPhysics(robot, max_lag=PHYSICS_MAX_LAG), load_params(None)))
"""


def test_a_physics_robot_that_falls_over_is_an_error_in_diagnostics_and_its_wheels_stay_stopped(tmp_path):
    """Pushed over (1.5 N m about x on a robot whose weight holds it with at most 1.1 N m,
    tests/physics/test_physics_robot_that_falls_is_reported.py), the simulated robot tips:
    /diagnostics turns ERROR 'wheels stopped: robot ... tipped over at t = ... s' and stays so,
    and a forward cmd_vel afterwards turns no wheel (joint_states speeds zero)."""
    script = tmp_path / "pushed_node.py"
    script.write_text(PUSHED_NODE)
    proc, graph = start(tmp_path, [], script=script)
    try:
        _, _, values, status = graph.next_diag()
        assert status.level != DiagnosticStatus.ERROR and values["link_fallen"] == "", status.message  # standing
        (tmp_path / "push").write_text("")

        def fallen():
            last = graph.last_diag()
            return last is not None and last[3].level == DiagnosticStatus.ERROR

        assert wait_for(fallen, 10.0), graph.last_diag()[3].message
        (tmp_path / "push").unlink()
        message = graph.last_diag()[3].message
        print(f"pushed over: {message!r}")
        assert message.startswith("wheels stopped: robot 'tomasi-omni3' tipped over at t = ")
        time.sleep(1.0)  # the push ended: let the robot come to rest on its back
        t_drive = time.monotonic()
        wheels = ("w1", "w2", "w3")  # the measured joints (the others move as the odometry implies)
        # commanded until joint_states came back from well inside the command (a loaded machine may
        # hold the node's publisher back for longer than one stretch of driving)
        speeds: list = []
        while not speeds and time.monotonic() < t_drive + 60.0:
            graph.drive(vx=V, duration=1.5)
            with graph.lock:
                late = [m for t, m in graph.joints if t > t_drive + 0.5]
                speeds = [[m.velocity[list(m.name).index(w)] for w in wheels] for m in late]
        assert speeds, "no joint_states while commanded"
        commanded = V / 0.04125  # [rad/s] the wheels would turn at (tomasi-omni3's radius)
        print(f"largest wheel speed after the fall: {np.max(np.abs(speeds)):.3g} rad/s (commanded ~{commanded:.3g})")
        assert np.max(np.abs(speeds)) < 0.05 * commanded
        _, _, values, status = graph.next_diag()
        assert status.level == DiagnosticStatus.ERROR and "tipped over" in status.message
        assert "tipped over" in values["link_fallen"]
        assert proc.stderr().count("tipped over") == 1  # logged once
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        rc, _ = proc.terminate()
        assert rc == 0, proc.stderr()
