"""Content of the node's messages (``omnikin.ros.messages``), without rclpy.

Expected values are closed forms written out by hand: the quaternion of a yaw, where the
(x, y, yaw) block lands in ROS's 6 x 6 covariance, the diagnostics level rules, the mapping of
a command's stamp onto the runtime's clock.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.ros import messages as m

H = math.sqrt(0.5)


def rotate(q, v):
    """``v`` rotated by the unit quaternion ``q = (x, y, z, w)``: ``q v q*`` written out."""
    x, y, z, w = q
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return r @ np.asarray(v, dtype=float)


@pytest.mark.parametrize(
    "theta, expected",
    [
        (0.0, (0.0, 0.0, 0.0, 1.0)),
        (math.pi / 2, (0.0, 0.0, H, H)),
        (-math.pi / 2, (0.0, 0.0, -H, H)),
        (math.pi, (0.0, 0.0, 1.0, 0.0)),
        (2 * math.pi / 3, (0.0, 0.0, math.sqrt(3) / 2, 0.5)),
        (2 * math.pi, (0.0, 0.0, 0.0, -1.0)),  # the same rotation as 0, the other sign
    ],
)
def test_quaternion_of_a_yaw(theta, expected):
    q = m.quaternion(theta)
    assert q == pytest.approx(expected, abs=1e-15)
    # it turns the x axis to (cos theta, sin theta, 0) and leaves z alone
    assert rotate(q, (1, 0, 0)) == pytest.approx([math.cos(theta), math.sin(theta), 0.0], abs=1e-15)
    assert rotate(q, (0, 0, 1)) == pytest.approx([0.0, 0.0, 1.0], abs=1e-15)


def test_covariance6_places_x_y_yaw_at_rows_0_1_5_and_symmetrises():
    c3 = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]  # not symmetric: its symmetric part is published
    out = m.covariance6(c3)
    assert len(out) == 36 and all(type(v) is float for v in out)
    expected = [0.0] * 36
    for (r, c), v in {
        (0, 0): 1.0,
        (0, 1): 3.0,
        (0, 5): 5.0,
        (1, 0): 3.0,
        (1, 1): 5.0,
        (1, 5): 7.0,
        (5, 0): 5.0,
        (5, 1): 7.0,
        (5, 5): 9.0,
    }.items():
        expected[6 * r + c] = v  # row-major (x, y, z, roll, pitch, yaw)
    assert out == expected


def test_covariance6_refuses_a_wrong_shape():
    with pytest.raises(InputError, match="3 x 3"):
        m.covariance6(np.eye(6))


def test_odometry_content():
    pose_cov = np.diag([0.01, 0.04, 0.09])
    twist_cov = np.diag([1e-4, 4e-4, 9e-4])
    c = m.odometry_content((1.5, -2.0, math.pi / 2), (0.1, 0.2, -0.3), pose_cov, twist_cov)
    assert c["position"] == (1.5, -2.0, 0.0)
    assert c["orientation"] == pytest.approx((0.0, 0.0, H, H), abs=1e-15)
    assert c["linear"] == (0.1, 0.2, 0.0)
    assert c["angular"] == (0.0, 0.0, -0.3)
    assert [c["pose_covariance"][i] for i in (0, 7, 35)] == [0.01, 0.04, 0.09]
    assert [c["twist_covariance"][i] for i in (0, 7, 35)] == [1e-4, 4e-4, 9e-4]
    assert sum(1 for v in c["pose_covariance"] if v != 0.0) == 3


def test_transform_content():
    c = m.transform_content((0.25, 0.5, -math.pi))
    assert c["translation"] == (0.25, 0.5, 0.0)
    assert c["rotation"] == pytest.approx((0.0, 0.0, -1.0, 0.0), abs=1e-15)


def test_joint_state_content_wheels_then_steering_joints():
    names, pos, vel = m.joint_state_content(
        ["front", "rear"], np.array([1.0, 2.0]), np.array([3.0, -4.0]), ["front_steer"], np.array([0.5])
    )
    assert names == ["front", "rear", "front_steer"]
    assert pos == [1.0, 2.0, 0.5]
    assert vel == [3.0, -4.0, 0.0]
    assert all(type(v) is float for v in pos + vel)
    assert m.joint_state_content(["l", "r"], [0, 1], [2, 3]) == (["l", "r"], [0.0, 1.0], [2.0, 3.0])


@pytest.mark.parametrize(
    "args",
    [
        (["a", "b"], [1.0], [1.0, 2.0]),  # positions short
        (["a"], [1.0], [1.0], ["a_steer"], None),  # steering joint without an angle
        (["a"], [1.0], [1.0], [], [0.3]),  # angle without a steering joint
    ],
)
def test_joint_state_content_refuses_mismatched_lengths(args):
    with pytest.raises(InputError):
        m.joint_state_content(*args)


# --- command time: a TwistStamped counts from its stamp --------------------------------------------------
@pytest.mark.parametrize(
    "ros_now, stamp, timeout, expected",
    [
        (1000.0, 999.875, 0.5, 100.0 - 0.125),  # 0.125 s old: counts from when it was stamped
        (1000.0, 999.5, 0.5, 99.5),  # exactly the timeout old: still valid (the filter uses >)
        (1000.0, 999.25, 0.5, None),  # older than the timeout: stale
        (1000.0, 1000.25, 0.5, 100.0),  # from the future (clocks apart): counts from arrival
        (1000.0, 0.0, 0.5, 100.0),  # zero stamp (unstamped): counts from arrival
        (1000.0, 995.0, 0.0, 95.0),  # timeout disabled: never stale
    ],
)
def test_command_time(ros_now, stamp, timeout, expected):
    assert m.command_time(100.0, ros_now, stamp, timeout) == expected


# --- loop timing -------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "now, loops, expected",
    [
        (0.0, 1, 0),  # the first cycle itself
        (0.37, 1, 0),  # 1.48 periods: the second period is not half a period late yet
        (0.375, 1, 1),  # 1.5 periods: the second period is due and did not run
        (2.5, 10, 0),  # 10 periods in, 10 cycles: up to date
        (5.0, 16, 4),  # 20 periods, the 21st (at 5.0) not due yet: 20 due, 16 run
    ],
)
def test_periods_missed(now, loops, expected):
    assert m.periods_missed(0.0, loops, 0.25, now) == expected


def test_periods_missed_before_the_first_cycle_and_rate():
    assert m.periods_missed(None, 0, 0.25, 10.0) == 0
    assert m.rate(150, 100, 3.0, 2.0) == 50.0
    assert m.rate(150, 100, 2.0, 2.0) == 0.0


# --- diagnostics ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kw, level, message",
    [
        ({}, m.OK, "running"),
        ({"rejected": 2}, m.WARN, "2 command(s) rejected"),
        ({"stale": 3}, m.WARN, "3 stale command(s) ignored"),
        ({"rejected": 1, "stale": 1}, m.WARN, "1 command(s) rejected; 1 stale command(s) ignored"),
        ({"rejected": 1, "waiting_for": "w1,w2"}, m.WARN, "waiting for the wheel controllers of w1,w2"),
        ({"waiting_for": "w1", "step_error": "bad read"}, m.ERROR, "wheels stopped: control step failed: bad read"),
        ({"step_error": "bad read", "link_error": "port gone"}, m.ERROR, "wheels stopped: port gone"),
        ({"overruns": 3}, m.WARN, "3 control cycle(s) overran the period"),
        ({"dropped": 0.5}, m.WARN, "simulation 0.5 s behind real time"),
        (
            {"stale": 1, "overruns": 1, "dropped": 0.125},
            m.WARN,
            "1 stale command(s) ignored; 1 control cycle(s) overran the period; simulation 0.125 s behind real time",
        ),
        ({"overruns": 2, "step_error": "bad read"}, m.ERROR, "wheels stopped: control step failed: bad read"),
        (
            {"rejected": 5, "stale": 1, "waiting_for": "w1", "link_error": "port gone"},
            m.ERROR,
            "wheels stopped: port gone",
        ),
    ],
)
def test_diagnostic_status_rules(kw, level, message):
    assert m.diagnostic_status(**kw) == (level, message)


def test_diagnostic_levels_are_rosdiagnostics_levels():
    assert (m.OK, m.WARN, m.ERROR) == (0, 1, 2)  # diagnostic_msgs/DiagnosticStatus OK, WARN, ERROR


def test_diagnostic_values():
    stats = {
        "accepted": 7,
        "rejected": 2,
        "timeouts": 1,
        "saturated": 3,
        "projected": 4,
        "last_reject_reason": "vx = nan",
    }
    kv = m.diagnostic_values(
        published=120,
        loop_rate_hz=49.87654,
        periods_missed=2,
        command_stats=stats,
        stale_commands=5,
        fk_residual_norm=0.25,
        timed_out=True,
        link_rearms=1,
        step_errors=6,
        last_step_error="boom",
        link_stats={"backend": "sim", "reads": 9},
        loop_overruns=4,
        loop_time_max_ms=21.23456,
        joint_commands_rejected=8,
    )
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in kv)
    d = dict(kv)
    assert len(d) == len(kv)
    assert d == {
        "odom_published": "120",
        "loop_rate_hz": "49.877",
        "periods_missed": "2",
        "loop_overruns": "4",
        "loop_time_max_ms": "21.235",
        "commands_accepted": "7",
        "commands_rejected": "2",
        "command_timeouts": "1",
        "commands_saturated": "3",
        "commands_projected": "4",
        "commands_stale": "5",
        "joint_commands_rejected": "8",
        "last_reject_reason": "vx = nan",
        "fk_residual_norm": "0.25",
        "timed_out": "True",
        "link_rearms": "1",
        "step_errors": "6",
        "last_step_error": "boom",
        "link_backend": "sim",
        "link_reads": "9",
    }


def test_messages_module_imports_without_rclpy():
    """The module the node's content comes from must not need ROS (checked in a clean interpreter
    where importing rclpy fails)."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('rclpy', 'nav_msgs', 'geometry_msgs', 'sensor_msgs',\n"
        "                                  'diagnostic_msgs', 'rcl_interfaces'):\n"
        "            raise ImportError(f'blocked: {name}')\n"
        "sys.meta_path.insert(0, Block())\n"
        "import omnikin.ros, omnikin.ros.messages, omnikin.ros.params\n"
        "try:\n"
        "    omnikin.ros.require_rclpy()\n"
        "except ImportError as exc:\n"
        "    assert 'omnikin[ros]' in str(exc) and '\\n' not in str(exc), exc\n"
        "else:\n"
        "    raise SystemExit('require_rclpy did not fail')\n"
        "try:\n"
        "    import omnikin.ros.node\n"
        "except ImportError as exc:\n"
        "    assert 'omnikin[ros]' in str(exc), exc\n"
        "else:\n"
        "    raise SystemExit('omnikin.ros.node imported without rclpy')\n"
        "print('ok')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stdout + r.stderr


