"""``omnikin ros``: the ROS 2 base driver node.

Subscribes ``cmd_vel`` (``geometry_msgs/Twist``, or ``TwistStamped`` with
``use_stamped_vel``); publishes ``odom`` (``nav_msgs/Odometry`` with twist and a
motion-dependent covariance), ``joint_states`` (wheel positions [rad] and speeds [rad/s],
steering joints ``<wheel>_steer``), ``/diagnostics`` (command and link statistics, the
forward-kinematics residual) and, when ``tf2_msgs`` is importable, ``/tf`` odom -> base_link.
``tf2_msgs`` is not among the ROS 2 wheels on PyPI: with the PyPI install the node says so
once and publishes no ``/tf``; run it from a ROS 2 install (``source /opt/ros/<distro>/
setup.bash``) to get it. Parameters: :mod:`omnikin.ros.params`.

The control loop runs at ``publish_rate``: read the wheels, update the odometry, filter the
command (timeout, limits), command the wheels, publish. Time inside the runtime is the
monotonic clock; message stamps are the node's ROS clock. On shutdown (SIGINT, SIGTERM)
the wheels are commanded to zero before the node exits.
"""

from __future__ import annotations

import math
import signal
import time

import numpy as np

from ..errors import InputError, LinkError
from ..limits import MotionLimits
from . import require_rclpy
from .params import DEFAULTS, validate


def _quaternion(theta: float):
    return 0.0, 0.0, math.sin(0.5 * theta), math.cos(0.5 * theta)


def _cov6(c3: np.ndarray) -> list:
    """6x6 row-major covariance (x, y, z, roll, pitch, yaw) from a 3x3 (x, y, yaw) one."""
    out = np.zeros((6, 6))
    idx = [0, 1, 5]
    out[np.ix_(idx, idx)] = c3
    return [float(v) for v in out.ravel()]


