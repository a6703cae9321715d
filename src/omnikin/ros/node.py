"""``omnikin ros``: the ROS 2 base driver node.

Subscribes ``cmd_vel`` (``geometry_msgs/Twist``, or ``TwistStamped`` with
``use_stamped_vel``) and ``joint_commands`` (``sensor_msgs/JointState``: wheel speeds, taken as
the twist they imply, :meth:`BaseNode._on_joint_commands`); publishes ``odom`` (``nav_msgs/Odometry`` with twist and a
motion-dependent covariance), ``joint_states`` (every movable joint of the robot's URDF: first
the encoded wheels' positions [rad] and speeds [rad/s] and the steering joints ``<wheel>_steer``
as measured, then the joints no sensor reads, moved as the odometry's body motion implies:
:mod:`omnikin.physics.joint_motion`), ``robot_description`` (``std_msgs/String``, the URDF of
:func:`omnikin.physics.urdf.urdf`, once, transient local: a subscriber that comes later still
gets it), ``/diagnostics`` (command and link statistics, the forward-kinematics residual),
``ground_truth`` (``nav_msgs/Odometry``, the simulated robot's true pose and mean twist over
the last cycle, in the frames of ``odom``; only with a simulated back-end, one that has a
``truth`` pose), ``imu`` and ``scan`` (``sensor_msgs/Imu``, ``sensor_msgs/LaserScan``: what the
robot's IMUs and lidars read, each reading stamped at its own time in the sensor's frame; only
with a back-end that reads them, the physics one: :meth:`BaseNode._publish_sensors`) and, when
``tf2_msgs`` is importable, ``/tf``: odom -> base_link and, at most
``link_tf_rate`` times a second, every URDF link in its parent link
(:mod:`omnikin.physics.link_frames`), and ``/tf_static`` (transient local): ``base_frame_id`` ->
the URDF's ``base_link`` when the two names differ, and the URDF's fixed joints if any.
``tf2_msgs`` is not among the ROS 2 wheels on PyPI: with the PyPI install the node says so
once and publishes no ``/tf``; build it for the wheels (``omnikin tf2-msgs``,
:mod:`omnikin.ros.interfaces`) or run the node from a ROS 2 install (``source /opt/ros/<distro>/
setup.bash``) to get it. Parameters: :mod:`omnikin.ros.params`; message content:
:mod:`omnikin.ros.messages` (this module only copies it into messages).

Simulated time: with ROS's ``use_sim_time`` on this node and a simulated back-end (``--backend
sim`` or ``physics``) the node is the clock: ``/clock`` (``rosgraph_msgs/Clock``) in simulated
time every cycle and every stamp in it (:meth:`BaseNode._init_clock`), for SLAM and Nav2 stacks
run with ``use_sim_time``.

Paths: a ``nav_msgs/Path`` on ``plan`` (in the odometry frame, or with an empty frame id) is
followed (:mod:`omnikin.control.follower`): planned from the robot's pose on a worker thread, timed
within 95 % of the node's limits (its body limits and ``wheel_max_velocity``, every wheel's own
``max_speed``), tracked by the controller of ``path_controller`` steering by the odometry, each
control cycle. While it is followed, ``reference`` (``geometry_msgs/PoseStamped``) is the
reference pose of the cycle and ``reference_path`` (``nav_msgs/Path``, transient local) the timed
reference, each pose stamped at the time the robot is due there; ``/diagnostics`` carries a
second status, ``omnikin path``, with the state and the tracking error (the odometry's distance to
the reference point and to the path). Any ``cmd_vel``, an empty path, or a new path stops the
path followed: the person at the keyboard wins. A path in another frame, or one the robot cannot
drive, is refused: the robot stops, the log and ``omnikin path`` (WARN) say why.

The control loop runs at ``publish_rate`` on a steady-clock timer: read the wheels, update
the odometry, filter the command (timeout, limits), command the wheels, publish. Time inside
the runtime is the monotonic clock; message stamps are the node's ROS clock. A
``TwistStamped`` counts from its stamp (:func:`omnikin.ros.messages.command_time`), a
``Twist`` from its arrival. On shutdown (SIGINT, SIGTERM) the wheels are commanded to zero
before the node exits.

Overruns: a control cycle that takes longer than the period (a slow back-end: the physics
catching up, a slow link) is counted (``loop_overruns``, the longest cycle in
``loop_time_max_ms``) and makes ``/diagnostics`` WARN until a status without one, as does
simulated time the physics back-end dropped because it ran slower than real time.

Failures of a control step: a :class:`~omnikin.errors.LinkError` is a lost link (the
back-end already commands zero speeds; the node retries every ``link_retry_period``). Any
other :class:`~omnikin.errors.OmnikinError` (an :class:`~omnikin.errors.InputError` from the
back-end or the runtime) is a bug, not a lost link: the node commands zero speeds, drops the
velocity command (the wheels stay stopped until a new ``cmd_vel``), publishes no odometry for
that cycle, logs the error at most once a second and reports ERROR in ``/diagnostics``.

A simulated robot that tips over (the physics back-end, ``--backend physics``:
:attr:`omnikin.physics.backend.PhysicsBackend.fallen`) has its wheels stopped by the back-end,
which drives it no more; the node logs it once and reports ERROR ``wheels stopped: robot ...
tipped over at t = ... s`` in ``/diagnostics`` from then on.

This module imports rclpy: import it only to run the node (``omnikin.ros.require_rclpy``
first gives the one-line error naming the ``ros`` extra).
"""

