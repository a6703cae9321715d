"""``omnikin ros tomasi-omni3-lidar --backend physics --world W`` on a real ROS 2 graph: the node
publishes ``scan`` and ``imu`` as the physics reads them, in the sensors' frames, which the
URDF on ``robot_description`` holds as fixed links of ``base_link``.

Closed form: the robot stands at the world's start pose in a square room of inner half-width
1.95 m, its lidar at the body origin facing along the body's x axis; a beam at angle a from the
heading meets the faces at ``min((1.95 - x) / cos, ...)`` (by hand, as in
``tests/sensors/test_lidar.py``). The preset's range noise (0.01 m) and dropouts (1 %) are
random: each beam within 6 standard deviations, the median error within 0.01 m.
"""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics back-end needs MuJoCo (extra 'physics')")

from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402 (after the importorskips)
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import Imu, LaserScan  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from test_ros_node import (  # noqa: E402 (after the importorskips there and above)
    RELIABLE_ALL,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    start,
    wait_for,
)

from support.rooms import to_faces  # noqa: E402

pytestmark = pytest.mark.ros

WORLD = """\
omnikin_world: 1
name: box-room
start: [0.3, -0.2, 20]
walls:
  - {points: [[-2, -2], [2, -2], [2, 2], [-2, 2], [-2, -2]], thickness: 0.1, height: 0.5}
"""
FACE = 1.95
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class Collect:
    """The test side's subscription to one topic: every message with its receive time."""

    def __init__(self, graph, kind, topic: str, qos=RELIABLE_ALL):
        self.lock = threading.Lock()
        self.msgs: list = []
        graph.node.create_subscription(kind, topic, self._on, qos)

    def _on(self, msg):
        with self.lock:
            self.msgs.append(msg)

    def all(self) -> list:
        with self.lock:
            return list(self.msgs)


def test_the_physics_node_publishes_scans_of_its_world_and_imu_readings_in_the_sensor_frames(tmp_path):
    (tmp_path / "room.yaml").write_text(WORLD)
    proc, graph = start(tmp_path, ["tomasi-omni3-lidar", "--backend", "physics", "--world", "room.yaml"])
    try:
        scans = Collect(graph, LaserScan, "scan")
        imus = Collect(graph, Imu, "imu")
        description = Collect(graph, String, "robot_description", LATCHED)
        assert wait_for(lambda: len(scans.all()) >= 5 and len(imus.all()) >= 200, 15.0), (
            f"{len(scans.all())} scans, {len(imus.all())} IMU readings\n{proc.stderr()}"
        )
        scan = scans.all()[-1]
        assert scan.header.frame_id == "laser"
        assert scan.angle_min == pytest.approx(-math.pi) and scan.angle_increment == pytest.approx(math.radians(1.0))
        assert len(scan.ranges) == 360 and scan.range_max == pytest.approx(12.0)
        assert scan.scan_time == pytest.approx(0.1)
        # the robot stands at the start pose (the world file's heading in degrees)
        angles = math.radians(20.0) + scan.angle_min + np.arange(360) * scan.angle_increment
        expected = to_faces(0.3, -0.2, angles, FACE)
        ranges = np.array(scan.ranges, dtype=float)
        seen = np.isfinite(ranges)
        assert seen.sum() >= 340  # 1 % dropouts (NaN)
        error = ranges[seen] - expected[seen]
        assert np.all(np.abs(error) < 0.06) and abs(float(np.median(error))) < 0.01, error
        # IMU: 200 Hz in its own frame, gravity on z, no turn
        readings = imus.all()
        assert {m.header.frame_id for m in readings} == {"imu"}
        stamps = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in readings])
        steps = np.diff(stamps)
        assert np.all(steps > 0) and np.median(steps) == pytest.approx(0.005, abs=2e-4)
        accel = np.array([[v.x, v.y, v.z] for v in (m.linear_acceleration for m in readings)])
        gyro = np.array([[v.x, v.y, v.z] for v in (m.angular_velocity for m in readings)])
        assert accel[:, 2].mean() == pytest.approx(9.81, abs=0.3)  # the preset's bias: 0.05 m/s^2
        assert np.abs(gyro.mean(axis=0)).max() < 0.03  # its bias: 0.005 rad/s
        assert readings[-1].orientation_covariance[0] == -1.0  # orientation unknown (REP 145)
        # the URDF holds the sensors' frames, fixed on base_link at their mounts
        assert wait_for(lambda: description.all(), 5.0)
        urdf = description.all()[-1].data
        assert '<joint name="laser_joint" type="fixed">' in urdf and '<child link="laser" />' in urdf
        assert '<joint name="imu_joint" type="fixed">' in urdf
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        rc, _ = proc.terminate()
        assert rc == 0, proc.stderr()


def _seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def test_with_use_sim_time_the_physics_node_is_the_clock_and_stamps_everything_in_simulated_time(tmp_path):
    """``--ros-args -p use_sim_time:=true``: ``/clock`` counts simulated seconds from 0 (not the
    wall clock's 1.7e9), and the odometry, the scans (at k / 10 s exactly) and the IMU readings
    (at j / 200 s) are stamped on it."""
    (tmp_path / "room.yaml").write_text(WORLD)
    args = ["tomasi-omni3-lidar", "--backend", "physics", "--world", "room.yaml"]
    proc, graph = start(tmp_path, [*args, "--ros-args", "-p", "use_sim_time:=true"])
    try:
        clocks = Collect(graph, Clock, "/clock")
        scans = Collect(graph, LaserScan, "scan")
        imus = Collect(graph, Imu, "imu")
        odoms = Collect(graph, Odometry, "odom")
        assert wait_for(lambda: len(scans.all()) >= 5 and min(len(odoms.all()), len(clocks.all())) >= 20, 15.0), (
            proc.stderr()
        )
        ticks = np.array([_seconds(m.clock) for m in clocks.all()])
        assert np.all(np.diff(ticks) >= 0) and ticks[-1] >= 0.3
        assert ticks[-1] < 1000.0  # simulated seconds since the start, not the system clock
        for stamp in (_seconds(m.header.stamp) for m in odoms.all()):
            assert 0.0 <= stamp <= ticks[-1] + 1.0
        scan_times = np.array([_seconds(m.header.stamp) for m in scans.all()])
        np.testing.assert_allclose(scan_times * 10.0, np.round(scan_times * 10.0), atol=1e-6)
        imu_times = np.array([_seconds(m.header.stamp) for m in imus.all()])
        np.testing.assert_allclose(imu_times * 200.0, np.round(imu_times * 200.0), atol=1e-5)
        assert np.all(np.diff(imu_times) > 0)
        assert "Traceback" not in proc.stderr()
    finally:
        graph.close()
        rc, _ = proc.terminate()
        assert rc == 0, proc.stderr()
