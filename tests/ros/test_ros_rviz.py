"""What rviz2 needs from ``omnikin ros`` without robot_state_publisher, on a real ROS 2 graph:
the URDF on ``robot_description`` for a subscriber that comes late (transient local), and every
movable joint of that URDF on ``joint_states``, the rollers turned as the body motion implies.

The node processes and the test side are those of test_ros_node.py (random domain, discovery on
this host, every process ended at the end of its test or module, also on failure). /tf needs
``tf2_msgs``, which the PyPI wheels lack: the links' transforms are checked without ROS
(test_link_frames.py), the joints they are computed from here.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from test_ros_node import _domain as _unused_domain
from test_ros_node import _ros_environment, rclpy, start, wait_for, yaw_of  # noqa: F401 (_ros_environment: autouse fixture)
from urdf_parser_py.urdf import URDF

from omnikin import load_robot
from omnikin.physics.urdf import urdf

pytest.importorskip("std_msgs.msg", reason="the ROS 2 node tests need the message packages")

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402

pytestmark = pytest.mark.ros

LATE = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)  # what rviz2's RobotModel asks for with the shipped configuration


def movable_joints(robot) -> set:
    return {j.name for j in URDF.from_xml_string(urdf(robot)).joints if j.type != "fixed"}


@pytest.fixture(scope="module")
def omni3(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rviz_omni3")
    proc, graph = start(tmp, ["tomasi-omni3", "--errors", "none", "--noise", "none"])
    try:
        yield proc, graph
    finally:
        graph.close()
        proc.close()


def test_a_late_subscriber_gets_the_urdf_on_robot_description(omni3):
    _, g = omni3
    time.sleep(1.0)  # the node published it at its start, long before this subscription
    got: list = []
    g.node.create_subscription(String, "robot_description", lambda m: got.append(m.data), LATE)
    assert wait_for(lambda: got, 10.0), "no robot_description for a late transient-local subscriber"
    assert got[0] == urdf(load_robot("tomasi-omni3"))
    time.sleep(0.5)
    assert len(got) == 1  # published once


def test_joint_states_carry_every_movable_urdf_joint(omni3):
    _, g = omni3
    assert wait_for(lambda: len(g.joints) >= 3, 5.0)
    js = g.joints[-1][1]
    assert len(js.name) == len(set(js.name)) == len(js.position) == len(js.velocity)
    assert set(js.name) == movable_joints(load_robot("tomasi-omni3"))
    assert list(js.name)[:3] == ["w1", "w2", "w3"]  # the measured joints first, as before


def _settled(g):
    """The last odometry and joint_states once the robot stands still and both were published after."""
    g.wait_still()
    time.sleep(0.3)
    with g.lock:
        return g.odom[-1][1], g.joints[-1][1]


def test_rollers_turn_by_the_sideways_distance_over_their_radius(omni3):
    """omni3 driven sideways by dy (body y; it does not turn): the rim point of wheel i at the
    contact moves across its rollers' axis (the drive direction u_i) at v . n_i, n_i = (-sin d_i,
    cos d_i); the roller of radius b spins that back to no slip, so every roller of wheel i turns
    by -(dy cos d_i) / b. d_i (the wheel joint's yaw) and b (the roller's collision sphere) from
    the URDF."""
    _, g = omni3
    robot = load_robot("tomasi-omni3")
    parsed = URDF.from_xml_string(urdf(robot))
    joints = {j.name: j for j in parsed.joints}
    odom0, js0 = _settled(g)
    g.drive(vy=0.15, duration=1.5)
    g.send(0.0)
    odom1, js1 = _settled(g)
    p0, p1 = odom0.pose.pose.position, odom1.pose.pose.position
    yaw = yaw_of(odom1.pose.pose.orientation)
    assert abs(yaw) < 1e-3 and abs(yaw_of(odom0.pose.pose.orientation)) < 1e-3
    dx, dy = p1.x - p0.x, p1.y - p0.y
    assert dy > 0.15  # it moved; along body y
    before = dict(zip(js0.name, js0.position, strict=True))
    after = dict(zip(js1.name, js1.position, strict=True))
    checked = 0
    for wheel in ("w1", "w2", "w3"):
        d = joints[wheel].origin.rpy[2]
        n = np.array([-math.sin(d), math.cos(d)])
        b = parsed.link_map[f"{wheel}_roller_0_0"].collisions[0].geometry.radius
        want = -(n @ [dx, dy]) / b
        rollers = [name for name in after if name.startswith(f"{wheel}_roller_")]
        assert len(rollers) == 12
        for name in rollers:
            assert after[name] - before[name] == pytest.approx(want, rel=2e-3, abs=2e-3), (name, want)
            checked += 1
    assert checked == 36


@pytest.mark.parametrize("name", ["diff-drive", "ackermann", "xr4000"])
def test_joint_states_carry_every_movable_urdf_joint_of_castors_and_steered_wheels(tmp_path, name):
    proc, g = start(tmp_path, [name, "--errors", "none", "--noise", "none"])
    try:
        assert wait_for(lambda: len(g.joints) >= 3, 5.0)
        js = g.joints[-1][1]
        assert len(js.name) == len(set(js.name)) == len(js.position) == len(js.velocity)
        assert set(js.name) == movable_joints(load_robot(name))
        assert all(math.isfinite(v) for v in [*js.position, *js.velocity])
    finally:
        g.close()
        proc.close()


@pytest.mark.parametrize("name", ["tomasi-omni3", "diff-drive", "xr4000"])
def test_the_nodes_link_transforms_place_every_urdf_link_at_the_joint_positions(name):
    """The node in this process, on rclpy's default context (/tf itself needs tf2_msgs, which
    the PyPI wheels lack): one control step, then the transforms it would publish on /tf name
    every link of the URDF but base_link as a child, each at its joint's origin in its parent,
    and a second call within 1 / link_tf_rate publishes none."""
    from omnikin.ros.node import BaseNode
    from omnikin.ros.params import DEFAULTS
    from omnikin.simulation.backend import SimBackend
    from omnikin.simulation.error_models import noise_profile

    robot = load_robot(name)
    parsed = URDF.from_xml_string(urdf(robot))
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(domain_id=_unused_domain(), signal_handler_options=SignalHandlerOptions.NO)  # the node's default context
    node = None
    try:
        node = BaseNode(robot, SimBackend(robot, None, noise_profile("none")), dict(DEFAULTS), name="rviz_probe")
        res = node.runtime.step(time.monotonic())
        steer = [] if res.state.steer is None else list(res.state.steer)
        implied, _ = node.joint_motion.update(res.state.t, res.twist, res.state.steer)
        positions = [*res.state.positions, *steer, *implied]
        stamp = node.get_clock().now().to_msg()
        transforms = node._link_transforms(stamp, positions)
        assert {t.child_frame_id for t in transforms} | {"base_link"} == {link.name for link in parsed.links}
        origin = {j.child: (j.parent, j.origin.xyz) for j in parsed.joints}
        for t in transforms:
            parent, xyz = origin[t.child_frame_id]
            assert t.header.frame_id == parent
            tr = t.transform.translation
            assert [tr.x, tr.y, tr.z] == pytest.approx(xyz, abs=1e-15)
        assert node._link_transforms(stamp, positions) == []
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.shutdown()