from __future__ import annotations

import dataclasses
import signal
import time
from typing import Any

import numpy as np

from ..common.messages import digits_apart
from ..control.controllers import check_controller_for
from ..control.follower import MAX_WAYPOINTS, FollowPlan, PathFollower, PlanWorker, plan_follow
from ..errors import InputError, LinkError, OmnikinError
from ..kinematics.se2 import between, log
from ..kinematics.sensors import Imu, Lidar
from ..motion.limits import MotionLimits
from ..physics.description import describe
from ..physics.joint_motion import JointMotion
from ..physics.link_frames import LinkFrames, urdf_joints
from ..physics.urdf import BASE_LINK, urdf
from ..runtime.base import BaseRuntime
from ..sensors.message_content import imu_fields, scan_fields, sensor_topic
from . import messages, require_rclpy
from .params import DEFAULTS, check_names, validate

try:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import PoseStamped, TransformStamped, Twist, TwistStamped
    from nav_msgs.msg import Odometry
    from nav_msgs.msg import Path as PathMessage
    from rcl_interfaces.msg import ParameterDescriptor
    from rclpy.clock import Clock, ClockType
    from rclpy.executors import ExternalShutdownException
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.time import Time
    from rosgraph_msgs.msg import Clock as ClockMessage
    from sensor_msgs.msg import Imu as ImuMessage
    from sensor_msgs.msg import JointState, LaserScan
    from std_msgs.msg import String
except ImportError:
    require_rclpy()  # without rclpy: the one-line error naming the ros extra
    raise  # rclpy there, a message package missing: its name

try:
    from tf2_msgs.msg import TFMessage
except ImportError:  # not among the ROS 2 wheels on PyPI
    TFMessage = None

NODE_NAME = "omnikin_base"
CLOCK_STEP = 0.05
"""A change [s] in the difference between the ROS clock and the runtime's beyond which the
sensors' stamps follow it (the system clock was set)."""

LATCHED = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
"""QoS of ``robot_description`` and ``/tf_static``: published once, kept for late subscribers
(a subscriber gets the message only if it asks for transient local durability too, as
robot_state_publisher's subscribers and rviz2's configuration here do)."""


def _seconds(stamp) -> float:
    """A ``builtin_interfaces/Time`` in seconds."""
    return stamp.sec + 1e-9 * stamp.nanosec


