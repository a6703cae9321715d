"""ROS 2 bags (rosbag2, sqlite3 or MCAP storage) in and out, through ``rosbags`` (pure Python).

``rosbags`` is imported on first use; without it every function raises an ``ImportError``
naming the extra to install: ``pip install "omnikin[bags]"``. No ROS installation is needed.

What is read:

* ``sensor_msgs/msg/JointState`` (:func:`read_joint_states`): the wheel angles [rad] of the
  robot's encoded wheels (rolling wheels with an ``encoder``, file order), each found by
  **joint name = wheel name**; for a steerable wheel ``W`` its steering angle [rad, relative
  to the mounting ``drive_deg``] from the joint ``W_steer``. Positions are taken in omnikin's
  sign convention (positive drives the hub along ``+u_i``; ``encoder.invert`` concerns raw
  ticks only). Other joints in the messages are ignored; messages that carry none of the
  wheels are skipped; a message that carries some but not all of them is an error. The time
  of a sample is its ``header.stamp``, or the bag's record time when every header stamp is
  zero (``stamp="auto"``, the default; ``"header"`` or ``"bag"`` to force one). A message
  repeating the previous one exactly (time and positions) is dropped and counted.
* ``nav_msgs/msg/Odometry`` and ``geometry_msgs/msg/PoseStamped`` (:func:`read_poses`): the 2D
  pose ``(x, y, yaw)``, yaw of the orientation quaternion
  ``atan2(2 (w z + x y), w^2 + x^2 - y^2 - z^2)``, at ``header.stamp``.

What is written (:func:`write_odometry`, :func:`record_run`): ``nav_msgs/msg/Odometry`` with
``header.frame_id`` (default ``odom``) and ``child_frame_id`` (default ``base_link``, REP-105),
position ``(x, y, 0)``, orientation the yaw quaternion ``(0, 0, sin(theta/2), cos(theta/2))``,
twist ``(vx, vy, 0; 0, 0, omega)`` in the child frame (REP-103 body axes: the mean twist of the
interval that ends at the sample, zero at the first sample) and 36-element row-major
covariances over ``(x, y, z, roll, pitch, yaw)`` (zero unless given; a 6-vector is taken as
the diagonal). Bags are written with the message definitions of ROS 2 Humble (identical for
these types in later distributions), rosbag2 format version 8, sqlite3 storage by default.
A bag is a new folder (:mod:`omnikin.io.output`, ``folder="data"``): an existing path is
refused, unless ``force`` and it is a bag omnikin wrote (replaced as a whole); an input bag is
never an output, nor holds one. The bag is written beside its name and moved there when
complete, so an interrupted run leaves nothing behind; messages are serialized and written one
at a time (memory does not grow with the bag).

Every problem with an input (no such bag, unreadable bag, missing topic, wrong message type,
wrong joint names, undecodable message) raises :class:`BagError` naming the bag and topic, in
one line (messages of ``rosbags`` that span lines are flattened). Readers take a bound on the
messages of the topic held in memory (``max_messages``, also checked against the count the
bag declares before reading) and on the size of one message (``max_message_bytes``); beyond
them they raise :class:`omnikin.errors.ResourceLimitError`.
"""

from __future__ import annotations

import heapq
import math
import os
import re
import stat
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..common.messages import one_line, shorten
from ..errors import BagError, OmnikinError, ResourceLimitError
from ..kinematics.robot import Robot
from ..kinematics.se2 import between, log
from ..motion.timing import check_start_time
from ..sensors.readings import Readings
from .output import check_output, data_folder

BAGS_EXTRA = 'pip install "omnikin[bags]"'

JOINT_STATE = "sensor_msgs/msg/JointState"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TWIST = "geometry_msgs/msg/Twist"
POSE_TYPES = (ODOMETRY, POSE_STAMPED)
STORAGES = ("sqlite3", "mcap")
STEER_SUFFIX = "_steer"
STAMPS = ("auto", "header", "bag")

NS = 1_000_000_000

ROS_TIME_SPAN = (0.0, 2.0**31 - 1)
"""The times [s] a ROS 2 bag can stamp: ``builtin_interfaces/Time`` holds int32 seconds, and
rclcpp, rclpy and MCAP (unsigned log times) refuse a negative time."""


