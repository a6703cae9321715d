"""``omnikin view ROBOT --ros`` follows a running ``omnikin ros`` node and drives it: real nodes
(the node, simulating the robot as its file says, and the viewer's own) on a ROS domain of their
own, the page in headless Chromium, and a listener of the test's own on the same domain that
records what the node was sent and what it published.

The distance is judged on the node's simulated time, not on how long the page held the key: the
node ramps its command at its acceleration limit ``a`` (0.5 m/s^2, its default) from the first
``cmd_vel`` towards ``v`` and back to rest from the zero the page sends at the release. Over ``D``
[s] of motion (its ``ground_truth``, stamped at each control step, from the last step at rest to
the first at rest again) the robot covers ``v (D - v/a)`` (two ramps of ``v^2 / 2a`` in ``v/a``
each and a plateau of ``v`` between) when ``D >= 2 v/a``, else the triangle ``a D^2 / 4``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time

import pytest

from support.browser import hold_key, wait_for, wait_until
from support.paths import omnikin_env
from support.ros_domain import fresh_domain

pytestmark = pytest.mark.ros
SPEED = 0.2
ACCEL = 0.5
"""The node's ``linear.x.max_acceleration`` [m/s^2] (its default)."""
READOUT = "#omnikin-readout"


def readout(page) -> dict:
    return page.evaluate(f"(() => {{ const d = document.querySelector('{READOUT}').dataset; return {{...d}}; }})()")


STILL = 1e-6
"""Largest displacement [m] of a control step at rest (a step of the ramp moves 100 um or more)."""


def moving_steps(truth: list[tuple[float, float, float]]) -> tuple[int, int]:
    """The indices in ``truth`` (``(stamp, x, y)`` at each control step) of the last step at rest
    before the first that moved more than :data:`STILL` and of the first at rest after the last
    that did; ``(-1, -1)`` before any motion."""
    moved = [i for i in range(1, len(truth)) if abs(truth[i][1] - truth[i - 1][1]) > STILL]
    if not moved:
        return -1, -1
    return moved[0] - 1, moved[-1]


def motion_distance(duration: float, speed: float, accel: float) -> float:
    """Distance [m] of a motion from rest to rest lasting ``duration`` [s] that ramps at ``accel``
    [m/s^2] towards ``speed`` [m/s] and, from the release, back to rest (module docstring)."""
    if duration >= 2 * speed / accel:
        return speed * (duration - speed / accel)
    return accel * duration**2 / 4


@pytest.fixture
def ros_env(tmp_path):
    """A ROS domain of this test's own (:func:`support.ros_domain.fresh_domain`), discovery on this host,
    logs in the test's folder."""
    env = omnikin_env(
        ROS_DOMAIN_ID=str(fresh_domain()),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_LOG_DIR=str(tmp_path / "ros_log"),
        PYTHONUNBUFFERED="1",
    )
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.pop("ROS_STATIC_PEERS", None)
    return env


@pytest.fixture
def ros_discovery(monkeypatch, tmp_path):
    """This test process's own rclpy context finds the nodes on this host only, logs in tmp_path."""
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "test_ros_log"))
    monkeypatch.delenv("ROS_LOCALHOST_ONLY", raising=False)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)


