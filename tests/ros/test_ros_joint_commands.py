"""ros2_control's topic-based hardware interface: wheel speeds on ``joint_commands``
(``sensor_msgs/JointState``, one velocity per wheel joint of ``joint_states``) drive the robot
as the body twist they imply, through the node's limits and timeout.

Closed form (as ``test_ros_node.py``'s cmd_vel timeout test): a forward command held from
``first`` to ``last`` and then left to time out covers ``v (last - first + cmd_vel_timeout)``
along +x, the acceleration and braking ramps being mirror images.
"""

from __future__ import annotations

import time

import pytest
from test_ros_node import (
    RELIABLE_ALL,
    _ros_environment,  # noqa: F401 (the module's ROS environment, autouse)
    start,
    wait_for,
)

from omnikin import load_robot

pytest.importorskip("sensor_msgs.msg", reason="the ROS 2 node tests need the message packages")

from sensor_msgs.msg import JointState  # noqa: E402

pytestmark = pytest.mark.ros

V = 0.2
TIMEOUT = 0.5  # cmd_vel_timeout, the default


def test_wheel_speeds_on_joint_commands_drive_the_robot_and_bad_ones_are_counted(tmp_path):
    robot = load_robot("tomasi-omni3")
    speeds = robot.ik((V, 0.0, 0.0)).wheel_speeds
    proc, g = start(tmp_path, ["tomasi-omni3", "--errors", "none", "--noise", "none"])
    try:
        pub = g.node.create_publisher(JointState, "joint_commands", RELIABLE_ALL)
        assert wait_for(lambda: pub.get_subscription_count() >= 1, 10.0), proc.stderr()

        def send(names, velocities) -> float:
            msg = JointState()
            msg.name, msg.velocity = list(names), [float(v) for v in velocities]
            pub.publish(msg)
            return time.monotonic()

        m0 = g.wait_still()
        before = g.next_diag()[2]
        # w3 missing: ignored and counted; sent until the node counts one (it hears this publisher)
        assert wait_for(
            lambda: send(["w1", "w2"], speeds[:2]) and int(g.last_diag()[2]["joint_commands_rejected"]) > 0, 10.0
        )
        first = last = send(["w3", "w1", "w2"], [speeds[2], speeds[0], speeds[1]])
        while time.monotonic() - first < 1.0:
            time.sleep(0.05)
            last = send(["w1", "w2", "w3"], speeds)
        assert wait_for(lambda: g.last_odom().twist.twist.linear.x > 0.5 * V, 2.0), "the node did not answer"
        m1 = g.wait_still(timeout=10.0)
        dx = m1.pose.pose.position.x - m0.pose.pose.position.x
        dy = m1.pose.pose.position.y - m0.pose.pose.position.y
        assert dx == pytest.approx(V * (last - first + TIMEOUT), abs=0.02), (dx, last - first)
        assert abs(dy) < 1e-3
        after = g.next_diag()[2]
        assert int(after["joint_commands_rejected"]) > int(before["joint_commands_rejected"])
        assert "no velocity for the wheel joint(s) w3" in proc.stderr()
        assert "Traceback" not in proc.stderr()
    finally:
        g.close()
        proc.close()