def build_node(robot, backend, values: dict, name: str = "omnikin_base"):
    """The rclpy node around a :class:`~omnikin.runtime.base.BaseRuntime` (rclpy initialised)."""
    require_rclpy()
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import Twist, TwistStamped
    from nav_msgs.msg import Odometry
    from rcl_interfaces.msg import ParameterDescriptor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    from ..runtime.base import BaseRuntime

    try:
        from geometry_msgs.msg import TransformStamped
        from tf2_msgs.msg import TFMessage
    except ImportError:
        TFMessage = None

    class BaseNode(Node):
        def __init__(self):
            super().__init__(name)
            dynamic = ParameterDescriptor(dynamic_typing=True)    # our own checks name the parameter
            for key, default in values.items():
                self.declare_parameter(key, default, dynamic)
            p = validate({k: self.get_parameter(k).value for k in DEFAULTS}, "--ros-args / parameters")
            link_timeout = getattr(backend, "link_timeout", None)
            if link_timeout is not None and 1.0 / p["publish_rate"] > 0.5 * link_timeout:
                raise InputError(
                    f"publish_rate {p['publish_rate']:g} Hz is too slow for the serial link: the wheel controllers "
                    f"stop after {link_timeout:g} s without a frame; use at least {2.0 / link_timeout:g} Hz")
            limits = MotionLimits(linear=p["linear.x.max_velocity"], angular=p["angular.z.max_velocity"],
                                  linear_accel=p["linear.x.max_acceleration"],
                                  angular_accel=p["angular.z.max_acceleration"],
                                  wheel=p["wheel_max_velocity"] or None)
            self.runtime = BaseRuntime(robot, backend, limits=limits, cmd_vel_timeout=p["cmd_vel_timeout"],
                                       wheel_slip=p["wheel_slip"])
            self.runtime.filter.reject_above = p["reject_above"]
            self.p = p
            qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
            msg_type = TwistStamped if p["use_stamped_vel"] else Twist
            self.create_subscription(msg_type, "cmd_vel", self._on_cmd, qos)
            self.odom_pub = self.create_publisher(Odometry, "odom", qos)
            self.joint_pub = self.create_publisher(JointState, "joint_states", qos)
            self.diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
            self.tf_pub = None
            if p["enable_odom_tf"]:
                if TFMessage is None:
                    self.get_logger().warning(
                        "tf2_msgs is not importable (it is not among the ROS 2 wheels on PyPI): no /tf "
                        "odom->base_link; run this node from a ROS 2 install to publish it")
                else:
                    self.tf_pub = self.create_publisher(TFMessage, "/tf", qos)
            self.published = 0
            self.link_rearms = 0                   # lost links re-armed (serial back-end)
            self._next_retry = None
            self.period = 1.0 / p["publish_rate"]
            self.loops = 0                         # control cycles run
            self._first_loop = None
            self._window = (time.monotonic(), 0)   # (time, published) at the last diagnostics
            self.link_error = ""
            self.joint_names = list(self.runtime.encoded)
            self.steer_names = [f"{n}_steer" for n in robot.steer_names]
            self.create_timer(1.0 / p["publish_rate"], self._loop)
            self.create_timer(1.0, self._diagnostics)
            self._DiagnosticArray, self._DiagnosticStatus, self._KeyValue = DiagnosticArray, DiagnosticStatus, KeyValue
            self._Odometry, self._JointState = Odometry, JointState
            self._TransformStamped, self._TFMessage = (TransformStamped, TFMessage) if TFMessage else (None, None)

        def now_s(self) -> float:
            """Runtime time [s]: the monotonic clock, the same one the back-ends use."""
            return time.monotonic()

        def _on_cmd(self, msg):
            tw = msg.twist if self.p["use_stamped_vel"] else msg
            self.runtime.command((tw.linear.x, tw.linear.y, tw.angular.z), self.now_s())

        def _loop(self):
            if self._first_loop is None:
                self._first_loop = self.now_s()
            self.loops += 1
            try:
                res = self.runtime.step(self.now_s())
            except LinkError as exc:      # link lost: the back-end already commands zero speeds
                self.link_error = str(exc)
                self.get_logger().error(str(exc), throttle_duration_sec=1.0)
                self._retry_link()
                return
            self.link_error = ""
            self._next_retry = None
            stamp = self.get_clock().now().to_msg()
            odom = self._Odometry()
            odom.header.stamp = stamp
            odom.header.frame_id = self.p["odom_frame_id"]
            odom.child_frame_id = self.p["base_frame_id"]
            x, y, th = res.pose
            odom.pose.pose.position.x, odom.pose.pose.position.y = float(x), float(y)
            q = _quaternion(th)
            o = odom.pose.pose.orientation
            o.x, o.y, o.z, o.w = q
            odom.pose.covariance = _cov6(0.5 * (res.pose_covariance + res.pose_covariance.T))
            vx, vy, w = res.twist
            odom.twist.twist.linear.x, odom.twist.twist.linear.y = float(vx), float(vy)
            odom.twist.twist.angular.z = float(w)
            odom.twist.covariance = _cov6(0.5 * (res.twist_covariance + res.twist_covariance.T))
            self.odom_pub.publish(odom)
            js = self._JointState()
            js.header.stamp = stamp
            js.name = self.joint_names + self.steer_names
            steer = list(res.state.steer) if res.state.steer is not None else []
            js.position = [float(v) for v in res.state.positions] + [float(v) for v in steer]
            js.velocity = [float(v) for v in res.state.velocities] + [0.0] * len(steer)
            self.joint_pub.publish(js)
            if self.tf_pub is not None:
                tf = self._TransformStamped()
                tf.header.stamp = stamp
                tf.header.frame_id = self.p["odom_frame_id"]
                tf.child_frame_id = self.p["base_frame_id"]
                tf.transform.translation.x, tf.transform.translation.y = float(x), float(y)
                r = tf.transform.rotation
                r.x, r.y, r.z, r.w = q
                self.tf_pub.publish(self._TFMessage(transforms=[tf]))
            self.published += 1

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
            """Control periods due since the first cycle that did not run (rcl skips the
            periods of a late timer instead of running them in a burst)."""
            if self._first_loop is None:
                return 0
            due = int((now - self._first_loop) / self.period - 0.5) + 1    # due over half a period ago
            return max(0, due - self.loops)

        def _diagnostics(self):
            s = self.runtime.filter.stats
            now = time.monotonic()
            t_prev, n_prev = self._window
            self._window = (now, self.published)
            loop_rate = (self.published - n_prev) / (now - t_prev) if now > t_prev else 0.0
            values = {"odom_published": self.published, "loop_rate_hz": round(loop_rate, 3),
                      "periods_missed": self.periods_missed(now), "commands_accepted": s.accepted,
                      "commands_rejected": s.rejected, "command_timeouts": s.timeouts,
                      "commands_saturated": s.saturated, "commands_projected": s.projected,
                      "last_reject_reason": s.last_reject_reason,
                      "fk_residual_norm": float(np.linalg.norm(self.runtime.odometry.residual)),
                      "timed_out": self.runtime.filter.timed_out, "link_rearms": self.link_rearms}
            values.update({f"link_{k}": v for k, v in self.runtime.backend.stats().items()})
            status = self._DiagnosticStatus(level=DiagnosticStatus.OK, name="omnikin base",
                                            message="running", hardware_id=robot.name)
            if s.rejected:
                status.level = DiagnosticStatus.WARN
                status.message = f"{s.rejected} command(s) rejected"
            waiting = values.get("link_waiting_for")
            if waiting and not self.link_error:
                status.level = DiagnosticStatus.WARN
                status.message = f"waiting for the wheel controllers of {waiting}"
            if self.link_error:
                status.level = DiagnosticStatus.ERROR
                status.message = f"wheels stopped: {self.link_error}"
            status.values = [self._KeyValue(key=k, value=str(v)) for k, v in values.items()]
            arr = self._DiagnosticArray()
            arr.header.stamp = self.get_clock().now().to_msg()
            arr.status = [status]
            self.diag_pub.publish(arr)

        def stop_wheels(self):
            zero = np.zeros(len(robot.rolling_names))
            self.runtime.backend.write(self.now_s(), zero, None)

    return BaseNode()


def run(robot, backend, values: dict, ros_args=None) -> int:
    """Initialise rclpy, spin the node until SIGINT/SIGTERM, stop the wheels, shut down."""
    require_rclpy()
    import rclpy
    from rclpy.executors import ExternalShutdownException

    try:
        rclpy.init(args=["omnikin"] + (["--ros-args"] + list(ros_args) if ros_args else []))
    except Exception as exc:                       # rclpy's errors for bad --ros-args
        backend.close()
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"--ros-args: {type(exc).__name__}: {first}") from None
    try:
        node = build_node(robot, backend, values)
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
    finally:
        node.stop_wheels()
        backend.close()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
