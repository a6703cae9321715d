"""The robot behind the page is a running ``omnikin ros`` node (``omnikin view ROBOT --ros``,
extras ``viewer`` and ``ros``).

:class:`RosRobot` is a ROS 2 node of its own (``omnikin_view``, in the domain of
``ROS_DOMAIN_ID`` like any ROS 2 program) that subscribes to the node's ``odom``,
``joint_states`` and, when a simulated back-end publishes it, ``ground_truth``
(``nav_msgs/Odometry``, ``sensor_msgs/JointState``; :mod:`omnikin.ros.node`), and publishes
the page's commands on ``cmd_vel`` (``geometry_msgs/Twist``, or ``TwistStamped`` with
``stamped``, as the node's ``use_stamped_vel``) at every control step while a target is set,
and zero once when it is released. The node's own command filter, limits and timeout act on
them: the page drives the robot as any ROS teleop would, and a page that falls silent stops it
(the node's ``cmd_vel_timeout``).

The page shows what the node publishes: the pose of ``ground_truth`` as the robot (else the
odometry's), the odometry's pose and twist, the wheels, steering and rollers of
``joint_states`` (joint names as in the URDF, :mod:`omnikin.physics.urdf`: ``W``, ``W_steer``,
``W_roller_ROW_K``). The goal seeker steers by the odometry. Steering by hand is not a
``cmd_vel`` command: the page's steering keys do nothing here.

**Another robot is not driven.** The node says which robot it drives: its ``robot_description``
(the URDF, transient local, so a viewer that starts later still gets it) and the names of its
``joint_states``. The viewer compares them with the robot it was given
(:func:`robot_mismatch`: the movable joints of :func:`omnikin.physics.urdf.urdf` of that robot;
the wheels among them, ``W`` without ``_steer`` or ``_roller_ROW_K``). On start it waits up to
:data:`CHECK_WAIT` s for either: a node of another robot is refused (:class:`RobotMismatch`, one
line naming both robots' wheels; ``omnikin view`` exits with status 2). One that is heard only
later is warned about (a line on standard error, the page's notice) and from then on gets no
``cmd_vel`` from this viewer.
"""

from __future__ import annotations

import math
import os
import re
import sys
import threading
import xml.etree.ElementTree as ET

import numpy as np

from ..common.messages import one_line, shorten
from ..errors import InputError, RobotMismatch
from ..io.bags import yaw_of
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits
from .live import PageRobot, Snapshot, triple

NODE_NAME = "omnikin_view"
CHECK_WAIT = 5.0
"""Time [s] the viewer waits on start for the node's ``robot_description`` or ``joint_states``
to say which robot it drives (module docstring)."""
MAX_DESCRIPTION_CHARS = 1 << 22
"""Longest ``robot_description`` read [characters] (a robot's URDF is some 10 to 100 KB)."""
ROLLER_JOINT = re.compile(r"_roller_\d+_\d+$")
TRUTH_FRESH = 1.0
"""Age [s] beyond which the last ``ground_truth`` no longer stands for the robot (the odometry
does)."""


def require_ros():
    """rclpy and the message packages, or one line naming the extra."""
    try:
        import rclpy  # noqa: F401
        from geometry_msgs.msg import Twist, TwistStamped  # noqa: F401
        from nav_msgs.msg import Odometry  # noqa: F401
        from sensor_msgs.msg import JointState  # noqa: F401
    except ImportError as e:
        raise InputError(
            f'omnikin view --ros needs rclpy and the ROS 2 messages: pip install "omnikin[ros]" ({e})'
        ) from None


def movable_joints(urdf_text: str) -> set[str]:
    """The names of the joints of URDF ``urdf_text`` that move (every type but ``fixed``)."""
    from ..physics.link_frames import urdf_joints

    return {j.name for j in urdf_joints(urdf_text) if j.movable}


def wheel_joints(joints) -> list[str]:
    """The wheels among joint names ``joints`` (:mod:`omnikin.physics.urdf`: a wheel's joint is
    named as the wheel; steering ``W_steer`` and rollers ``W_roller_ROW_K`` are not wheels), sorted."""
    return sorted(n for n in joints if not n.endswith("_steer") and not ROLLER_JOINT.search(n))