TOPIC = re.compile(r"^/?[A-Za-z_~][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
"""ROS 2 topic names: tokens of letters, digits and underscores separated by '/', not starting
with a digit; '~' only at the start."""


def check_topic(name: str, what: str = "topic") -> str:
    """``name`` if it is a valid ROS 2 topic name, else :class:`BagError` naming it."""
    if not isinstance(name, str) or not TOPIC.match(name):
        raise BagError(
            f"{what}: {name!r} is not a valid ROS 2 topic name (letters, digits and underscores "
            f"separated by '/', e.g. /odom)"
        )
    return name


FRAME_ID = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
"""tf2 frame ids as omnikin writes them: the tokens of a ROS 2 name (letters, digits and
underscores, not starting with a digit) separated by '/', without a leading '/' (tf2 drops
it, REP-105 names such as ``odom``, ``base_link``, ``robot1/odom``)."""


def check_frame_ids(frame_id: str, child_frame_id: str, what: tuple[str, str] = ("frame_id", "child_frame_id")) -> None:
    """Refuse (:class:`BagError`, one line) a frame id that is not a valid tf2 frame name
    (:data:`FRAME_ID`) or a child frame equal to its parent (an Odometry message relates two
    frames). ``what``: the names of the two in messages (the command line's options)."""
    for name, label in zip((frame_id, child_frame_id), what, strict=True):
        if not isinstance(name, str) or not FRAME_ID.fullmatch(name):
            raise BagError(
                f"{label}: {shorten(name)} is not a valid frame id (letters, digits and underscores "
                f"separated by '/', no leading '/', e.g. odom, base_link)"
            )
    if frame_id == child_frame_id:
        raise BagError(f"{what[1]} {child_frame_id!r} is the same frame as {what[0]}; the child frame is the robot's")


# --- rosbags, lazily ---------------------------------------------------------------------------------------
class _Rosbags:
    """The parts of ``rosbags`` omnikin uses, imported once."""

    _instance = None

    def __init__(self):
        try:
            from rosbags.rosbag2 import Reader, Writer
            from rosbags.typesys import Stores, get_typestore
        except ImportError:
            raise ImportError(f"reading and writing ROS 2 bags needs the rosbags package: {BAGS_EXTRA}") from None
        self.Reader = Reader
        self.Writer = Writer
        self.store = get_typestore(Stores.ROS2_HUMBLE)
        self.types = self.store.types

    @classmethod
    def get(cls) -> _Rosbags:
        if cls._instance is None:
            cls._instance = cls()
        return cls._instance


def require_rosbags() -> None:
    """Import ``rosbags`` or raise an ``ImportError`` naming the ``bags`` extra."""
    _Rosbags.get()


# --- time ----------------------------------------------------------------------------------------------
def _stamp_ns(stamp) -> int:
    return int(stamp.sec) * NS + int(stamp.nanosec)


def _time_msg(rb: _Rosbags, ns: int):
    sec, nsec = divmod(int(ns), NS)
    return rb.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)


def seconds_to_ns(t) -> np.ndarray:
    """Seconds (float array) to integer nanoseconds, rounded."""
    return np.round(np.asarray(t, dtype=float) * 1e9).astype(np.int64)


# --- reading -------------------------------------------------------------------------------------------
def _check_bag_path(bag) -> Path:
    """``bag`` as a :class:`Path` if it is a folder or a regular file, holding no device, pipe or
    socket (which could block the reader forever), else :class:`BagError`."""
    path = Path(bag)
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):  # missing, or a name too long or with NUL
        raise BagError(
            f"{one_line(bag, 300)}: no such bag (expected a rosbag2 directory, or a .db3 or .mcap file)"
        ) from None
    inside = []
    if stat.S_ISDIR(mode):
        try:
            inside = [entry for entry in os.scandir(path) if not (entry.is_file() or entry.is_dir())]
        except OSError as exc:
            raise BagError(f"{bag}: cannot read the bag: {exc.strerror or exc}") from None
    elif not stat.S_ISREG(mode):
        raise BagError(
            f"{bag}: not a bag but a device, pipe or socket (a bag is a rosbag2 directory, or a .db3 or .mcap file)"
        )
    if inside:
        raise BagError(f"{bag}: holds {inside[0].name!r}, a device, pipe or socket, not a bag file")
    return path


def _open_reader(rb: _Rosbags, bag):
    path = _check_bag_path(bag)
    try:
        reader = rb.Reader(path)
        reader.open()
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 (rosbags raises ReaderError, FileNotFoundError, sqlite3 and MCAP errors)
        raise BagError(f"{bag}: cannot read the bag: {one_line(exc)}") from None
    return reader


def topic_types(bag) -> dict[str, str]:
    """``{topic: message type}`` of a bag."""
    rb = _Rosbags.get()
    reader = _open_reader(rb, bag)
    try:
        return {c.topic: c.msgtype for c in reader.connections}
    finally:
        reader.close()


def message_count(bag, topic: str) -> int:
    """Number of messages of ``topic`` the bag declares (its metadata; 0 for no such topic),
    read without reading the messages: for sizing a job before starting it."""
    rb = _Rosbags.get()
    reader = _open_reader(rb, bag)
    try:
        return sum(int(getattr(c, "msgcount", 0) or 0) for c in reader.connections if c.topic == topic)
    finally:
        reader.close()