@pytest.mark.parametrize("n", [0, 1, 7])
def test_a_serialized_path_is_read_as_rclpy_wrote_it(n):
    pytest.importorskip("rclpy", reason="the reference serializer is rclpy's (extra ros)")
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    from rclpy.serialization import serialize_message

    rng = np.random.default_rng(n)
    msg = Path()
    msg.header.frame_id = "odom"
    expected = []
    for k in range(n):
        pose = PoseStamped()
        pose.header.frame_id = "x" * k  # strings of every length shift the alignment
        pose.header.stamp.sec = k
        x, y, theta = rng.uniform(-5, 5, 3)
        pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = x, y, 0.25
        pose.pose.orientation.z, pose.pose.orientation.w = math.sin(theta / 2), math.cos(theta / 2)
        msg.poses.append(pose)
        expected.append((x, y, theta))
    data = serialize_message(msg)
    assert m.plan_frame(data) == "odom" and m.plan_count(data) == n
    got, want = m.plan_poses(data, 100).reshape(-1, 3), np.array(expected).reshape(-1, 3)
    assert got[:, :2] == pytest.approx(want[:, :2], abs=1e-12)
    assert np.angle(np.exp(1j * (got[:, 2] - want[:, 2]))) == pytest.approx(np.zeros(n), abs=1e-12)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "not a CDR message"),
        (b"\x00\x07\x00\x00", "not a CDR message"),
        (b"\x00\x01\x00\x00\x00\x00", "ends early"),
        (b"\x00\x01\x00\x00" + b"\x00" * 8 + b"\xff\xff\xff\x7f", "runs past the end"),
        (b"\x00\x01\x00\x00" + b"\x00" * 8 + b"\x01\x00\x00\x00" + b"\x00" * 4 + b"\x10\x27\x00\x00", "says it has"),
    ],
)
def test_a_path_message_cut_short_or_lying_about_its_size_is_refused_in_one_line(data, message):
    with pytest.raises(InputError, match=message):
        m.plan_poses(data, 100_000)