class Listener:
    """An rclpy node of the test on ``domain`` recording every ``cmd_vel`` ``(vx, vy, omega)``,
    every ``ground_truth`` ``(stamp [s], x, y)`` and the last ``odom`` ``(x, y)`` [m]."""

    def __init__(self, domain: int):
        import rclpy
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rclpy.signals import SignalHandlerOptions

        self.lock = threading.Lock()
        self.commands: list[tuple[float, float, float]] = []
        self.truth: list[tuple[float, float, float]] = []
        self.odom: tuple[float, float] | None = None
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain, signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node("test_view_ros_listener", context=self.context)
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.node.create_subscription(Twist, "cmd_vel", self._on_cmd, qos)
        self.node.create_subscription(Odometry, "ground_truth", self._on_truth, qos)
        self.node.create_subscription(Odometry, "odom", self._on_odom, qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception:  # noqa: BLE001 (the context shut down under it)
            pass

    def _on_cmd(self, msg) -> None:
        with self.lock:
            self.commands.append((msg.linear.x, msg.linear.y, msg.angular.z))

    def _on_truth(self, msg) -> None:
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        with self.lock:
            self.truth.append((stamp, msg.pose.pose.position.x, msg.pose.pose.position.y))

    def _on_odom(self, msg) -> None:
        with self.lock:
            self.odom = (msg.pose.pose.position.x, msg.pose.pose.position.y)

    def recorded(self) -> tuple[list, list, tuple[float, float] | None]:
        """The commands, the ground truth and the last odometry heard so far."""
        with self.lock:
            return list(self.commands), list(self.truth), self.odom

    def close(self) -> None:
        import rclpy

        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
        self.thread.join(2.0)


def test_the_ros_view_follows_a_node_and_its_keys_drive_it(ros_env, ros_discovery, page, page_log, tmp_path):
    params = tmp_path / "node.yaml"
    # no cmd_vel timeout: a viewer late by more than 0.5 s on a busy machine keeps the command on
    params.write_text("cmd_vel_timeout: 0.0\n", encoding="utf-8")
    procs = []
    listener = Listener(int(ros_env["ROS_DOMAIN_ID"]))
    try:
        node = start_node("tomasi-omni3", ros_env, "--params", str(params))
        procs.append(node)
        view = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "omnikin.cli.main",
                "view",
                "tomasi-omni3",
                "--ros",
                "--port",
                "0",
                "--duration",
                "120",
            ],
            env=ros_env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        procs.append(view)
        line = view.stdout.readline()
        found = re.search(r"http://\S+/", line)
        assert found, f"no address printed: {line!r}"
        assert f"ROS_DOMAIN_ID {ros_env['ROS_DOMAIN_ID']}" in line
        page.goto(found.group(0))
        page.wait_for_selector(f"{READOUT}[data-x]", timeout=30000)
        wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
        # the node's odometry is on the page once the graph has met: its time advances
        first = float(readout(page)["t"])
        wait_for(page, f"Number(document.querySelector('{READOUT}').dataset.t) > {first + 1.0}", timeout=15)
        # discovery: the viewer's cmd_vel is heard by the node and by the listener
        wait_until(
            lambda: listener.node.count_publishers("cmd_vel") >= 1 and listener.node.count_subscribers("cmd_vel") >= 2,
            "cmd_vel publisher and the node's subscription",
        )
        wait_until(lambda: listener.recorded()[1] and listener.recorded()[2], "ground_truth and odom")
        odom_start = listener.recorded()[2]
        hold_key(page, "w", 1.2)
        wait_until(lambda: (0.0, 0.0, 0.0) in listener.recorded()[0], "zero cmd_vel at the release")
        wait_for(page, f"Number(document.querySelector('{READOUT}').dataset.vx) === 0", timeout=30)

        def at_rest_after_moving() -> bool:
            truth = listener.recorded()[1]
            last = moving_steps(truth)[1]
            return last >= 0 and last + 5 < len(truth)  # and still 5 steps later

        wait_until(at_rest_after_moving, "ground_truth at rest after the motion")
        commands, truth, odom_end = listener.recorded()
        # the page sent the held W as SPEED forward at every control step, then one zero
        assert commands[-1] == (0.0, 0.0, 0.0) and len(commands) >= 2, commands
        assert all(c == (SPEED, 0.0, 0.0) for c in commands[:-1]), commands
        # the motion in the node's simulated time: from its last step at rest to its first at rest
        begin, end = moving_steps(truth)
        duration = truth[end][0] - truth[begin][0]
        expected = motion_distance(duration, SPEED, ACCEL)
        # the node's steps are discrete: each ramp is a staircase of steps, off the continuous ramp
        # by at most SPEED over one step (the longest of the motion, as the stamps say)
        longest = max(b[0] - a[0] for a, b in zip(truth[begin:end], truth[begin + 1 : end + 1], strict=True))
        tolerance = 2 * SPEED * longest
        assert truth[end][1] - truth[begin][1] == pytest.approx(expected, abs=tolerance), (duration, longest)
        assert abs(truth[end][2] - truth[begin][2]) < 1e-6  # the robot as the file says (no errors)
        assert odom_end[0] - odom_start[0] == pytest.approx(expected, abs=tolerance), (duration, longest)
        # the page shows the node's ground truth as the robot and its odometry beside it
        wait_for(
            page,
            f"(() => {{ const d = document.querySelector('{READOUT}').dataset;"
            f" return Math.abs(Number(d.x) - {truth[end][1]!r}) < 1e-6"
            f" && Math.abs(Number(d.odomX) - {odom_end[0]!r}) < 1e-6; }})()",
            timeout=30,
        )
        assert page_log.external == [] and page_log.page_errors == []
    finally:
        listener.close()
        for proc in reversed(procs):
            err = stop(proc)
            assert "Traceback" not in err, err[-2000:]