def _messages(
    bag, topic: str, allowed: Iterable[str], max_messages: int | None = None, max_message_bytes: int | None = None
) -> Iterator[tuple[int, int, Any, str]]:
    """Yield ``(index, bag time [ns], message, msgtype)`` of ``topic``, checking its type and
    the bounds (module docstring)."""
    rb = _Rosbags.get()
    allowed = tuple(allowed)
    reader = _open_reader(rb, bag)
    try:
        conns = [c for c in reader.connections if c.topic == topic]
        if not conns:
            have = ", ".join(f"{c.topic} ({c.msgtype})" for c in sorted(reader.connections, key=lambda c: c.topic))
            raise BagError(f"{bag}: no topic {shorten(topic)} in the bag; it has: {one_line(have or 'no topics', 500)}")
        bad = sorted({c.msgtype for c in conns if c.msgtype not in allowed})
        if bad:
            raise BagError(f"{bag}: topic {topic!r} carries {', '.join(bad)}; expected {' or '.join(allowed)}")
        declared = sum(int(getattr(c, "msgcount", 0) or 0) for c in conns)
        if max_messages is not None and declared > max_messages:
            raise _too_many(bag, topic, declared, max_messages)
        try:
            stream = reader.messages(connections=conns)
            for k, (conn, t_ns, raw) in enumerate(stream):
                if max_messages is not None and k >= max_messages:
                    raise _too_many(bag, topic, k + 1, max_messages, declared=False)
                if max_message_bytes is not None and len(raw) > max_message_bytes:
                    raise ResourceLimitError(
                        f"{bag}: topic {topic!r}, message {k}: {len(raw)} bytes, more than the "
                        f"{max_message_bytes} bytes allowed for one message",
                        needed=len(raw),
                        limit=max_message_bytes,
                        unit="bytes",
                    )
                try:
                    msg = rb.store.deserialize_cdr(raw, conn.msgtype)
                except Exception as exc:  # noqa: BLE001 (any decoding failure of rosbags' serde)
                    raise BagError(
                        f"{bag}: topic {topic!r}, message {k}: cannot decode {conn.msgtype}: {one_line(exc)}"
                    ) from None
                yield k, int(t_ns), msg, conn.msgtype
        except (BagError, ResourceLimitError):
            raise
        except Exception as exc:  # noqa: BLE001 (storage errors of sqlite3 / MCAP while reading)
            raise BagError(f"{bag}: topic {topic!r}: cannot read the messages: {one_line(exc)}") from None
    finally:
        reader.close()


def _too_many(bag, topic: str, count: int, limit: int, declared: bool = True) -> ResourceLimitError:
    has = f"declares {count} messages" if declared else f"has more than {limit} messages"
    return ResourceLimitError(
        f"{bag}: topic {topic!r} {has}, more than the {limit} that may be held in memory",
        needed=count,
        limit=limit,
        unit="messages",
    )


@dataclass(frozen=True)
class JointStates:
    """Wheel readings of a JointState topic.

    ``stamps`` ``(N,)`` int64 [ns] (header or bag time, see ``stamp_source``); ``bag_times``
    ``(N,)`` int64 [ns] the record times; ``t`` ``(N,)`` [s] since the first sample;
    ``angles`` ``(N, n_enc)`` [rad] of ``wheel_names``; ``steer`` ``(N, n_steer)`` [rad] or None;
    ``skipped`` messages without any of the wheels; ``duplicates`` exact repeats dropped.
    """

    bag: str
    topic: str
    stamps: np.ndarray
    bag_times: np.ndarray
    angles: np.ndarray
    steer: np.ndarray | None
    wheel_names: list
    steer_names: list
    stamp_source: str
    skipped: int = 0
    duplicates: int = 0

    @property
    def t(self) -> np.ndarray:
        return (self.stamps - self.stamps[0]).astype(float) * 1e-9


def _encoded_names(robot: Robot) -> list[str]:
    from ..odometry.batch import encoded_wheels

    return [w.name for w in encoded_wheels(robot)]


