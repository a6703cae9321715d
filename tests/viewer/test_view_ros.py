"""``omnikin view ROBOT --ros`` follows a running ``omnikin ros`` node and drives it: real nodes
(the node, simulating the robot as its file says, and the viewer's own) on a ROS domain of their
own, the page in headless Chromium.

The node's runtime ramps its command at its acceleration limit (0.5 m/s^2, its default) from
the first cmd_vel and back to zero from the zero the page sends at the release, so the robot
covers ``v T`` in all, ``T`` the time the page held the key.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest

from browser import hold_key, record_keys, recorded_keys, wait_for
from omnikin_paths import omnikin_env
from ros_domain import fresh_domain

pytestmark = pytest.mark.ros
SPEED = 0.2
READOUT = "#omnikin-readout"


def readout(page) -> dict:
    return page.evaluate(f"(() => {{ const d = document.querySelector('{READOUT}').dataset; return {{...d}}; }})()")


@pytest.fixture
def ros_env(tmp_path):
    """A ROS domain of this test's own (:func:`ros_domain.fresh_domain`), discovery on this host,
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


def test_the_ros_view_follows_a_node_and_its_keys_drive_it(ros_env, page, page_log, tmp_path):
    procs = []
    try:
        node = subprocess.Popen(
            [sys.executable, "-m", "omnikin.cli.main", "ros", "tomasi-omni3", "--errors", "none", "--noise", "none"],
            env=ros_env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
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
        time.sleep(2.0)  # discovery: the node's subscription to the viewer's cmd_vel
        before = readout(page)
        record_keys(page)
        hold_key(page, "w", 1.2)
        time.sleep(SPEED / 0.5 + 0.6)
        wait_for(page, f"Number(document.querySelector('{READOUT}').dataset.vx) === 0", timeout=10)
        after = readout(page)
        events = [e for e in recorded_keys(page) if e["key"] == "w" and not e["repeat"]]
        held = events[-1]["handled"] - events[0]["handled"]
        # the page shows the node's ground truth as the robot and its odometry beside it
        assert float(after["x"]) - float(before["x"]) == pytest.approx(SPEED * held, abs=SPEED * 0.15)
        assert float(after["odomX"]) - float(before["odomX"]) == pytest.approx(SPEED * held, abs=SPEED * 0.15)
        assert abs(float(after["y"]) - float(before["y"])) < 1e-6  # the robot as the file says (no errors)
        assert page_log.external == [] and page_log.page_errors == []
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                _, err = proc.communicate(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, 9) if proc is node else proc.kill()
                _, err = proc.communicate()
            assert "Traceback" not in (err or ""), (err or "")[-2000:]


def start_node(robot: str, env: dict) -> subprocess.Popen:
    """``omnikin ros ROBOT`` (simulated, exact) on the test's domain."""
    return subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "ros", robot, "--errors", "none", "--noise", "none"],
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

    from omnikin.ros.link_frames import urdf_joints

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


@pytest.fixture
def ros_discovery(monkeypatch, tmp_path):
    """This test process's own rclpy context finds the nodes on this host only, logs in tmp_path."""
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "test_ros_log"))
    monkeypatch.delenv("ROS_LOCALHOST_ONLY", raising=False)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)


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