def start_node(robot: str, env: dict, *args: str) -> subprocess.Popen:
    """``omnikin ros ROBOT ARGS`` (simulated, exact) on the test's domain."""
    return subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "ros", robot, "--errors", "none", "--noise", "none", *args],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def stop(proc: subprocess.Popen) -> str:
    """Stop ``proc`` (SIGTERM, then SIGKILL to its group after 15 s); its standard error."""
    if proc.poll() is None:
        proc.terminate()
    try:
        _, err = proc.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, 9)
        _, err = proc.communicate()
    return err or ""


def published_joints(env: dict, timeout: float = 60.0) -> set[str]:
    """Join the test's domain with an rclpy context of this process and return the movable joints
    of the first ``robot_description`` heard (a node that publishes it is up)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from std_msgs.msg import String

    from omnikin.physics.link_frames import urdf_joints

    heard: list[str] = []
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(env["ROS_DOMAIN_ID"]), signal_handler_options=SignalHandlerOptions.NO)
    try:
        node = rclpy.create_node("test_listener", context=context)
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(String, "robot_description", lambda msg: heard.append(msg.data), qos)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        end = time.monotonic() + timeout
        while not heard and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.2)
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
    assert heard, f"no robot_description within {timeout} s"
    return {j.name for j in urdf_joints(heard[0]) if j.movable}


def test_the_ros_view_refuses_a_node_that_drives_another_robot(ros_env, ros_discovery):
    node = start_node("mecanum4", ros_env)
    try:
        joints = published_joints(ros_env)  # the node is up: its URDF names mecanum4's four wheels
        assert {"front_left", "front_right", "rear_left", "rear_right"} <= joints
        view = subprocess.run(
            [sys.executable, "-m", "omnikin.cli.main", "view", "tomasi-omni3", "--ros", "--port", "0"],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        err = stop(node)
        assert "Traceback" not in err, err[-2000:]
    assert view.returncode == 2, (view.stdout, view.stderr)
    lines = view.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), view.stderr
    assert "drives another robot" in lines[0]
    assert "4 wheels ['front_left', 'front_right', 'rear_left', 'rear_right']" in lines[0]
    assert "'tomasi-omni3' has 3 ['w1', 'w2', 'w3']" in lines[0]
    assert view.stdout == ""  # no page was served


def test_the_ros_view_warns_when_a_node_of_another_robot_appears_later(ros_env):
    view = subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "view", "tomasi-omni3", "--ros", "--port", "0", "--duration", "120"],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    node = None
    try:
        line = view.stdout.readline()  # served: no node was heard while it waited
        assert re.search(r"http://\S+/", line), line
        node = start_node("diff-drive", ros_env)
        warning = view.stderr.readline()  # the viewer prints nothing else on standard error
        assert warning.startswith("omnikin view: warning: the node on ROS_DOMAIN_ID"), warning
        assert "drives another robot than 'tomasi-omni3'" in warning and "the page sends it no cmd_vel" in warning
        assert view.poll() is None  # and it goes on serving
    finally:
        if node is not None:
            err = stop(node)
            assert "Traceback" not in err, err[-2000:]
        err = stop(view)
        assert "Traceback" not in err, err[-2000:]
