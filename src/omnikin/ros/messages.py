"""What the node's messages contain, as plain numbers: no rclpy here.

The node (:mod:`omnikin.ros.node`) only copies these values into message objects, so the
content of every message is computed, and tested, without ROS 2.

Frames (REP-103, REP-105): ``odom`` is the world frame fixed where the robot started;
``base_link`` has x forward, y left, z up. A pose is ``(x [m], y [m], theta [rad])`` of the
base in ``odom``; a twist is ``(vx [m/s], vy [m/s], omega [rad/s])`` in base axes; 3 x 3
covariances are over ``(x, y, theta)`` (pose, [m^2, m rad, rad^2]) or ``(vx, vy, omega)``
(twist). ROS's 6 x 6 covariances are row-major over ``(x, y, z, roll, pitch, yaw)``.

Times: the runtime runs on the monotonic clock [s]; message stamps are the node's ROS clock
[s]. :func:`command_time` maps a ``TwistStamped``'s stamp onto the monotonic clock.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import InputError

OK, WARN, ERROR = 0, 1, 2
"""Diagnostic levels, equal to ``diagnostic_msgs/DiagnosticStatus`` OK, WARN and ERROR."""

COVARIANCE_INDEX = (0, 1, 5)
"""Rows/columns of x, y and yaw in ROS's 6 x 6 (x, y, z, roll, pitch, yaw) covariance."""


def quaternion(theta: float) -> tuple:
    """Unit quaternion ``(x, y, z, w)`` of a rotation by ``theta`` [rad] about z."""
    return 0.0, 0.0, math.sin(0.5 * theta), math.cos(0.5 * theta)


def covariance6(c3) -> list:
    """36 floats, row-major: the 6 x 6 (x, y, z, roll, pitch, yaw) covariance whose (x, y, yaw)
    block is the symmetric part of the 3 x 3 ``c3`` over (x, y, theta); z, roll and pitch rows and
    columns are zero (a planar base does not move in them). Units as in ``c3``."""
    c = np.asarray(c3, dtype=float)
    if c.shape != (3, 3):
        raise InputError(f"covariance6 needs a 3 x 3 matrix, got shape {c.shape}")
    out = np.zeros((6, 6))
    out[np.ix_(COVARIANCE_INDEX, COVARIANCE_INDEX)] = 0.5 * (c + c.T)
    return [float(v) for v in out.ravel()]


def odometry_content(pose, twist, pose_covariance, twist_covariance) -> dict:
    """``nav_msgs/Odometry`` content: ``position`` (x, y, z) [m] and ``orientation`` (x, y, z, w)
    of the base in odom, ``pose_covariance`` (36), ``linear`` (vx, vy, vz) [m/s] and ``angular``
    (wx, wy, wz) [rad/s] in base axes, ``twist_covariance`` (36)."""
    x, y, theta = (float(v) for v in pose)
    vx, vy, omega = (float(v) for v in twist)
    return {
        "position": (x, y, 0.0),
        "orientation": quaternion(theta),
        "pose_covariance": covariance6(pose_covariance),
        "linear": (vx, vy, 0.0),
        "angular": (0.0, 0.0, omega),
        "twist_covariance": covariance6(twist_covariance),
    }


def transform_content(pose) -> dict:
    """``geometry_msgs/Transform`` odom -> base: ``translation`` (x, y, z) [m], ``rotation`` (x, y, z, w)."""
    x, y, theta = (float(v) for v in pose)
    return {"translation": (x, y, 0.0), "rotation": quaternion(theta)}


def joint_state_content(
    wheels: Sequence[str], positions, velocities, steer_joints: Sequence[str] = (), steer=None
) -> tuple:
    """``sensor_msgs/JointState`` ``(name, position, velocity)``: one joint per encoded wheel
    (angle since the start [rad], speed [rad/s]), then one per steerable wheel (steering angle
    [rad]; velocity 0.0: the back-ends do not measure steering rates)."""
    positions = [float(v) for v in positions]
    velocities = [float(v) for v in velocities]
    if len(positions) != len(wheels) or len(velocities) != len(wheels):
        raise InputError(f"{len(wheels)} wheel joints, {len(positions)} positions, {len(velocities)} velocities")
    steer = [] if steer is None else [float(v) for v in steer]
    if len(steer) != len(steer_joints):
        raise InputError(f"{len(steer_joints)} steering joints, {len(steer)} steering angles")
    return list(wheels) + list(steer_joints), positions + steer, velocities + [0.0] * len(steer)