class BaseNode(Node):
    """The rclpy node around a :class:`~omnikin.runtime.base.BaseRuntime` (module docstring).

    ``values`` are the parameters' values before ``--ros-args`` (defaults and ``--params FILE``);
    rclpy must be initialised.
    """

    def __init__(self, robot, backend, values: dict, name: str = NODE_NAME):
        # overrides (--ros-args -p, --params-file) are declared as given, so unknown names show
        super().__init__(name, automatically_declare_parameters_from_overrides=True)
        dynamic = ParameterDescriptor(dynamic_typing=True)  # our own checks name the parameter
        for key, default in values.items():
            if not self.has_parameter(key):
                self.declare_parameter(key, default, dynamic)
        check_names(self.list_parameters([], 0).names, "--ros-args", ros_own=True)
        p = validate({k: self.get_parameter(k).value for k in DEFAULTS}, "--ros-args / parameters")
        # the controllers' own link_timeout (the host may allow them longer: --link-timeout)
        protocol = getattr(backend, "protocol", None)
        link_timeout = protocol.timing.link_timeout if protocol is not None else None
        if link_timeout is not None and 1.0 / p["publish_rate"] > 0.5 * link_timeout:
            least = 2.0 / link_timeout
            digits = digits_apart(p["publish_rate"], least)
            raise InputError(
                f"publish_rate {p['publish_rate']:.{digits}g} Hz is too slow for the serial link: the wheel "
                f"controllers stop after {link_timeout:g} s without a frame; use at least {least:.{digits}g} Hz"
            )
        limits = MotionLimits(
            linear=p["linear.x.max_velocity"],
            angular=p["angular.z.max_velocity"],
            linear_accel=p["linear.x.max_acceleration"],
            angular_accel=p["angular.z.max_acceleration"],
            wheel=p["wheel_max_velocity"] or None,
        )
        self.robot = robot
        self._init_clock(backend)
        self.runtime = BaseRuntime(
            robot, backend, limits=limits, cmd_vel_timeout=p["cmd_vel_timeout"], wheel_slip=p["wheel_slip"]
        )
        self.runtime.filter.reject_above = p["reject_above"]
        self.p = p
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        msg_type = TwistStamped if p["use_stamped_vel"] else Twist
        self.create_subscription(msg_type, "cmd_vel", self._on_cmd, qos)
        self.create_subscription(JointState, "joint_commands", self._on_joint_commands, qos)
        self.joint_commands_rejected = 0  # joint_commands that named no wheel speeds the node could take
        self.odom_pub = self.create_publisher(Odometry, "odom", qos)
        self.joint_pub = self.create_publisher(JointState, "joint_states", qos)
        self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._init_following(robot, limits)
        self.truth_pub = None  # ground truth: only a simulated back-end knows it
        self._simulated: Any = backend  # its ``truth`` [m, m, rad], when it has one
        if getattr(backend, "truth", None) is not None:
            self.truth_pub = self.create_publisher(Odometry, "ground_truth", qos)
        self._last_truth: tuple | None = None  # (runtime time [s], true pose)
        self._zero3 = np.zeros((3, 3))
        self.tf_pub = None
        self._describe_robot(robot)
        wants_tf = p["enable_odom_tf"] or (p["link_tf_rate"] > 0.0 and self.link_frames is not None)
        if wants_tf:
            if TFMessage is None:
                self.get_logger().warning(
                    "tf2_msgs is not importable (it is not among the ROS 2 wheels on PyPI): no /tf "
                    "(odom->base_link, the robot's links); build it with omnikin tf2-msgs, or run this node from a "
                    "ROS 2 install"
                )
            else:
                self.tf_pub = self.create_publisher(TFMessage, "/tf", qos)
                self._publish_static_tf()
        self._init_sensors(backend, qos)
        self.published = 0
        self.link_rearms = 0  # lost links re-armed (serial back-end)
        self._next_retry: float | None = None  # node time [s] of the next link reopen
        self.period = 1.0 / p["publish_rate"]
        self.loops = 0  # control cycles run
        self.overruns = 0  # control cycles that took longer than the period
        self._overruns_window = 0  # ... since the previous diagnostics
        self._loop_time_max = 0.0  # [s] the longest cycle since the previous diagnostics
        self._dropped_window = 0.0  # [s] simulated time dropped, at the previous diagnostics
        self._first_loop: float | None = None
        self._window = (time.monotonic(), 0)  # (time, published) at the last diagnostics
        self.link_error = ""
        self._fall_logged = False  # the physics back-end's robot tipped over, and the log said so
        self.stale_commands = 0  # TwistStamped older than cmd_vel_timeout, ignored
        self.step_errors = 0  # control steps failed on a non-link error
        self.last_step_error = ""
        self._step_error_window = ""  # the last such error since the previous diagnostics
        self.joint_names = list(self.runtime.encoded)
        self.steer_names = [f"{n}_steer" for n in robot.steer_names]
        self._link_tf_due = 0.0  # [s, monotonic] when the links' transforms are next due
        # the loop runs on the steady clock, as the runtime does: a step of the system clock
        # (the ROS clock without sim time) neither stalls it nor makes it skip periods
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(self.period, self._loop, clock=steady)
        self.create_timer(1.0, self._diagnostics, clock=steady)

    def _init_clock(self, backend) -> None:
        """With ROS's ``use_sim_time`` on this node and a simulated back-end (one with a
        ``sim_time``), the node is the clock, as a simulator is: it publishes ``/clock`` in
        simulated time every cycle and stamps every message with it (:meth:`clock_now`), so
        nodes run with ``use_sim_time`` (slam_toolbox, Nav2, rviz2) see one clock that slows
        down with the simulation. Otherwise (a real robot, or ``use_sim_time`` off) stamps come
        from the node's ROS clock, which follows an external ``/clock`` under ``use_sim_time``."""
        self._sim_clock: Any = None
        self.clock_pub = None
        if not self.get_parameter("use_sim_time").value or getattr(backend, "sim_time", None) is None:
            return
        self._sim_clock = backend
        self.clock_pub = self.create_publisher(
            ClockMessage, "/clock", QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        )
        self._publish_clock()

    def _publish_clock(self) -> None:
        """``/clock``: the simulated time now (only when the node is the clock)."""
        if self.clock_pub is not None:
            self.clock_pub.publish(ClockMessage(clock=self.clock_now().to_msg()))

    def _init_sensors(self, backend, qos) -> None:
        """``imu`` and ``scan`` (``imu/NAME``, ``scan/NAME`` with several) for the robot's IMUs
        and lidars, when the back-end reads them (``sensor_readings``: the physics back-end);
        a warning once when the robot has some that its back-end does not read."""
        self._sensing: Any = None
        self._clock_offset_ns: int | None = None  # the ROS clock minus the runtime's [ns]
        self._imu_pubs: dict[str, tuple] = {}
        self._scan_pubs: dict[str, tuple] = {}
        sensors = getattr(backend, "true_robot", self.robot).sensors
        imus = [s for s in sensors if isinstance(s, Imu)]
        lidars = [s for s in sensors if isinstance(s, Lidar)]
        if not imus and not lidars:
            return
        if not callable(getattr(backend, "sensor_readings", None)):
            self.get_logger().warning(
                "the robot's IMUs and lidars are read by the physics back-end only (--backend physics): "
                "no imu or scan topics"
            )
            return
        self._sensing = backend
        for imu in imus:
            topic = sensor_topic("imu", imu.name, len(imus) > 1)
            self._imu_pubs[imu.name] = (self.create_publisher(ImuMessage, topic, qos), imu_fields(imu))
        for lidar in lidars:
            topic = sensor_topic("scan", lidar.name, len(lidars) > 1)
            self._scan_pubs[lidar.name] = (self.create_publisher(LaserScan, topic, qos), scan_fields(lidar))

    def _publish_sensors(self) -> None:
        """Publish what the IMUs and lidars read since the previous cycle, each message stamped
        with the node's clock at the reading's time (its simulated time on the runtime's clock,
        :meth:`omnikin.physics.backend.PhysicsBackend.caller_time`, moved onto the ROS clock by
        the two clocks' difference, taken once: a difference read at every cycle would carry the
        jitter of the two reads into the stamps, and taken again only when the ROS clock has
        stepped by more than :data:`CLOCK_STEP`)."""
        if self._sensing is None:
            return
        readings = self._sensing.sensor_readings()
        if readings is None:
            return
        if self._sim_clock is not None:  # the node is the clock: stamps in simulated time

            def stamp(t: float):
                return Time(nanoseconds=int(round(float(t) * 1e9))).to_msg()

        else:
            offset_ns = self.get_clock().now().nanoseconds - int(round(self.now_s() * 1e9))
            if self._clock_offset_ns is None or abs(offset_ns - self._clock_offset_ns) > CLOCK_STEP * 1e9:
                self._clock_offset_ns = offset_ns
            offset = self._clock_offset_ns

            def stamp(t: float):
                return Time(nanoseconds=offset + int(round(self._sensing.caller_time(t) * 1e9))).to_msg()

        for record in readings.imus:
            publisher, fields = self._imu_pubs[record.sensor.name]
            for t, gyro, accel in zip(record.t, record.gyro, record.accel, strict=True):
                msg = ImuMessage()
                msg.header.stamp = stamp(t)
                msg.header.frame_id = record.sensor.name
                o = msg.orientation
                o.x, o.y, o.z, o.w = fields["orientation"]
                msg.orientation_covariance = fields["orientation_covariance"]
                w, a = msg.angular_velocity, msg.linear_acceleration
                w.x, w.y, w.z = (float(v) for v in gyro)
                a.x, a.y, a.z = (float(v) for v in accel)
                msg.angular_velocity_covariance = fields["angular_velocity_covariance"]
                msg.linear_acceleration_covariance = fields["linear_acceleration_covariance"]
                publisher.publish(msg)
        for scans in readings.scans:
            publisher, fields = self._scan_pubs[scans.sensor.name]
            for t, ranges in zip(scans.t, scans.ranges, strict=True):
                msg = LaserScan(**fields)
                msg.header.stamp = stamp(t)
                msg.header.frame_id = scans.sensor.name
                msg.ranges = ranges.astype(np.float32).tolist()
                publisher.publish(msg)

    def _init_following(self, robot, limits: MotionLimits) -> None:
        """The path follower (module docstring): ``plan`` in (serialized: its poses are read on
        the planning thread, not by the bindings on the control loop's), ``reference`` and
        ``reference_path`` out, one planning thread. A controller the layout cannot take is
        refused here, before any path."""
        controller = self.p["path_controller"]
        check_controller_for(None if controller == "auto" else controller, robot)
        self.follower = PathFollower()
        self._body = limits
        self._worker = PlanWorker(self._plan)
        self.paths_received = 0
        self.create_subscription(PathMessage, "plan", self._on_plan, 10, raw=True)
        self.reference_pub = self.create_publisher(PoseStamped, "reference", 10)
        self.reference_path_pub = self.create_publisher(PathMessage, "reference_path", LATCHED)

    def _describe_robot(self, robot) -> None:
        """Publish ``robot_description`` (once, latched) and prepare the joints and links the
        URDF adds to the measured ones; a robot the URDF writer refuses (a wheel name meeting a
        name built from another) runs without them, with a warning."""
        self.joint_motion: JointMotion | None = None
        self.link_frames: LinkFrames | None = None
        try:
            body = describe(robot)
            text = urdf(body, robot.sensors)
            self.joint_motion = JointMotion(robot, self.runtime.encoded, body)
        except InputError as exc:
            self.get_logger().warning(f"no robot_description, link transforms or unmeasured joints: {exc}")
            return
        self.description_pub = self.create_publisher(String, "robot_description", LATCHED)
        self.description_pub.publish(String(data=text))
        self.link_frames = LinkFrames(urdf_joints(text))
        measured = list(self.runtime.encoded) + [f"{n}_steer" for n in robot.steer_names]
        self._link_order = self.link_frames.index_in(measured + self.joint_motion.names)

    def _transform(self, stamp, parent: str, child: str, translation, rotation):
        tf = TransformStamped()
        tf.header.stamp = stamp
        tf.header.frame_id = parent
        tf.child_frame_id = child
        tr, rot = tf.transform.translation, tf.transform.rotation
        tr.x, tr.y, tr.z = (float(v) for v in translation)
        rot.x, rot.y, rot.z, rot.w = (float(v) for v in rotation)
        return tf

    def _publish_static_tf(self) -> None:
        """``/tf_static`` once: ``base_frame_id`` -> the URDF's base link (identity) when the
        names differ, and the URDF's fixed joints."""
        stamp = self.clock_now().to_msg()
        transforms = []
        if self.link_frames is not None and self.p["link_tf_rate"] > 0.0:
            if self.p["base_frame_id"] != BASE_LINK:
                transforms.append(self._transform(stamp, self.p["base_frame_id"], BASE_LINK, (0, 0, 0), (0, 0, 0, 1)))
            xyz, rot = self.link_frames.still()
            for j, t, q in zip(self.link_frames.fixed, xyz, rot, strict=True):
                transforms.append(self._transform(stamp, j.parent, j.child, t, q))
        if transforms:
            self.static_tf_pub = self.create_publisher(TFMessage, "/tf_static", LATCHED)
            self.static_tf_pub.publish(TFMessage(transforms=transforms))

    def now_s(self) -> float:
        """Runtime time [s]: the monotonic clock, the same one the back-ends use."""
        return time.monotonic()

    def clock_now(self) -> Time:
        """The time of the message stamps: the simulated time when the node is the clock
        (``use_sim_time`` with a simulated back-end, :meth:`_init_clock`), else the node's ROS
        clock."""
        if self._sim_clock is not None:
            return Time(nanoseconds=int(round(float(self._sim_clock.sim_time) * 1e9)))
        return self.get_clock().now()

    def ros_now_s(self) -> float:
        """The clock of the message stamps [s] (:meth:`clock_now`)."""
        return self.clock_now().nanoseconds * 1e-9

    def _on_cmd(self, msg):
        received = self.now_s()
        if self.p["use_stamped_vel"]:
            t = messages.command_time(received, self.ros_now_s(), _seconds(msg.header.stamp), self.p["cmd_vel_timeout"])
            if t is None:
                self.stale_commands += 1
                self.get_logger().warning(
                    f"cmd_vel stamped more than cmd_vel_timeout = {self.p['cmd_vel_timeout']:g} s ago ignored "
                    "(late delivery, or the sender's clock is behind this one)",
                    throttle_duration_sec=5.0,
                )
                return
            tw = msg.twist
        else:
            t, tw = received, msg
        self._cancel_path("a cmd_vel arrived (the person at the keyboard wins)")
        self.runtime.command((tw.linear.x, tw.linear.y, tw.angular.z), t)

    def _on_joint_commands(self, msg) -> None:
        """Wheel speeds on ``joint_commands`` (ros2_control's topic-based hardware interface):
        taken as the body twist they imply (:func:`omnikin.ros.messages.wheel_command_twist`),
        through the same limits and timeout as a ``cmd_vel``; one that names no usable speeds is
        counted and warned of (at most every 5 s)."""
        received = self.now_s()
        try:
            twist = messages.wheel_command_twist(self.robot, self.joint_names, msg.name, msg.velocity, msg.position)
        except InputError as exc:
            self.joint_commands_rejected += 1
            self.get_logger().warning(f"{exc}: ignored", throttle_duration_sec=5.0)
            return
        self._cancel_path("joint_commands arrived (a controller commands the wheels)")
        self.runtime.command(tuple(twist), received)

    def _cancel_path(self, why: str, log: bool = True) -> None:
        """Stop the path followed and drop one being planned; the robot brakes to a stop unless
        a command follows."""
        dropped = self._worker.cancel()
        if self.follower.stop(why):
            if log:
                self.get_logger().info(f"path stopped: {why}")
            self.runtime.command(np.zeros(3), self.now_s())
        elif dropped:
            self.follower.drop(f"{why} while the path was planned")

    def _on_plan(self, data: bytes) -> None:
        """A serialized ``nav_msgs/Path`` on ``plan``: stop what was followed, then plan the new
        one from the pose the robot has, on the planning thread (:meth:`_cycle` starts it when
        it is ready). Nothing a peer sends stops the node: what cannot be followed is refused."""
        self.paths_received += 1
        try:
            self._receive_plan(data)
        except OmnikinError as exc:
            self._refuse_path(str(exc))
        except Exception as exc:  # (a message no check foresaw: refused, the node keeps running)
            self._refuse_path(f"{type(exc).__name__}: {exc} (a bug in omnikin: please report it)")

    def _receive_plan(self, data: bytes) -> None:
        n = messages.plan_count(data)
        if n == 0:
            self._cancel_path("an empty path arrived")
            return
        self._cancel_path("a new path arrived")
        why = messages.plan_frame_error(messages.plan_frame(data), self.p["odom_frame_id"])
        if why is None and n > MAX_WAYPOINTS:
            why = f"a path of {n} poses: more than {MAX_WAYPOINTS}"
        if why is not None:
            self._refuse_path(why)
            return
        self._worker.request(data=data, pose=np.array(self.runtime.pose, dtype=float))

    def _plan(self, generation: int, data: bytes, pose: np.ndarray) -> FollowPlan | None:
        """The planning thread: the path of the serialized message ``data`` followed from
        ``pose``; None when a newer path or a command came first."""
        waypoints = messages.plan_poses(data, MAX_WAYPOINTS)
        if not self._worker.current(generation):
            return None
        p = self.p
        return plan_follow(
            self.robot,
            waypoints,
            pose,
            body=self._body,
            controller=None if p["path_controller"] == "auto" else p["path_controller"],
            heading=p["path_heading"],
            smooth=p["path_smooth"],
            blend=p["path_blend"],
            rate=p["publish_rate"],
            name="plan",
        )

    def _refuse_path(self, why: str) -> None:
        if self.follower.refuse(why):
            self.runtime.command(np.zeros(3), self.now_s())
        self.get_logger().warning(f"path refused: {why}", throttle_duration_sec=1.0)

    def _start_planned(self, now: float) -> None:
        """Begin a path whose planning has finished (or report why it cannot be followed)."""
        result = self._worker.take()
        if result is None:
            return
        if isinstance(result, Exception):
            self._refuse_path(str(result))
            return
        assert isinstance(result, FollowPlan)
        self.follower.begin(result, now)
        self.get_logger().info(self.follower.summary())
        self._publish_reference_path(result)

    def _publish_reference_path(self, plan: FollowPlan) -> None:
        t, poses = messages.reference_samples(plan.trajectory)
        start = self.clock_now().nanoseconds
        msg = PathMessage()
        msg.header.stamp = self.clock_now().to_msg()
        msg.header.frame_id = self.p["odom_frame_id"]
        for tk, pose in zip(t, poses, strict=True):
            msg.poses.append(self._pose_stamped(start + round(float(tk) * 1e9), pose))
        self.reference_path_pub.publish(msg)

    def _pose_stamped(self, nanoseconds: int, pose) -> Any:
        out = PoseStamped()
        out.header.stamp.sec, out.header.stamp.nanosec = divmod(int(nanoseconds), 1_000_000_000)
        out.header.frame_id = self.p["odom_frame_id"]
        x, y, theta = (float(v) for v in pose)
        out.pose.position.x, out.pose.position.y = x, y
        q = out.pose.orientation
        q.x, q.y, q.z, q.w = messages.quaternion(theta)
        return out

    def _loop(self):
        now = self.now_s()
        try:
            self._cycle(now)
            self._publish_clock()
        finally:
            took = self.now_s() - now
            self._loop_time_max = max(self._loop_time_max, took)
            if took > self.period:
                self.overruns += 1
                self._overruns_window += 1
                self.get_logger().warning(
                    f"control cycle took {took * 1e3:.1f} ms, longer than the period {self.period * 1e3:.1f} ms",
                    throttle_duration_sec=5.0,
                )

    def _cycle(self, now: float) -> None:
        if self._first_loop is None:
            self._first_loop = now
        self.loops += 1
        self._start_planned(now)
        try:
            res = self._step(now)
        except LinkError as exc:  # link lost: the back-end already commands zero speeds
            self.link_error = str(exc)
            self.get_logger().error(str(exc), throttle_duration_sec=1.0)
            self._cancel_path("the wheels' link was lost")
            self._retry_link()
            return
        except OmnikinError as exc:  # a bug or a bad back-end, not a lost link
            self._cancel_path("a control step failed")
            self._step_failed(exc, now)
            return
        self.link_error = ""
        self._next_retry = None
        self._publish(res)
        self._publish_truth(now)
        self._publish_sensors()

    def _step(self, now: float):
        """One control step: a path followed commands from the pose just measured."""
        if not self.follower.following:
            return self.runtime.step(now)
        state = self.runtime.sense(now)
        twist = self.follower.command(now, self.runtime.pose)
        if twist is None:  # the path's end has settled: brake to a stop
            self.get_logger().info(self.follower.summary())
            twist = np.zeros(3)
        else:
            self.reference_pub.publish(self._pose_stamped(self.clock_now().nanoseconds, self.follower.reference))
        self.runtime.command(twist, now)
        return self.runtime.act(now, state)

    def _publish(self, res) -> None:
        stamp = self.clock_now().to_msg()
        c = messages.odometry_content(res.pose, res.twist, res.pose_covariance, res.twist_covariance)
        odom = Odometry()
        odom.header.stamp = stamp
        odom.header.frame_id = self.p["odom_frame_id"]
        odom.child_frame_id = self.p["base_frame_id"]
        pose, twist = odom.pose.pose, odom.twist.twist
        pose.position.x, pose.position.y, pose.position.z = c["position"]
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = c["orientation"]
        odom.pose.covariance = c["pose_covariance"]
        twist.linear.x, twist.linear.y, twist.linear.z = c["linear"]
        twist.angular.x, twist.angular.y, twist.angular.z = c["angular"]
        odom.twist.covariance = c["twist_covariance"]
        self.odom_pub.publish(odom)
        js = JointState()
        js.header.stamp = stamp
        names, positions, velocities = messages.joint_state_content(
            self.joint_names, res.state.positions, res.state.velocities, self.steer_names, res.state.steer
        )
        if self.joint_motion is not None:
            more_positions, more_velocities = self.joint_motion.update(res.state.t, res.twist, res.state.steer)
            names = names + self.joint_motion.names
            positions = positions + more_positions.tolist()
            velocities = velocities + more_velocities.tolist()
        js.name, js.position, js.velocity = names, positions, velocities
        self.joint_pub.publish(js)
        if self.tf_pub is not None:
            transforms = []
            if self.p["enable_odom_tf"]:
                c = messages.transform_content(res.pose)
                transforms.append(self._transform(stamp, self.p["odom_frame_id"], self.p["base_frame_id"], **c))
            transforms += self._link_transforms(stamp, positions)
            if transforms:
                self.tf_pub.publish(TFMessage(transforms=transforms))
        self.published += 1

    def _link_transforms(self, stamp, positions) -> list:
        """Every movable URDF joint's child link in its parent at the joint positions of this
        ``joint_states``, when ``link_tf_rate`` says they are due; else none."""
        rate = self.p["link_tf_rate"]
        if self.link_frames is None or rate <= 0.0:
            return []
        now = self.now_s()
        if now < self._link_tf_due:
            return []
        due = self._link_tf_due + 1.0 / rate
        self._link_tf_due = due if due > now else now + 1.0 / rate  # late (a stall): count from now
        moved = np.asarray(positions, dtype=float)[self._link_order]
        xyz, rot = self.link_frames.moved(moved)
        return [
            self._transform(stamp, j.parent, j.child, t, q)
            for j, t, q in zip(self.link_frames.movable, xyz, rot, strict=True)
        ]

    def _publish_truth(self, now: float) -> None:
        """``ground_truth``: the back-end's true pose in the odom frame (in a world, seen from the
        world's start pose, where the odometry starts), and the mean body twist since the previous
        cycle (the SE(2) logarithm of the true increment over the cycle time, as ``odom``'s)."""
        if self.truth_pub is None:
            return
        pose = np.array(self._simulated.truth, dtype=np.float64)
        start = getattr(self._simulated, "start", None)
        if start is not None and np.any(np.asarray(start) != 0.0):  # in a world: from where it started
            pose = between(np.asarray(start, dtype=np.float64), pose)
        twist = np.zeros(3)
        if self._last_truth is not None and now > self._last_truth[0]:
            twist = log(between(self._last_truth[1], pose)) / (now - self._last_truth[0])
        self._last_truth = (now, pose)
        c = messages.odometry_content(pose, twist, self._zero3, self._zero3)
        msg = Odometry()
        msg.header.stamp = self.clock_now().to_msg()
        msg.header.frame_id = self.p["odom_frame_id"]
        msg.child_frame_id = self.p["base_frame_id"]
        p, tw = msg.pose.pose, msg.twist.twist
        p.position.x, p.position.y, p.position.z = c["position"]
        p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = c["orientation"]
        tw.linear.x, tw.linear.y, tw.linear.z = c["linear"]
        tw.angular.x, tw.angular.y, tw.angular.z = c["angular"]
        self.truth_pub.publish(msg)

    def _step_failed(self, exc: Exception, now: float) -> None:
        """A control step raised a non-link error: stop the wheels, drop the command, report."""
        self.step_errors += 1
        self.last_step_error = self._step_error_window = str(exc)
        self.runtime.filter.halt()
        self.get_logger().error(f"control step failed, wheels commanded to zero: {exc}", throttle_duration_sec=1.0)
        try:
            self.stop_wheels(now)
        except OmnikinError as stop_exc:
            self.get_logger().error(f"cannot command zero wheel speeds: {stop_exc}", throttle_duration_sec=1.0)

    def _retry_link(self):
        """Every ``link_retry_period`` while the link is lost: reopen and re-arm it. The
        command is dropped, so the wheels stay stopped until a new cmd_vel arrives."""
        period = self.p["link_retry_period"]
        reconnect = getattr(self.runtime.backend, "reconnect", None)
        if not period or reconnect is None or not getattr(self.runtime.backend, "link_lost", False):
            return
        now = self.now_s()
        if self._next_retry is None:
            self._next_retry = now + period
        if now < self._next_retry:
            return
        self._next_retry = now + period
        try:
            reconnect()
        except LinkError as exc:
            self.get_logger().warning(f"link not re-armed yet: {exc}", throttle_duration_sec=5.0)
            return
        self.runtime.filter.halt()
        self.link_rearms += 1
        self.get_logger().info("serial link re-armed: the wheels stay stopped until a new cmd_vel arrives")

    def periods_missed(self, now: float) -> int:
        """Control periods due since the first cycle that did not run (:func:`messages.periods_missed`)."""
        return messages.periods_missed(self._first_loop, self.loops, self.period, now)

    def _diagnostics(self):
        s = self.runtime.filter.stats
        now = time.monotonic()
        t_prev, n_prev = self._window
        self._window = (now, self.published)
        link_stats = self.runtime.backend.stats()
        dropped = float(link_stats.get("time_dropped", 0.0))
        dropped_window, self._dropped_window = dropped - self._dropped_window, dropped
        overruns_window, self._overruns_window = self._overruns_window, 0
        loop_time_max, self._loop_time_max = self._loop_time_max, 0.0
        values = messages.diagnostic_values(
            published=self.published,
            loop_rate_hz=messages.rate(self.published, n_prev, now, t_prev),
            periods_missed=self.periods_missed(now),
            command_stats=dataclasses.asdict(s),
            stale_commands=self.stale_commands,
            fk_residual_norm=float(np.linalg.norm(self.runtime.odometry.residual)),
            timed_out=self.runtime.filter.timed_out,
            link_rearms=self.link_rearms,
            step_errors=self.step_errors,
            last_step_error=self.last_step_error,
            link_stats=link_stats,
            loop_overruns=self.overruns,
            loop_time_max_ms=1e3 * loop_time_max,
            joint_commands_rejected=self.joint_commands_rejected,
        )
        level, message = messages.diagnostic_status(
            rejected=s.rejected,
            stale=self.stale_commands,
            waiting_for=str(link_stats.get("waiting_for", "")),
            link_error=self.link_error,
            step_error=self._step_error_window,
            overruns=overruns_window,
            dropped=dropped_window,
            fallen=str(link_stats.get("fallen", "")),
        )
        if link_stats.get("fallen") and not self._fall_logged:
            self._fall_logged = True
            self.get_logger().error(f"wheels stopped: {link_stats['fallen']}")
        self._step_error_window = ""
        status = DiagnosticStatus(
            level=bytes([level]), name="omnikin base", message=message, hardware_id=self.robot.name
        )
        status.values = [KeyValue(key=k, value=v) for k, v in values]
        follower = self.follower
        path_status = DiagnosticStatus(
            level=bytes([messages.WARN if follower.state == "refused" else messages.OK]),
            name="omnikin path",
            message=follower.summary(),
            hardware_id=self.robot.name,
        )
        path_values = [*follower.values(), ("paths_received", str(self.paths_received))]
        path_status.values = [KeyValue(key=k, value=v) for k, v in path_values]
        arr = DiagnosticArray()
        arr.header.stamp = self.clock_now().to_msg()
        arr.status = [status, path_status]
        self.diag_pub.publish(arr)

    def close_planner(self) -> None:
        """Drop the path waiting to be planned or being planned (its thread does not hold up the
        exit), quietly: the node's log may be gone."""
        self._cancel_path("the node is stopping", log=False)

    def stop_wheels(self, now: float | None = None) -> None:
        """Command zero speed to every rolling wheel (steering left where it is)."""
        zero = np.zeros(len(self.robot.rolling_names))
        self.runtime.backend.write(self.now_s() if now is None else now, zero, None)


def build_node(robot, backend, values: dict, name: str = NODE_NAME) -> BaseNode:
    """The node around ``backend`` (rclpy initialised); see :class:`BaseNode`."""
    return BaseNode(robot, backend, values, name)


def run(robot, backend, values: dict, ros_args=None) -> int:
    """Initialise rclpy, spin the node until SIGINT/SIGTERM, stop the wheels, shut down."""
    try:
        rclpy.init(args=["omnikin"] + (["--ros-args"] + list(ros_args) if ros_args else []))
    except (RuntimeError, ValueError) as exc:  # rclpy's errors for bad --ros-args (RCLError, ...)
        backend.close()
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"--ros-args: {type(exc).__name__}: {first}") from None
    try:
        node = BaseNode(robot, backend, values)
    except BaseException:
        backend.close()
        rclpy.shutdown()
        raise

    def stop(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if rclpy.ok():
            raise
        # SIGINT shut the context down while a callback ran: its publish found the context gone
    finally:
        try:
            node.stop_wheels()
        except OmnikinError as exc:
            node.get_logger().error(f"cannot command zero wheel speeds: {exc}")
        backend.close()
        node.close_planner()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