def read_joint_states(
    bag,
    robot: Robot,
    topic: str = "/joint_states",
    *,
    stamp: str = "auto",
    steer_suffix: str = STEER_SUFFIX,
    max_messages: int | None = None,
    max_message_bytes: int | None = None,
) -> JointStates:
    """Wheel angles (and steering angles) of ``robot`` from a JointState topic (module docstring)."""
    if stamp not in STAMPS:
        raise BagError(f"stamp must be one of {list(STAMPS)}, got {stamp!r}")
    wheels = _encoded_names(robot)
    steer_joints = [f"{n}{steer_suffix}" for n in robot.steer_names]
    needed = wheels + steer_joints
    header_list: list[int] = []
    bag_list: list[int] = []
    rows: list[np.ndarray] = []
    index_list: list[int] = []
    skipped = 0
    seen_names: set[str] = set()
    for k, t_ns, msg, _ in _messages(bag, topic, (JOINT_STATE,), max_messages, max_message_bytes):
        names = list(msg.name)
        pos = np.asarray(msg.position, dtype=float)
        seen_names.update(names)
        if len(pos) != len(names):
            raise BagError(f"{bag}: topic {topic!r}, message {k}: {len(names)} joint names but {len(pos)} positions")
        index = {}
        for i, n in enumerate(names):
            if n in index:
                raise BagError(f"{bag}: topic {topic!r}, message {k}: joint {shorten(n)} appears twice")
            index[n] = i
        present = [n for n in needed if n in index]
        if not present:
            skipped += 1
            continue
        missing = [n for n in needed if n not in index]
        if missing:
            raise BagError(
                f"{bag}: topic {topic!r}, message {k}: no joint(s) {missing} (robot {robot.name!r} "
                f"needs {needed}); the message has {shorten(names, 200)}"
            )
        row = pos[[index[n] for n in needed]]
        bad = [n for n, v in zip(needed, row, strict=True) if not math.isfinite(v)]
        if bad:
            raise BagError(f"{bag}: topic {topic!r}, message {k}: non-finite position of joint(s) {bad}")
        header_list.append(_stamp_ns(msg.header.stamp))
        bag_list.append(t_ns)
        rows.append(row)
        index_list.append(k)
    if not rows:
        raise BagError(
            f"{bag}: topic {topic!r}: no JointState message names the wheel joints {needed} of robot "
            f"{robot.name!r} (joint name = wheel name); the topic's joints are "
            f"{shorten(sorted(seen_names), 300) if seen_names else 'none (no messages)'}"
        )
    header_ns = np.array(header_list, dtype=np.int64)
    bag_ns = np.array(bag_list, dtype=np.int64)
    source = stamp
    if stamp == "auto":
        source = "bag" if not np.any(header_ns) else "header"
    stamps = header_ns if source == "header" else bag_ns
    data = np.array(rows)
    repeat = np.zeros(len(data), dtype=bool)
    repeat[1:] = (stamps[1:] == stamps[:-1]) & np.all(data[1:] == data[:-1], axis=1)
    keep = ~repeat
    data, stamps, bag_ns, msg_index = data[keep], stamps[keep], bag_ns[keep], np.array(index_list)[keep]
    back = np.flatnonzero(np.diff(stamps) <= 0)
    if back.size:
        i = int(back[0]) + 1
        what = "header stamps" if source == "header" else "bag record times"
        hint = (
            "; all header stamps are zero: use --stamp bag (record times)"
            if source == "header" and not np.any(header_ns)
            else "; --stamp bag uses the record times instead"
            if source == "header"
            else ""
        )
        raise BagError(
            f"{bag}: topic {topic!r}, message {int(msg_index[i])}: {what} must increase strictly: "
            f"{int(stamps[i])} ns follows {int(stamps[i - 1])} ns of message {int(msg_index[i - 1])}"
            f"{hint}"
        )
    if len(data) < 2:
        raise BagError(f"{bag}: topic {topic!r}: odometry needs at least two distinct wheel samples, got {len(data)}")
    n = len(wheels)
    steer = data[:, n:] if steer_joints else None
    return JointStates(
        str(bag), topic, stamps, bag_ns, data[:, :n], steer, wheels, steer_joints, source, skipped, int(repeat.sum())
    )


@dataclass(frozen=True)
class PoseTrack:
    """Planar poses of an Odometry or PoseStamped topic: ``stamps`` int64 [ns], ``poses`` ``(N, 3)``."""

    bag: str
    topic: str
    msgtype: str
    stamps: np.ndarray
    bag_times: np.ndarray
    poses: np.ndarray
    frame_id: str
    child_frame_id: str = ""
    twists: np.ndarray | None = None

    @property
    def t(self) -> np.ndarray:
        """Header times [s] (absolute, as floats)."""
        return self.stamps.astype(float) * 1e-9


