"""``omnikin ros`` follows a ``nav_msgs/Path`` on ``plan`` on a real ROS 2 graph: the node in its own
process (the exact kinematic back-end), the test publishing the path and recording
``ground_truth``, ``reference``, ``reference_path`` and the ``omnikin path`` status of
``/diagnostics``.

Expected values are the path's own geometry: the distance of the true poses to the segments
between the waypoints (written here), the path's length (the sum of its segments), its end. The
node runs on the wall clock, so a control cycle that comes late on a busy machine shows as a
tracking error: the tolerances (1 cm at the end after settling, 2 cm along the way on a path
driven at 0.3 m/s) hold for cycles up to some 30 ms late.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

pytest.importorskip("rclpy", reason='the ROS 2 node tests need rclpy (pip install -e ".[ros]", Linux x86_64)')

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402 (after the importorskip)
from geometry_msgs.msg import PoseStamped  # noqa: E402
from nav_msgs.msg import Path as PathMessage  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from test_ros_node import (  # noqa: E402
    RELIABLE_ALL,
    Odometry,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    start,
    wait_for,
    yaw_of,
)

from support.kinematics import distance_to_polyline  # noqa: E402

pytestmark = pytest.mark.ros

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
EXACT = ["--errors", "none", "--noise", "none"]


class PathSide:
    """The test's side of path following: publishes ``plan``, records what the node answers."""

    def __init__(self, graph):
        self.graph = graph
        self.lock = threading.Lock()
        self.truth: list = []  # (receive time [monotonic s], (x, y, theta))
        self.references: list = []
        self.reference_paths: list = []
        self.status: list = []  # (receive time, level, message, {key: value})
        node = graph.node
        node.create_subscription(Odometry, "ground_truth", self._on_truth, RELIABLE_ALL)
        node.create_subscription(PoseStamped, "reference", self._on_reference, RELIABLE_ALL)
        node.create_subscription(PathMessage, "reference_path", self._on_reference_path, LATCHED)
        node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diagnostics, 10)
        self.pub = node.create_publisher(PathMessage, "plan", 10)

    def _on_truth(self, msg):
        p = msg.pose.pose
        with self.lock:
            self.truth.append((time.monotonic(), (p.position.x, p.position.y, yaw_of(p.orientation))))

    def _on_reference(self, msg):
        with self.lock:
            self.references.append(msg)

    def _on_reference_path(self, msg):
        with self.lock:
            self.reference_paths.append(msg)

    def _on_diagnostics(self, msg):
        for st in msg.status:
            if st.name == "omnikin path":
                with self.lock:
                    self.status.append(
                        (time.monotonic(), st.level[0], st.message, {kv.key: kv.value for kv in st.values})
                    )

    def send(self, waypoints, frame: str = "odom") -> float:
        """Publish a path through ``waypoints`` ``(x, y[, theta])``; when [monotonic s]."""
        msg = PathMessage()
        msg.header.frame_id = frame
        msg.header.stamp = self.graph.node.get_clock().now().to_msg()
        for w in waypoints:
            pose = PoseStamped()
            pose.header.frame_id = frame
            pose.pose.position.x, pose.pose.position.y = float(w[0]), float(w[1])
            theta = float(w[2]) if len(w) > 2 else 0.0
            pose.pose.orientation.z, pose.pose.orientation.w = math.sin(theta / 2), math.cos(theta / 2)
            msg.poses.append(pose)
        assert wait_for(lambda: self.pub.get_subscription_count() >= 1, 20.0), "plan has no subscriber"
        now = time.monotonic()
        self.pub.publish(msg)
        return now

    def state(self, after: float, predicate, timeout: float, what: str):
        """The first ``omnikin path`` status received after ``after`` that ``predicate`` accepts."""

        def found():
            with self.lock:
                return next((s for s in self.status if s[0] > after and predicate(s)), None)

        assert wait_for(lambda: found() is not None, timeout), (
            f"no path status {what}: {self.status[-3:]} (base: {self.graph.diags[-1:]})"
        )
        return found()

    def truth_since(self, after: float) -> np.ndarray:
        with self.lock:
            return np.array([p for t, p in self.truth if t > after])