def command_time(received: float, ros_now: float, stamp: float, timeout: float) -> float | None:
    """Runtime time [s] of a ``TwistStamped`` received at runtime time ``received`` (monotonic
    clock), when the node's ROS clock read ``ros_now`` [s] and the message's stamp is ``stamp``
    [s] (ROS clock of the sender): the command counts from when it was stamped, so delivery
    latency does not extend it (as ros2_controllers' controllers do).

    * ``stamp == 0``: an unstamped message; it counts from its arrival.
    * A stamp ahead of ``ros_now`` (clocks not synchronised) counts from its arrival.
    * A command older than ``timeout`` [s] (when > 0) is stale: ``None``, to be ignored.
    """
    if stamp == 0.0:
        return received
    age = max(0.0, ros_now - stamp)
    if timeout > 0.0 and age > timeout:
        return None
    return received - age


def wheel_command_twist(robot, wheels: Sequence[str], names, velocities, positions) -> np.ndarray:
    """The body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] a ``sensor_msgs/JointState`` on
    ``joint_commands`` asks for (ros2_control's topic-based hardware interface: one velocity
    [rad/s] per wheel joint, a position [rad] per ``<wheel>_steer`` joint of a steerable robot):
    the forward kinematics' least-squares fit of the velocities of ``wheels`` (the joints of
    ``joint_states``), so that wheel speeds that fight each other (a slip the layout cannot make)
    are not sent on as they are. Other names are ignored.

    Raises
    ------
    InputError
        In one line: names and velocities (or positions) of different lengths, a name given
        twice, a wheel or steering joint missing, a value that is not finite.
    """
    names = [str(n) for n in names]
    velocities = list(velocities)
    positions = list(positions)
    if len(velocities) != len(names):
        raise InputError(f"joint_commands: {len(names)} names but {len(velocities)} velocities")
    if len(set(names)) != len(names):
        raise InputError("joint_commands: a joint is named twice")
    index = {n: i for i, n in enumerate(names)}
    missing = [w for w in wheels if w not in index]
    if missing:
        raise InputError(f"joint_commands: no velocity for the wheel joint(s) {', '.join(missing)}")
    speeds = np.array([float(velocities[index[w]]) for w in wheels])
    if not np.all(np.isfinite(speeds)):
        raise InputError("joint_commands: a wheel velocity is not finite")
    steer = None
    if robot.steerable:
        joints = [f"{n}_steer" for n in robot.steer_names]
        absent = [j for j in joints if j not in index or index[j] >= len(positions)]
        if absent:
            raise InputError(f"joint_commands: no position for the steering joint(s) {', '.join(absent)}")
        steer = np.array([float(positions[index[j]]) for j in joints])
        if not np.all(np.isfinite(steer)):
            raise InputError("joint_commands: a steering position is not finite")
    return np.asarray(robot.fk(speeds, steer, wheels=list(wheels)).twist, dtype=float)


def periods_missed(first_loop: float | None, loops: int, period: float, now: float) -> int:
    """Control periods due since the first cycle (at ``first_loop`` [s]) that did not run, at
    time ``now`` [s], with ``loops`` cycles run: rcl skips the periods of a late timer instead of
    running them in a burst. A period counts as due half a period after its time."""
    if first_loop is None:
        return 0
    due = int((now - first_loop) / period - 0.5) + 1
    return max(0, due - loops)


def rate(count: int, count_before: int, t: float, t_before: float) -> float:
    """Events per second [Hz] between two readings of a counter; 0 over an empty interval."""
    return (count - count_before) / (t - t_before) if t > t_before else 0.0