def yaw_of(q) -> float:
    """Yaw [rad] of a quaternion message (any norm)."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z)


def read_poses(bag, topic: str, *, max_messages: int | None = None, max_message_bytes: int | None = None) -> PoseTrack:
    """Planar poses ``(x, y, yaw)`` of a ``nav_msgs/Odometry`` or ``geometry_msgs/PoseStamped`` topic."""
    stamps, bag_ns, poses, twists = [], [], [], []
    frame = child = ""
    msgtype = ""
    for k, t_ns, msg, mtype in _messages(bag, topic, POSE_TYPES, max_messages, max_message_bytes):
        msgtype = mtype
        pose = msg.pose.pose if mtype == ODOMETRY else msg.pose
        q = pose.orientation
        if q.x == q.y == q.z == q.w == 0.0:
            raise BagError(f"{bag}: topic {topic!r}, message {k}: zero orientation quaternion")
        p = (pose.position.x, pose.position.y, yaw_of(q))
        if not all(math.isfinite(v) for v in p):
            raise BagError(f"{bag}: topic {topic!r}, message {k}: non-finite pose {p}")
        stamps.append(_stamp_ns(msg.header.stamp))
        bag_ns.append(t_ns)
        poses.append(p)
        frame = msg.header.frame_id
        if mtype == ODOMETRY:
            child = msg.child_frame_id
            tw = msg.twist.twist
            twists.append((tw.linear.x, tw.linear.y, tw.angular.z))
    if not poses:
        raise BagError(f"{bag}: topic {topic!r}: no messages")
    return PoseTrack(
        str(bag),
        topic,
        msgtype,
        np.array(stamps, dtype=np.int64),
        np.array(bag_ns, dtype=np.int64),
        np.array(poses),
        frame,
        child,
        np.array(twists) if twists else None,
    )


def export_poses(
    bag,
    topic: str,
    fmt: str,
    output=None,
    *,
    force: bool = False,
    max_messages: int | None = None,
    max_message_bytes: int | None = None,
) -> PoseTrack:
    """Write the poses of ``topic`` as a ``tum``, ``kitti`` or ``csv`` file (``output`` None or
    ``-``: stdout) under the output policy (an existing file needs ``force``; never the bag).

    Timestamps are the header stamps, written exactly in seconds with nanoseconds.
    """
    from .trajectories import FORMATS, write_trajectory

    if fmt not in FORMATS:
        raise BagError(f"unknown export format {fmt!r}; one of {list(FORMATS)}")
    output = "-" if output is None else output
    check_output(output, inputs=[bag], force=force)
    track = read_poses(bag, topic, max_messages=max_messages, max_message_bytes=max_message_bytes)
    write_trajectory(output, track.stamps, track.poses, fmt, force=force, inputs=[bag])
    return track


# --- writing -------------------------------------------------------------------------------------------
def _covariance(value, name: str) -> np.ndarray:
    if value is None:
        return np.zeros(36)
    c = np.asarray(value, dtype=float).ravel()
    if c.size == 6:
        c = np.diag(c).ravel()
    if c.size != 36 or not np.all(np.isfinite(c)):
        raise BagError(f"{name}: expected 6 (diagonal) or 36 finite numbers, got {np.asarray(value).size}")
    return c


def _odometry_msg(rb: _Rosbags, ns: int, pose, twist, frame_id, child_frame_id, pose_cov, twist_cov):
    T = rb.types
    half = 0.5 * float(pose[2])
    header = T["std_msgs/msg/Header"](stamp=_time_msg(rb, ns), frame_id=frame_id)
    p = T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=float(pose[0]), y=float(pose[1]), z=0.0),
        orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)),
    )
    tw = T["geometry_msgs/msg/Twist"](
        linear=T["geometry_msgs/msg/Vector3"](x=float(twist[0]), y=float(twist[1]), z=0.0),
        angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=float(twist[2])),
    )
    return T[ODOMETRY](
        header=header,
        child_frame_id=child_frame_id,
        pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=p, covariance=pose_cov),
        twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=tw, covariance=twist_cov),
    )


def _twist_msg(rb: _Rosbags, twist):
    T = rb.types
    return T[TWIST](
        linear=T["geometry_msgs/msg/Vector3"](x=float(twist[0]), y=float(twist[1]), z=0.0),
        angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=float(twist[2])),
    )


def _joint_state_msg(rb: _Rosbags, ns: int, names, position, velocity):
    T = rb.types
    header = T["std_msgs/msg/Header"](stamp=_time_msg(rb, ns), frame_id="")
    return T[JOINT_STATE](
        header=header,
        name=list(names),
        position=np.asarray(position, dtype=np.float64),
        velocity=np.asarray(velocity, dtype=np.float64),
        effort=np.zeros(0),
    )


@dataclass(frozen=True)
class _Topic:
    name: str
    msgtype: str
    latched: bool = False  # offered as transient local (kept for late subscribers: /tf_static)


def _latched_qos() -> list:
    """The QoS a latched topic is offered with (``/tf_static``'s: reliable, transient local,
    the last message kept), as ``ros2 bag play`` replays it."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    never = QosTime(sec=0, nsec=0)
    return [
        Qos(
            QosHistory.KEEP_LAST,
            1,
            QosReliability.RELIABLE,
            QosDurability.TRANSIENT_LOCAL,
            never,
            never,
            QosLiveliness.AUTOMATIC,
            never,
            False,
        )
    ]


def _serialize(rb: _Rosbags, msg, msgtype: str) -> bytes:
    return bytes(rb.store.serialize_cdr(msg, msgtype))


def require_new_bag(path, *, inputs: Iterable = (), force: bool = False) -> Path:
    """``path`` as a :class:`Path` if a bag may be written there.

    The output policy of :mod:`omnikin.io.output` for a data folder: a new path, or with
    ``force`` a bag omnikin wrote (replaced as a whole); never an input bag, nor inside one.
    Called before any long work (reading, simulating) so that a taken name fails at once.
    Raises :class:`omnikin.errors.OutputExistsError` (or the other errors of
    :func:`omnikin.io.output.check_output`)."""
    out = check_output(path, inputs=inputs, force=force, folder="data")
    if out is None:  # '-' is refused for folders by check_output
        raise BagError("a bag is a folder: name it (standard output cannot take a bag)")
    return out