def robot_mismatch(robot_name: str, expected: set[str], heard, source: str, *, exact: bool) -> str | None:
    """None when the joint names ``heard`` (of the node's ``source``: its robot_description or
    joint_states) fit the robot ``robot_name`` whose movable joints are ``expected``; else one
    line saying how they differ. ``exact``: the node's URDF must have exactly these joints
    (a robot_description); else each name heard must be one of them (joint_states may leave
    joints out)."""
    heard = set(heard)
    if heard == expected or (not exact and heard <= expected):
        return None
    theirs, ours = wheel_joints(heard), wheel_joints(expected)
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    head = f"the node on ROS_DOMAIN_ID {domain} drives another robot than {shorten(robot_name)}: its {source}"
    if theirs != ours and (exact or not set(theirs) <= set(ours)):
        return (
            f"{head} names {len(theirs)} wheels {shorten(theirs, 200)}, {shorten(robot_name)} has "
            f"{len(ours)} {shorten(ours, 200)}"
        )
    extra, missing = sorted(heard - expected), sorted(expected - heard) if exact else []
    said = f"joints {shorten(extra, 200)} that {shorten(robot_name)} does not have"
    if missing:
        said += f", and not its joints {shorten(missing, 200)}"
    return f"{head} has {said}"


def _pose(msg) -> tuple[float, float, float]:
    p = msg.pose.pose
    return float(p.position.x), float(p.position.y), yaw_of(p.orientation)