def diagnostic_values(
    *,
    published: int,
    loop_rate_hz: float,
    periods_missed: int,
    command_stats: Mapping,
    stale_commands: int,
    fk_residual_norm: float,
    timed_out: bool,
    link_rearms: int,
    step_errors: int,
    last_step_error: str,
    link_stats: Mapping,
    loop_overruns: int = 0,
    loop_time_max_ms: float = 0.0,
    joint_commands_rejected: int = 0,
) -> list:
    """``(key, value)`` strings of the ``omnikin base`` status (``docs/ros.md``, section Topics):
    ``command_stats`` holds the command filter's counts (``accepted``, ``rejected``,
    ``timeouts``, ``saturated``, ``projected``, ``last_reject_reason``), ``link_stats`` the
    back-end's statistics (keys prefixed ``link_``); ``loop_overruns`` counts the control cycles
    longer than the period since the start, ``loop_time_max_ms`` is the longest cycle [ms] since
    the previous status, ``joint_commands_rejected`` counts the ``joint_commands`` ignored since
    the start."""
    values = {
        "odom_published": published,
        "loop_rate_hz": round(float(loop_rate_hz), 3),
        "periods_missed": periods_missed,
        "loop_overruns": loop_overruns,
        "loop_time_max_ms": round(float(loop_time_max_ms), 3),
        "commands_accepted": command_stats["accepted"],
        "commands_rejected": command_stats["rejected"],
        "command_timeouts": command_stats["timeouts"],
        "commands_saturated": command_stats["saturated"],
        "commands_projected": command_stats["projected"],
        "commands_stale": stale_commands,
        "joint_commands_rejected": joint_commands_rejected,
        "last_reject_reason": command_stats["last_reject_reason"],
        "fk_residual_norm": float(fk_residual_norm),
        "timed_out": bool(timed_out),
        "link_rearms": link_rearms,
        "step_errors": step_errors,
        "last_step_error": last_step_error,
    }
    values.update({f"link_{k}": v for k, v in link_stats.items()})
    return [(k, str(v)) for k, v in values.items()]


def diagnostic_status(
    *,
    rejected: int = 0,
    stale: int = 0,
    waiting_for: str = "",
    link_error: str = "",
    step_error: str = "",
    overruns: int = 0,
    dropped: float = 0.0,
    fallen: str = "",
) -> tuple:
    """``(level, message)`` of the ``omnikin base`` status, first rule that applies:

    0. ERROR ``wheels stopped: <fallen>`` once the simulated robot tipped over (``fallen``, the
       physics back-end's line: it stops the wheels and drives no more);
    1. ERROR ``wheels stopped: <error>`` while the link is lost (``link_error``);
    2. ERROR ``wheels stopped: control step failed: <error>`` when a control step failed since
       the previous status (``step_error``; a bug or a bad back-end, not a lost link);
    3. WARN ``waiting for the wheel controllers of <wheels>`` after (re-)arming a link;
    4. WARN ``<n> command(s) rejected`` and/or ``<n> stale command(s) ignored``, counts since start,
       and/or ``<n> control cycle(s) overran the period`` (``overruns``) and/or ``simulation
       <s> s behind real time`` (``dropped`` [s] of simulated time the physics back-end could
       not keep up with), both since the previous status;
    5. OK ``running``.
    """
    if fallen:
        return ERROR, f"wheels stopped: {fallen}"
    if link_error:
        return ERROR, f"wheels stopped: {link_error}"
    if step_error:
        return ERROR, f"wheels stopped: control step failed: {step_error}"
    if waiting_for:
        return WARN, f"waiting for the wheel controllers of {waiting_for}"
    problems = ([f"{rejected} command(s) rejected"] if rejected else []) + (
        [f"{stale} stale command(s) ignored"] if stale else []
    )
    if overruns:
        problems.append(f"{overruns} control cycle(s) overran the period")
    if dropped > 0.0:
        problems.append(f"simulation {dropped:.3g} s behind real time")
    if problems:
        return WARN, "; ".join(problems)
    return OK, "running"


def yaw(x: float, y: float, z: float, w: float) -> float:
    """The heading [rad] of a quaternion ``(x, y, z, w)``: the rotation about z of its rotation
    (ZYX Euler yaw, ``atan2(2 (w z + x y), w^2 + x^2 - y^2 - z^2)``, which for a quaternion that
    is not unit gives the heading of its direction); the zero quaternion (never a rotation) reads
    as 0, and one with a component that is not finite as NaN (a waypoint refused as not finite)."""
    if not all(math.isfinite(v) for v in (x, y, z, w)):
        return math.nan
    if not (x or y or z or w):
        return 0.0
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