def _write_bag(
    path,
    topics: list[_Topic],
    messages: Iterable[tuple[int, int, bytes]],
    storage: str = "sqlite3",
    custom: dict | None = None,
    *,
    force: bool = False,
    inputs: Iterable = (),
) -> int:
    """Write a new bag with ``topics`` from ``messages`` ``(topic index, bag time [ns], serialized
    bytes)`` in time order, one at a time; returns the number written. The bag is built beside
    ``path`` and moved there when complete (:func:`omnikin.io.output.data_folder`)."""
    rb = _Rosbags.get()
    if storage not in STORAGES:
        raise BagError(f"{path}: unknown bag storage {storage!r}; one of {list(STORAGES)}")
    require_new_bag(path, inputs=inputs, force=force)
    import inspect

    params = inspect.signature(rb.Writer).parameters
    kwargs: dict[str, Any] = {}
    if "version" in params:
        kwargs["version"] = 8
    if storage != "sqlite3":
        try:
            from rosbags.rosbag2 import StoragePlugin
        except ImportError:
            raise BagError(f"{path}: writing MCAP needs a newer rosbags (>= 0.11): pip install -U rosbags") from None
        kwargs["storage_plugin"] = StoragePlugin.MCAP
    count = 0
    with data_folder(path) as stage:
        try:
            with rb.Writer(stage, **kwargs) as writer:
                conns = [
                    writer.add_connection(t.name, t.msgtype, typestore=rb.store, offered_qos_profiles=_latched_qos())
                    if t.latched
                    else writer.add_connection(t.name, t.msgtype, typestore=rb.store)
                    for t in topics
                ]
                for key, value in (custom or {}).items():
                    if hasattr(writer, "set_custom_data"):
                        writer.set_custom_data(str(key), str(value))
                for j, t_ns, raw in messages:
                    writer.write(conns[j], int(t_ns), raw)
                    count += 1
        except (OmnikinError, OSError, KeyboardInterrupt):
            raise
        except Exception as exc:  # noqa: BLE001 (rosbags WriterError, serde errors)
            raise BagError(f"{path}: cannot write the bag: {one_line(exc)}") from None
    return count


def odometry_messages(
    stamps,
    poses,
    twists,
    *,
    bag_times=None,
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    pose_covariance=None,
    twist_covariance=None,
    topic: int = 0,
) -> Iterator[tuple[int, int, bytes]]:
    """Serialized ``nav_msgs/Odometry`` messages ``(topic, bag time ns, bytes)``, made one at a
    time in the order given."""
    rb = _Rosbags.get()
    pc = _covariance(pose_covariance, "pose covariance")
    tc = _covariance(twist_covariance, "twist covariance")
    stamps = np.asarray(stamps, dtype=np.int64)
    bag_times = stamps if bag_times is None else np.asarray(bag_times, dtype=np.int64)
    poses, twists = np.asarray(poses), np.asarray(twists)
    for k in range(len(stamps)):
        msg = _odometry_msg(rb, int(stamps[k]), poses[k], twists[k], frame_id, child_frame_id, pc, tc)
        yield topic, int(bag_times[k]), _serialize(rb, msg, ODOMETRY)


def write_odometry(
    path,
    stamps,
    poses,
    twists,
    *,
    topic: str = "/odom",
    bag_times=None,
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    pose_covariance=None,
    twist_covariance=None,
    storage: str = "sqlite3",
    force: bool = False,
    inputs: Iterable = (),
) -> None:
    """Write poses ``(N, 3)`` and body twists ``(N, 3)`` at ``stamps`` [int ns] as Odometry to a new bag
    (messages in order of bag time)."""
    check_frame_ids(frame_id, child_frame_id)
    stamps = np.asarray(stamps, dtype=np.int64)
    bag_times = stamps if bag_times is None else np.asarray(bag_times, dtype=np.int64)
    order = np.argsort(bag_times, kind="stable")
    msgs = odometry_messages(
        stamps[order],
        np.asarray(poses)[order],
        np.asarray(twists)[order],
        bag_times=bag_times[order],
        frame_id=frame_id,
        child_frame_id=child_frame_id,
        pose_covariance=pose_covariance,
        twist_covariance=twist_covariance,
    )
    _write_bag(path, [_Topic(topic, ODOMETRY)], msgs, storage, force=force, inputs=inputs)


def interval_twists(t, poses) -> np.ndarray:
    """Per sample the constant body twist of the interval that ends there (zero at the first):
    ``log(P_{k-1}^-1 P_k) / (t_k - t_{k-1})``, ``(N, 3)``."""
    p = np.asarray(poses, dtype=float)
    out = np.zeros_like(p)
    if len(p) > 1:
        out[1:] = log(between(p[:-1], p[1:])) / np.diff(np.asarray(t, dtype=float))[:, None]
    return out


# --- bag odometry --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BagOdometry:
    """Result of :func:`bag_odometry`: the input readings and the odometry written."""

    joint_states: JointStates
    poses: np.ndarray
    twists: np.ndarray
    output: str
    topic: str

    def summary(self) -> dict:
        js = self.joint_states
        end = self.poses[-1]
        path = float(np.sum(np.hypot(*np.diff(self.poses[:, :2], axis=0).T)))
        return {
            "input": js.bag,
            "joint_states_topic": js.topic,
            "samples": len(js.stamps),
            "duration": float(js.t[-1]),
            "stamp_source": js.stamp_source,
            "wheels": js.wheel_names,
            "steer_joints": js.steer_names,
            "skipped_messages": js.skipped,
            "duplicates_dropped": js.duplicates,
            "output": self.output,
            "odom_topic": self.topic,
            "final_pose": end.tolist(),
            "path_length": path,
        }