def test_a_quaternion_that_is_not_unit_gives_the_heading_of_its_direction():
    assert m.yaw(0.0, 0.0, 2.0, 2.0) == pytest.approx(math.pi / 2)
    assert m.yaw(0.0, 0.0, 0.1, 0.1) == pytest.approx(math.pi / 2)
    assert m.yaw(0.0, 0.0, 0.0, 0.0) == 0.0
    assert math.isnan(m.yaw(0.0, 0.0, math.inf, 1.0))


def test_wheel_speeds_on_joint_commands_become_the_twist_they_drive():
    """tomasi-omni3's wheel speeds for a twist give that twist back (the layout's inverse and
    forward kinematics, docs/conventions.md); speeds that fight each other give the
    least-squares twist, not a fight; names in any order, others ignored."""
    from omnikin import load_robot

    robot = load_robot("tomasi-omni3")
    twist = np.array([0.2, -0.1, 0.5])
    speeds = robot.ik(twist).wheel_speeds
    names = ["w3", "extra_joint", "w1", "w2"]
    velocities = [speeds[2], 123.0, speeds[0], speeds[1]]
    got = m.wheel_command_twist(robot, ["w1", "w2", "w3"], names, velocities, [])
    np.testing.assert_allclose(got, twist, atol=1e-12)
    # all three wheels at the same speed turn the robot in place: omega = r w / L (L = 0.113 m,
    # r = 0.04125 m); adding a fight (one wheel off) is projected away
    w = 2.0
    spin = m.wheel_command_twist(robot, ["w1", "w2", "w3"], ["w1", "w2", "w3"], [w, w, w], [])
    np.testing.assert_allclose(spin, [0.0, 0.0, 0.04125 * w / 0.113], atol=1e-12)


@pytest.mark.parametrize(
    "names, velocities, positions, problem",
    [
        (["w1", "w2"], [1.0, 2.0], [], "no velocity for the wheel joint(s) w3"),
        (["w1", "w2", "w3"], [1.0, 2.0], [], "3 names but 2 velocities"),
        (["w1", "w1", "w2", "w3"], [1.0, 1.0, 2.0, 3.0], [], "named twice"),
        (["w1", "w2", "w3"], [1.0, float("nan"), 3.0], [], "not finite"),
    ],
)
def test_joint_commands_the_node_cannot_take_are_refused_in_one_line(names, velocities, positions, problem):
    from omnikin import load_robot

    with pytest.raises(InputError, match="^joint_commands: ") as info:
        m.wheel_command_twist(load_robot("tomasi-omni3"), ["w1", "w2", "w3"], names, velocities, positions)
    assert problem in str(info.value) and "\n" not in str(info.value)


def test_a_steered_robot_needs_its_steering_positions_on_joint_commands():
    from omnikin import load_robot

    robot = load_robot("xr4000")
    wheels = list(robot.encoded_names)
    with pytest.raises(InputError, match="no position for the steering joint"):
        m.wheel_command_twist(robot, wheels, wheels, [0.0] * len(wheels), [])