def plan_frame_error(frame: str, odom_frame: str) -> str | None:
    """Why a ``nav_msgs/Path`` in ``frame`` cannot be followed (None when it can): the node
    follows paths in its odometry frame (an empty frame counts as it); it looks up no transform.
    The frame is named in ASCII, shortened (a look-alike letter shows as its code)."""
    if frame in ("", odom_frame):
        return None
    shown = ascii(frame if len(frame) <= 60 else frame[:60] + "...")
    return (
        f"a path in frame {shown}: this node follows paths in its odometry frame {odom_frame!r} "
        f"(it looks up no transform; publish the plan in {odom_frame!r})"
    )


REFERENCE_POSES = 2000
"""Most poses of a ``reference_path`` message (:func:`reference_samples`)."""


def reference_samples(trajectory, period: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """The timed reference of a followed path as ``nav_msgs/Path`` content: times ``(m,)`` [s from
    its start], ``period`` apart (or farther, so that there are at most :data:`REFERENCE_POSES`)
    and its end, and poses ``(m, 3)`` [m, m, rad] in odom."""
    period = max(period, trajectory.duration / (REFERENCE_POSES - 1))
    t = np.append(np.arange(0.0, trajectory.duration, period), trajectory.duration)
    pose, _, _ = trajectory.at(t)
    return t, pose


def _cdr_reader(data: bytes, what: str):
    """Readers of a serialized message (CDR, as ROS 2's middleware sends it: a 4-byte
    encapsulation header, big- or little-endian, then the fields aligned to their size from
    after the header): ``take(fmt, align)`` and ``string()``, each an
    :class:`~omnikin.errors.InputError` naming ``what`` past the end of ``data``."""
    import struct

    if len(data) < 4 or data[0] != 0 or data[1] not in (0, 1):
        raise InputError(f"{what}: not a CDR message")
    order = "<" if data[1] == 1 else ">"
    offset = 4

    def take(fmt: str, align: int) -> tuple:
        nonlocal offset
        offset += (-(offset - 4)) % align
        size = struct.calcsize(order + fmt)
        if offset + size > len(data):
            raise InputError(f"{what}: the message ends early (at byte {len(data)})")
        values = struct.unpack_from(order + fmt, data, offset)
        offset += size
        return values

    def string() -> str:
        nonlocal offset
        (n,) = take("I", 4)
        if n == 0 or offset + n > len(data):
            raise InputError(f"{what}: a string runs past the end of the message")
        text = data[offset : offset + n - 1].decode("utf-8", errors="replace")
        offset += n
        return text

    def left() -> int:
        return len(data) - offset

    return take, string, left


def plan_frame(data: bytes) -> str:
    """The ``header.frame_id`` of a serialized ``nav_msgs/Path`` (read without its poses)."""
    take, string, _ = _cdr_reader(data, "plan")
    take("iI", 4)
    return string()


def plan_count(data: bytes) -> int:
    """How many poses a serialized ``nav_msgs/Path`` says it has (read without them)."""
    take, string, _ = _cdr_reader(data, "plan")
    take("iI", 4)
    string()
    return int(take("I", 4)[0])


PLAN_POSE_BYTES = 8 + 4 + 1 + 56
"""The fewest bytes a serialized ``geometry_msgs/PoseStamped`` takes (stamp, an empty frame id,
seven doubles): a count of poses beyond what the message's bytes can hold is refused."""


def plan_poses(data: bytes, limit: int) -> np.ndarray:
    """The poses of a serialized ``nav_msgs/Path`` as ``(n, 3)`` ``(x [m], y [m], yaw [rad])``
    (:func:`yaw` of each orientation), read in Python (no message objects: 100,000 poses in some
    0.2 s, a thread that reads them does not hold the interpreter as the bindings' conversion
    does). More than ``limit`` poses, or a count the bytes cannot hold: an
    :class:`~omnikin.errors.InputError` in one line."""
    take, string, left = _cdr_reader(data, "plan")
    take("iI", 4)
    string()
    (n,) = take("I", 4)
    if n > limit:
        raise InputError(f"a path of {n} poses: more than {limit}")
    if n * PLAN_POSE_BYTES > left():
        raise InputError(f"a path that says it has {n} poses in {len(data)} bytes")
    out = np.empty((n, 3))
    for k in range(n):
        take("iI", 4)
        string()
        x, y, _, qx, qy, qz, qw = take("7d", 8)
        out[k] = (x, y, yaw(qx, qy, qz, qw))
    return out