def bag_odometry(
    robot: Robot,
    bag_in,
    bag_out,
    *,
    joint_states_topic: str = "/joint_states",
    odom_topic: str = "/odom",
    method: str = "exact",
    max_wheel_speed: float | None = None,
    max_wheel_accel: float | None = None,
    stamp: str = "auto",
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    pose_covariance=None,
    twist_covariance=None,
    storage: str = "sqlite3",
    steer_suffix: str = STEER_SUFFIX,
    force: bool = False,
    max_messages: int | None = None,
    max_message_bytes: int | None = None,
) -> BagOdometry:
    """Wheel odometry of the JointState topic of ``bag_in`` written as Odometry to the new bag ``bag_out``.

    Each output message has the stamp and the bag record time of the input sample it comes
    from; the pose starts at the origin at the first sample. ``max_wheel_speed`` [rad/s] and
    ``max_wheel_accel`` [rad/s^2]: the speed and change-of-speed rules of the wheel angles
    (:func:`omnikin.odometry.batch.batch_odometry_from_angles`; checked before the bag is read).
    """
    from ..odometry.batch import batch_odometry_from_angles
    from ..odometry.plausibility import check_max_wheel_accel, check_max_wheel_speed

    check_max_wheel_speed(max_wheel_speed)
    check_max_wheel_accel(max_wheel_accel)
    check_frame_ids(frame_id, child_frame_id)
    require_new_bag(bag_out, inputs=[bag_in], force=force)
    js = read_joint_states(
        bag_in,
        robot,
        joint_states_topic,
        stamp=stamp,
        steer_suffix=steer_suffix,
        max_messages=max_messages,
        max_message_bytes=max_message_bytes,
    )
    try:
        res = batch_odometry_from_angles(
            robot,
            js.t,
            js.angles,
            steer=js.steer,
            method=method,
            max_wheel_speed=max_wheel_speed,
            max_wheel_accel=max_wheel_accel,
        )
    except OmnikinError as exc:
        raise BagError(f"{bag_in}: topic {joint_states_topic!r}: {exc}") from None
    twists = np.zeros_like(res.poses)
    twists[1:] = res.twists
    _covariance(pose_covariance, "pose covariance")  # refused before the bag is started
    _covariance(twist_covariance, "twist covariance")
    order = np.argsort(js.bag_times, kind="stable")
    msgs = odometry_messages(
        js.stamps[order],
        res.poses[order],
        twists[order],
        bag_times=js.bag_times[order],
        frame_id=frame_id,
        child_frame_id=child_frame_id,
        pose_covariance=pose_covariance,
        twist_covariance=twist_covariance,
    )
    _write_bag(
        bag_out,
        [_Topic(odom_topic, ODOMETRY)],
        msgs,
        storage,
        {"omnikin.robot": robot.name, "omnikin.method": method, "omnikin.input": str(bag_in)},
        force=force,
        inputs=[bag_in],
    )
    return BagOdometry(js, res.poses, twists, str(bag_out), odom_topic)


# --- simulated runs ------------------------------------------------------------------------------------
RUN_TOPICS = {"ground_truth": "/ground_truth", "odom": "/odom", "joint_states": "/joint_states", "cmd_vel": "/cmd_vel"}


def record_run(path, run, robot: Robot, **options) -> dict:
    """Write a simulated run (:class:`omnikin.simulation.kinematic.SimulatedRun`, first trial) to a
    new bag (:func:`record_samples`, whose keyword ``options`` it takes: ``start``, ``topics``,
    frames, ``storage``, ``custom``, ``force``): its encoders' counts times ``robot``'s angle per
    tick, and on ``/cmd_vel`` the body twist of each interval of its plan. Returns ``{topic:
    message count}``.
    """
    t = np.asarray(run.t, dtype=float)
    truth = np.asarray(run.truth)[0]
    if truth.shape[0] != len(t):
        raise BagError("record_run needs the full ground truth (simulate with keep_truth=True)")
    angles = np.asarray(run.ticks, dtype=float) * robot.rad_per_tick(_encoded_names(robot))
    command = np.zeros((len(t), 3))
    command[:-1] = run.sampled.increments / np.diff(t)[:, None]
    return record_samples(
        path,
        robot,
        t,
        truth=truth,
        odometry=run.odometry,
        wheel_angles=angles,
        steer=run.steer,
        command=command,
        rate=run.sampled.rate,
        sensing=getattr(run, "sensing", None),
        **options,
    )