class RosRobot(PageRobot):
    """A running node followed and driven from the page (module docstring)."""

    def __init__(
        self,
        robot: Robot,
        *,
        speed: float = 0.2,
        turn: float = 0.5,
        limits: MotionLimits | None = None,
        stamped: bool = False,
    ):
        require_ros()
        import rclpy
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from std_msgs.msg import String

        from ..physics.urdf import urdf

        super().__init__(robot, speed=speed, turn=turn, limits=limits)
        self._twist_type = TwistStamped if stamped else Twist
        self.stamped = stamped
        self._lock = threading.Lock()
        self.odom = None  # the last messages (their arrival times on the page's clock)
        self.truth = None
        self.joint_states: dict[str, tuple[float, float]] = {}
        self._truth_at = -math.inf
        self.messages = {"odom": 0, "ground_truth": 0, "joint_states": 0, "robot_description": 0}
        self.expected = movable_joints(urdf(self.description))  # the joints the node publishes for `robot`
        self.mismatch: str | None = None  # how the node's robot differs (then nothing is published)
        self.matched: str | None = None  # what confirmed the node's robot (robot_description, joint_states)
        self._robot_known = threading.Event()  # the node's robot is known (matched or not)
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        try:
            self.node = rclpy.create_node(NODE_NAME, context=self.context)
            qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
            self.node.create_subscription(Odometry, "odom", self._on_odom, qos)
            self.node.create_subscription(Odometry, "ground_truth", self._on_truth, qos)
            self.node.create_subscription(JointState, "joint_states", self._on_joints, qos)
            latched = QoSProfile(
                depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
            )
            self.node.create_subscription(String, "robot_description", self._on_description, latched)
            self.publisher = self.node.create_publisher(self._twist_type, "cmd_vel", qos)
            self.executor = SingleThreadedExecutor(context=self.context)
            self.executor.add_node(self.node)
        except BaseException:
            rclpy.shutdown(context=self.context)
            raise
        self._spinner = threading.Thread(target=self._spin, name="omnikin-view-ros", daemon=True)
        self._spinner.start()
        self._sent_zero = True
        if self._robot_known.wait(CHECK_WAIT) and self.mismatch is not None:
            self.close()
            raise RobotMismatch(self.mismatch)
        self._started = True  # from now on a mismatch is warned about

    _started = False

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception:  # noqa: BLE001 (the context shut down under it: the viewer is closing)
            pass

    def _now(self) -> float:
        return self.clock() if self.clock is not None else 0.0

    # --- subscriptions (the spinner's thread) -----------------------------------------------------
    def _on_odom(self, msg) -> None:
        with self._lock:
            self.odom = msg
            self.messages["odom"] += 1

    def _on_truth(self, msg) -> None:
        with self._lock:
            self.truth = msg
            self._truth_at = self._now()
            self.messages["ground_truth"] += 1

    def _check(self, heard, source: str, exact: bool) -> None:
        """The node's ``source`` names the joints ``heard``: the first verdict stands (module
        docstring)."""
        if self._robot_known.is_set():
            return
        line = robot_mismatch(self.robot.name, self.expected, heard, source, exact=exact)
        if line is None:
            self.matched = source
        else:
            self.mismatch = line
            self.notice = f"{line}: the page sends it no cmd_vel"
            if self._started:
                print(f"omnikin view: warning: {line}; the page sends it no cmd_vel", file=sys.stderr, flush=True)
        self._robot_known.set()

    def _on_description(self, msg) -> None:
        text = msg.data
        self.messages["robot_description"] += 1
        if len(text) > MAX_DESCRIPTION_CHARS:
            heard = {f"(a robot_description of {len(text)} characters, above {MAX_DESCRIPTION_CHARS})"}
        else:
            try:
                heard = movable_joints(text)
            except (ET.ParseError, InputError, ValueError) as exc:
                heard = {f"(not a URDF: {one_line(exc, 100)})"}
        self._check(heard, "robot_description", exact=True)

    def _on_joints(self, msg) -> None:
        self._check(msg.name, "joint_states", exact=False)
        n = min(len(msg.name), len(msg.position))
        velocities = list(msg.velocity) + [0.0] * max(0, n - len(msg.velocity))
        with self._lock:
            for name, position, velocity in zip(msg.name[:n], msg.position[:n], velocities[:n], strict=True):
                self.joint_states[name] = (float(position), float(velocity))
            self.messages["joint_states"] += 1

    # --- the page's robot -------------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        with self._lock:
            odom = self.odom
        return _pose(odom) if odom is not None else (0.0, 0.0, 0.0)

    def _publish(self, twist: np.ndarray) -> None:
        msg = self._twist_type()
        body = msg.twist if self.stamped else msg
        if self.stamped:
            msg.header.stamp = self.node.get_clock().now().to_msg()
            msg.header.frame_id = "base_link"
        body.linear.x, body.linear.y, body.angular.z = (float(v) for v in twist)
        self.publisher.publish(msg)

    def follow(self, waypoints, **options) -> None:
        """Not from here: the node follows a path itself (a ``nav_msgs/Path`` on its ``plan``);
        the page says so."""
        self.notice = (
            "the page follows paths with a simulated robot (omnikin view without --ros); "
            "a running node follows a nav_msgs/Path published on its plan topic"
        )

    def _control(self, t: float) -> Snapshot:
        seeking = self._seek(t)
        target = self.target if seeking is None else seeking
        if self.mismatch is not None:  # another robot: never driven from here
            self.seeker = None
            target = np.zeros(3)
        elif np.any(target):
            self._publish(target)
            self._sent_zero = False
        elif not self._sent_zero:
            self._publish(np.zeros(3))  # released: stop now, not at the node's timeout
            self._sent_zero = True
        self.t = t
        return self._snapshot(t, target)

    def _snapshot(self, t: float, target: np.ndarray) -> Snapshot:
        with self._lock:
            odom, truth, truth_at = self.odom, self.truth, self._truth_at
            joints = dict(self.joint_states)
        odometry = _pose(odom) if odom is not None else (0.0, 0.0, 0.0)
        fresh = truth is not None and t - truth_at <= TRUTH_FRESH
        twist = (0.0, 0.0, 0.0)
        if odom is not None:
            tw = odom.twist.twist
            twist = (float(tw.linear.x), float(tw.linear.y), float(tw.angular.z))
        n = len(self.description.wheels)
        angles, speeds, steer = np.zeros(n), np.zeros(n), np.full(n, np.nan)
        rollers: list[float | None] = [None] * n
        roller_speeds: list[float | None] = [None] * n
        for i, wheel in enumerate(self.description.wheels):
            angles[i], speeds[i] = joints.get(wheel.name, (0.0, 0.0))
            if wheel.steering is not None and f"{wheel.name}_steer" in joints:
                steer[i] = joints[f"{wheel.name}_steer"][0]
            if wheel.rollers is not None:
                first = wheel.rollers.rollers[0]
                rollers[i], roller_speeds[i] = joints.get(f"{wheel.name}_roller_{first.row}_{first.index}", (0.0, 0.0))
        return Snapshot(
            t=t,
            truth=_pose(truth) if fresh else odometry,
            odometry=odometry,
            twist=twist,
            command=triple(target),
            target=triple(target),
            wheel_angles=angles,
            wheel_speeds=speeds,
            steer=steer,
            residual=(),
            roller_angles=tuple(rollers),
            roller_speeds=tuple(roller_speeds),
            missing=("residual",) + (("truth",) if not fresh else ()) + (("odometry", "twist") if odom is None else ()),
            missing_why="not received",
        )

    def close(self) -> None:
        """Stop the robot (a zero command), leave the ROS graph."""
        import rclpy

        try:
            if not self._sent_zero:
                self._publish(np.zeros(3))
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        finally:
            rclpy.shutdown(context=self.context)
            self._spinner.join(2.0)