def test_a_path_on_plan_is_driven_to_its_end_with_its_reference_and_error_published(tmp_path):
    corners = [(0.0, 0.0), (0.6, 0.0), (0.6, 0.4)]
    proc, graph = start(tmp_path, ["tomasi-omni3", *EXACT, "--ros-args", "-p", "path_smooth:=false"])
    try:
        side = PathSide(graph)
        sent = side.send([(x, y, 0.0) for x, y in corners])
        following = side.state(sent, lambda s: s[3]["path_state"] == "following", 30.0, "following")
        assert float(following[3]["path_length_m"]) == pytest.approx(1.0, abs=1e-3)  # 0.6 + 0.4 m
        duration = float(following[3]["path_duration_s"])
        done = side.state(sent, lambda s: s[3]["path_state"] == "done", duration + 60.0, "done")
        assert done[1] == 0 and done[2].startswith("done path 'plan' (1 m in")
        truth = side.truth_since(sent)
        assert truth[-1][:2] == pytest.approx(corners[-1], abs=0.01)
        assert distance_to_polyline(truth[:, :2], corners).max() < 0.02
        assert float(done[3]["max_distance_to_path_m"]) < 0.02  # the odometry's, the node's own measure
        # the timed reference: stamped from the start to the end of the trajectory, ending at the end
        assert wait_for(lambda: side.reference_paths, 10.0), "no reference_path"
        ref = side.reference_paths[-1]
        stamps = np.array([p.header.stamp.sec + 1e-9 * p.header.stamp.nanosec for p in ref.poses])
        assert np.all(np.diff(stamps) > 0) and stamps[-1] - stamps[0] == pytest.approx(
            duration, rel=1e-5
        )  # (status: 6 digits)
        last = ref.poses[-1].pose.position
        assert (last.x, last.y) == pytest.approx(corners[-1], abs=1e-9)
        assert ref.header.frame_id == "odom" and len(side.references) > 10
    finally:
        graph.close()
        proc.close()


def test_a_cmd_vel_or_an_empty_path_stops_the_path_followed(tmp_path):
    proc, graph = start(tmp_path, ["omni4", *EXACT])
    try:
        side = PathSide(graph)
        sent = side.send([(0.0, 0.0), (3.0, 0.0)])
        side.state(sent, lambda s: s[3]["path_state"] == "following", 30.0, "following")
        first, last = graph.drive(vy=0.1, duration=0.5)
        stopped = side.state(last, lambda s: s[3]["path_state"] == "stopped", 10.0, "stopped by cmd_vel")
        assert stopped[3]["path_note"] == "a cmd_vel arrived (the person at the keyboard wins)"
        still = graph.wait_still(timeout=20.0)
        assert still.pose.pose.position.x < 2.0 and still.pose.pose.position.y > 0.02  # the keyboard drove it sideways

        sent = side.send([(0.0, 0.0), (3.0, 0.0)])
        side.state(sent, lambda s: s[3]["path_state"] == "following", 30.0, "following again")
        sent = side.send([])
        stopped = side.state(sent, lambda s: s[3]["path_state"] == "stopped", 10.0, "stopped by an empty path")
        assert stopped[3]["path_note"] == "an empty path arrived"
        graph.wait_still(timeout=20.0)
    finally:
        graph.close()
        proc.close()


@pytest.mark.parametrize(
    ("robot", "waypoints", "frame", "note"),
    [
        (["omni4"], [(1.0, 0.0)], "map", "a path in frame 'map': this node follows paths in its odometry frame 'odom'"),
        (["omni4"], [(1.0, 0.0), (1.0, math.nan)], "odom", "path 'plan': waypoint 1 is not finite"),
        (["omni4"], [(0.0005, 0.0)], "odom", "path 'plan': it does not go anywhere"),
        (
            ["diff-drive", "--ros-args", "-p", "path_smooth:=false"],
            [(0.0, 1.0)],
            "odom",
            "path 'plan' leaves the robot at 90 deg, but robot 'diff-drive' faces 0",
        ),
    ],
)
def test_a_path_that_cannot_be_followed_is_refused_with_a_warning_and_the_robot_stays(
    tmp_path, robot, waypoints, frame, note
):
    proc, graph = start(tmp_path, [robot[0], *EXACT, *robot[1:]])
    try:
        side = PathSide(graph)
        sent = side.send(waypoints, frame)
        refused = side.state(sent, lambda s: s[3]["path_state"] == "refused", 30.0, "refused")
        assert refused[1] == 1 and refused[3]["path_note"].startswith(note), refused[3]
        assert refused[2].startswith("path refused: ")
        odom = graph.wait_still(timeout=20.0)
        assert (odom.pose.pose.position.x, odom.pose.pose.position.y) == (0.0, 0.0)
        assert proc.proc.poll() is None  # still running
    finally:
        graph.close()
        proc.close()