def record_samples(
    path,
    robot: Robot,
    t,
    *,
    truth,
    odometry,
    wheel_angles,
    steer,
    command,
    rate: float,
    start: float = 0.0,
    topics: dict | None = None,
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    storage: str = "sqlite3",
    custom: dict | None = None,
    steer_suffix: str = STEER_SUFFIX,
    force: bool = False,
    sensing: Readings | None = None,
) -> dict:
    """Write a run sampled at the times ``t`` ``(n,)`` [s] (``rate`` [Hz] apart) to a new bag.

    Topics (``topics`` renames them): ``/ground_truth`` (Odometry, the true poses ``truth``
    ``(n, 3)``), ``/odom`` (Odometry, the robot's ``odometry`` ``(n, 3)``), ``/joint_states``
    (JointState: the encoded wheels' angles ``wheel_angles`` ``(n, n_encoded)`` [rad] of
    ``robot``, in ``robot.encoded_names`` order, and their mean speeds over the interval ending at
    the sample [rad/s]; the steering angles ``steer`` ``(n, n_steer)`` [rad] or None as joints
    ``W_steer``) and ``/cmd_vel`` (Twist: the body twist ``command`` ``(n, 3)`` [m/s, m/s,
    rad/s] held from the sample). Sample k is stamped ``start + t_k`` [s]. ``robot`` is the
    commanding (nominal) robot whose odometry ``odometry`` is, so reading the bag's joint states
    back with it reproduces ``/odom``. Messages are made and written one sample at a time.
    ``sensing``: the readings of the robot's IMUs and lidars (:mod:`omnikin.sensors.readings`),
    which add ``/imu``, ``/scan``, ``/tf`` and ``/tf_static`` (:mod:`omnikin.io.bag_sensors`).
    Returns ``{topic: message count}``.
    """
    rb = _Rosbags.get()
    names = dict(RUN_TOPICS, **(topics or {}))
    unknown = sorted(set(names) - set(RUN_TOPICS))
    if unknown:
        raise BagError(f"unknown run topic key(s) {unknown}; keys are {sorted(RUN_TOPICS)}")
    check_frame_ids(frame_id, child_frame_id)
    t = np.asarray(t, dtype=float)
    start = check_start_time(start, float(t[-1]), rate, "start", output="a ROS 2 bag", span=ROS_TIME_SPAN, step=1 / NS)
    stamps = seconds_to_ns(t) + round(start * 1e9)
    truth = np.asarray(truth, dtype=float)
    odometry = np.asarray(odometry, dtype=float)
    cmd = np.asarray(command, dtype=float)
    angles = np.asarray(wheel_angles, dtype=float)
    joint_names = list(_encoded_names(robot))
    if steer is not None:
        angles = np.concatenate([angles, np.asarray(steer, dtype=float)], axis=1)
        joint_names += [f"{n}{steer_suffix}" for n in robot.steer_names]
    for what, value, columns in (
        ("truth", truth, 3),
        ("odometry", odometry, 3),
        ("command", cmd, 3),
        ("wheel angles", angles, len(joint_names)),
    ):
        if value.shape != (len(t), columns):
            raise BagError(f"record_samples: {what} must have shape ({len(t)}, {columns}), got {value.shape}")
    speeds = np.zeros_like(angles)
    speeds[1:] = np.diff(angles, axis=0) / np.diff(t)[:, None]
    truth_twist = interval_twists(t, truth)
    odom_twist = interval_twists(t, odometry)
    zero = np.zeros(36)

    def messages() -> Iterator[tuple[int, int, bytes]]:
        for k, ns in enumerate(stamps.tolist()):
            yield (
                0,
                ns,
                _serialize(
                    rb, _odometry_msg(rb, ns, truth[k], truth_twist[k], frame_id, child_frame_id, zero, zero), ODOMETRY
                ),
            )
            yield (
                1,
                ns,
                _serialize(
                    rb,
                    _odometry_msg(rb, ns, odometry[k], odom_twist[k], frame_id, child_frame_id, zero, zero),
                    ODOMETRY,
                ),
            )
            yield 2, ns, _serialize(rb, _joint_state_msg(rb, ns, joint_names, angles[k], speeds[k]), JOINT_STATE)
            yield 3, ns, _serialize(rb, _twist_msg(rb, cmd[k]), TWIST)

    types = {"ground_truth": ODOMETRY, "odom": ODOMETRY, "joint_states": JOINT_STATE, "cmd_vel": TWIST}
    keys = list(RUN_TOPICS)  # the topic indices used by messages()
    written = [_Topic(names[k], types[k]) for k in keys]
    counts = {names[k]: len(t) for k in keys}
    stream: Iterable[tuple[int, int, bytes]] = messages()
    if sensing is not None and not sensing.empty:
        from .bag_sensors import sensor_messages, sensor_topics

        extra = sensor_topics(sensing)
        first = len(written)
        written += [_Topic(name, msgtype, latched=name == "/tf_static") for name, msgtype in extra]
        streams = sensor_messages(rb, sensing, stamps, odometry, round(start * 1e9), frame_id, child_frame_id)
        shifted = [((first + j, ns, raw) for j, ns, raw in s) for s in streams]
        stream = heapq.merge(stream, *shifted, key=lambda m: m[1])
        counts["/tf"] = len(t)
        counts["/tf_static"] = 1
        for (name, _), size in zip(
            extra[2:], [len(r.t) for r in sensing.imus] + [len(r.t) for r in sensing.scans], strict=True
        ):
            counts[name] = size
    _write_bag(path, written, stream, storage, custom, force=force)
    return counts
