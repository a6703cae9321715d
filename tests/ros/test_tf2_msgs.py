"""``omnikin tf2-msgs``: tf2_msgs built from its ``.msg`` with the ROS 2 wheels from PyPI
(``.ci/run`` builds it before the tests, as a system package), and the node's ``/tf`` and
``/tf_static`` on a real ROS 2 graph with it: the type hash of ROS 2's own TFMessage, odom ->
base_link and every URDF link, the sensors' frames at their mounts.

The hash is ROS 2's: ``RIHS01_e369d0f0...`` is what Humble, Jazzy and Kilted give for
``tf2_msgs/msg/TFMessage`` (rosbags' type stores compute the same from the message definition).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from omnikin.ros.interfaces import build_stamp, build_tf2_msgs, built_here, exports, tf2_msgs_importable
from support.cli import run_cli

TF_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"

needs_tf2 = pytest.mark.skipif(
    not tf2_msgs_importable(), reason="tf2_msgs is not built for this Python: run omnikin tf2-msgs (docs/ros.md)"
)

WORLD = """\
omnikin_world: 1
name: box-room
start: [0, 0, 0]
walls:
  - {points: [[-2, -2], [2, -2], [2, 2], [-2, 2], [-2, -2]], thickness: 0.1, height: 0.5}
"""


@needs_tf2
def test_a_second_build_for_this_python_and_these_wheels_does_nothing():
    """Into the prefix the tests' tf2_msgs comes from (``.ci/run``'s: the Python's own, which
    needs no environment)."""
    import tf2_msgs

    prefix = Path(tf2_msgs.__file__).resolve().parents[4]  # PREFIX/lib/pythonX.Y/site-packages/tf2_msgs
    assert (prefix / "share" / "tf2_msgs" / "build_stamp.txt").is_file(), f"{prefix}: not built by omnikin tf2-msgs"
    build = build_tf2_msgs(prefix)
    assert build.built is False and build.seconds < 30.0
    assert build.exports == exports(prefix) and (build.exports == ()) == (prefix == Path(sys.prefix).resolve())


def test_a_build_without_its_tools_or_with_a_prefix_it_cannot_write_is_refused_in_one_line(tmp_path, capsys):
    # no cmake, make or compilers on the PATH: each named with how to install it
    done = subprocess.run(
        [sys.executable, "-c", "from omnikin.cli.main import main; raise SystemExit(main())", "tf2-msgs"]
        + ["--prefix", str(tmp_path / "prefix")],
        env={"PATH": str(tmp_path), "HOME": str(tmp_path)}
        | {k: v for k, v in os.environ.items() if k in ("PYTHONPATH", "LD_LIBRARY_PATH")},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert "\n" not in line and "Traceback" not in line
    assert "missing" in line and "cmake 3.21 or later" in line and "apt-get install g++" in line
    assert not (tmp_path / "prefix").exists()  # refused before anything was made
    bad = (("", "--prefix is empty"), ("~no-such-user-here/x", "~no-such-user-here"), ("a:b", "holds ':'"))
    for prefix, problem in bad:
        rc, _, err = run_cli(capsys, "tf2-msgs", "--prefix", prefix)
        assert rc == 2 and problem in err and err.count("\n") == 1 and "internal error" not in err, err
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    rc, _, err = run_cli(capsys, "tf2-msgs", "--prefix", blocker / "below")
    assert rc == 2 and "cannot write to" in err and err.count("\n") == 1
    rc, _, err = run_cli(capsys, "tf2-msgs", "--jobs", "0")
    assert rc == 2 and "jobs" in err


@needs_tf2
@pytest.mark.ros
def test_the_node_publishes_tf_of_every_link_and_the_sensors_static_frames_with_ros2s_type_hash(tmp_path):
    pytest.importorskip("mujoco", reason="the physics back-end needs MuJoCo (extra 'physics')")
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from test_ros_node import RELIABLE_ALL, start, wait_for
    from tf2_msgs.msg import TFMessage

    (tmp_path / "room.yaml").write_text(WORLD)
    proc, graph = start(tmp_path, ["tomasi-omni3-lidar", "--backend", "physics", "--world", "room.yaml"])
    try:
        lock = threading.Lock()
        dynamic: dict = {}
        static: dict = {}

        def keep(into):
            def on(msg):
                with lock:
                    for t in msg.transforms:
                        into[(t.header.frame_id, t.child_frame_id)] = t

            return on

        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        graph.node.create_subscription(TFMessage, "/tf", keep(dynamic), RELIABLE_ALL)
        graph.node.create_subscription(TFMessage, "/tf_static", keep(static), latched)

        def arrived() -> bool:
            with lock:
                return ("odom", "base_link") in dynamic and ("base_link", "w1_wheel") in dynamic and len(static) >= 2

        assert wait_for(arrived, 15.0), proc.stderr()
        infos = graph.node.get_publishers_info_by_topic("/tf")
        assert infos and {str(i.topic_type_hash) for i in infos} == {TF_HASH}
        with lock:
            children = {child for _, child in dynamic}
            frames = dict(static)
        # the wheels and their rollers move: every one of them is on /tf
        assert {"w1_wheel", "w2_wheel", "w3_wheel"} <= children
        assert any("_roller_" in c for c in children)
        # the sensors' frames: fixed on base_link at the preset's mounts
        laser = frames[("base_link", "laser")].transform
        assert laser.translation.z == pytest.approx(0.12) and abs(laser.translation.x) < 1e-12
        assert math.isclose(laser.rotation.w, 1.0)
        assert ("base_link", "imu") in frames
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        proc.close()


def test_a_build_counts_as_there_only_while_every_file_it_installed_is(tmp_path):
    """The stamp alone does not vouch for a build: a removed (or half-installed) one is built
    again."""
    share = tmp_path / "share" / "tf2_msgs"
    share.mkdir(parents=True)
    installed = [tmp_path / "lib" / "libtf2_msgs__rosidl_generator_c.so", tmp_path / "lib" / "x.py"]
    installed[0].parent.mkdir()
    for f in installed:
        f.write_text("")
    (share / "install_manifest.txt").write_text("\n".join(str(f) for f in installed) + "\n")
    stamp = build_stamp()
    (share / "build_stamp.txt").write_text(stamp)
    assert built_here(tmp_path, stamp)
    assert not built_here(tmp_path, stamp + "another wheel 1.0\n")
    installed[1].unlink()
    assert not built_here(tmp_path, stamp)


def test_the_printed_environment_lines_keep_any_prefix_as_it_is(tmp_path):
    """A prefix with spaces, quotes, $(...) or backticks is set as it is by the lines printed for
    the shell, and runs nothing."""
    odd = tmp_path / 'a "b" $(touch pwned) `touch pwned2` c'
    for line in exports(odd):
        name = line.split()[1].split("=")[0]
        done = subprocess.run(
            ["bash", "-c", f'{line}; printf %s "${name}"'], cwd=tmp_path, env={}, capture_output=True, text=True
        )
        assert done.returncode == 0 and done.stdout.startswith(str(odd)), (line, done.stdout)
    assert not (tmp_path / "pwned").exists() and not (tmp_path / "pwned2").exists()
