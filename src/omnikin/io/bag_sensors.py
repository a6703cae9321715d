"""The sensors of a run in a ROS 2 bag (``docs/sensors.md``, "In a bag"): what
:func:`omnikin.io.bags.record_samples` adds when the run kept its sensors' readings.

- ``/imu`` (``sensor_msgs/Imu``; ``/imu/NAME`` when the robot has several IMUs): angular velocity
  [rad/s] and linear acceleration [m/s^2] in the IMU's frame ``NAME``;
- ``/scan`` (``sensor_msgs/LaserScan``; ``/scan/NAME`` for several lidars) in the lidar's frame,
  the ranges as REP 117 has them;
- their other fields (covariances, beam angles, ...) as :mod:`omnikin.sensors.message_content`
  gives them;
- ``/tf`` (``tf2_msgs/TFMessage``): ``odom -> base_link`` at every sample, from the odometry (what
  a SLAM or Nav2 stack reads);
- ``/tf_static``: ``base_link -> NAME`` for every IMU and lidar, at the first stamp.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from ..sensors.message_content import imu_fields, scan_fields, sensor_topic
from ..sensors.readings import Readings

IMU = "sensor_msgs/msg/Imu"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"


def _quaternion(T, yaw: float):
    return T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def _transform(T, time, parent: str, child: str, x: float, y: float, z: float, yaw: float):
    return T["geometry_msgs/msg/TransformStamped"](
        header=T["std_msgs/msg/Header"](stamp=time, frame_id=parent),
        child_frame_id=child,
        transform=T["geometry_msgs/msg/Transform"](
            translation=T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z)),
            rotation=_quaternion(T, float(yaw)),
        ),
    )


def _vector(T, v):
    return T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))


def sensor_topics(sensing: Readings) -> list[tuple[str, str]]:
    """``(topic, message type)`` of the sensor topics of ``sensing``, in the order of
    :func:`sensor_messages`' topic indices."""
    topics = [("/tf", TF_MESSAGE), ("/tf_static", TF_MESSAGE)]
    several = len(sensing.imus) > 1
    topics += [("/" + sensor_topic("imu", r.sensor.name, several), IMU) for r in sensing.imus]
    several = len(sensing.scans) > 1
    topics += [("/" + sensor_topic("scan", r.sensor.name, several), LASER_SCAN) for r in sensing.scans]
    return topics


def sensor_messages(
    rb, sensing: Readings, stamps: np.ndarray, odometry: np.ndarray, offset_ns: int, frame_id: str, child_frame_id: str
) -> list[Iterator[tuple[int, int, bytes]]]:
    """One time-ordered stream of ``(topic index, stamp [ns], serialized message)`` per topic
    of :func:`sensor_topics` (indices from 0 in that order): ``stamps`` ``(n,)`` [ns] and
    ``odometry`` ``(n, 3)`` of the run's samples, the sensors' times shifted by ``offset_ns``."""
    T = rb.types

    def serialize(msg, msgtype: str) -> bytes:
        return bytes(rb.store.serialize_cdr(msg, msgtype))

    def time(ns: int):
        sec, nsec = divmod(int(ns), 1_000_000_000)
        return T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)

    def tf() -> Iterator[tuple[int, int, bytes]]:
        for ns, (x, y, theta) in zip(stamps.tolist(), odometry, strict=True):
            msg = T[TF_MESSAGE](transforms=[_transform(T, time(ns), frame_id, child_frame_id, x, y, 0.0, theta)])
            yield 0, ns, serialize(msg, TF_MESSAGE)

    def tf_static() -> Iterator[tuple[int, int, bytes]]:
        ns = int(stamps[0])
        mounts = [r.sensor for r in sensing.imus] + [r.sensor for r in sensing.scans]
        transforms = [
            _transform(T, time(ns), child_frame_id, s.name, s.mount.x, s.mount.y, s.mount.z, s.mount.yaw)
            for s in mounts
        ]
        yield 1, ns, serialize(T[TF_MESSAGE](transforms=transforms), TF_MESSAGE)

    def imu(index: int, record) -> Iterator[tuple[int, int, bytes]]:
        sensor = record.sensor
        fields = imu_fields(sensor)
        x, y, z, w = fields["orientation"]
        covariances = {k: np.array(fields[k]) for k in fields if k.endswith("covariance")}
        for t, gyro, accel in zip(record.t, record.gyro, record.accel, strict=True):
            ns = int(round(float(t) * 1e9)) + offset_ns
            msg = T[IMU](
                header=T["std_msgs/msg/Header"](stamp=time(ns), frame_id=sensor.name),
                orientation=T["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
                angular_velocity=_vector(T, gyro),
                linear_acceleration=_vector(T, accel),
                **covariances,
            )
            yield index, ns, serialize(msg, IMU)

    def scan(index: int, record) -> Iterator[tuple[int, int, bytes]]:
        lidar = record.sensor
        fields = scan_fields(lidar)
        for t, ranges in zip(record.t, record.ranges, strict=True):
            ns = int(round(float(t) * 1e9)) + offset_ns
            msg = T[LASER_SCAN](
                header=T["std_msgs/msg/Header"](stamp=time(ns), frame_id=lidar.name),
                **fields,
                ranges=np.asarray(ranges, dtype=np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
            yield index, ns, serialize(msg, LASER_SCAN)

    streams = [tf(), tf_static()]
    streams += [imu(2 + i, r) for i, r in enumerate(sensing.imus)]
    streams += [scan(2 + len(sensing.imus) + i, r) for i, r in enumerate(sensing.scans)]
    return streams
