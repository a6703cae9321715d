"""What ``sensor_msgs/Imu`` and ``sensor_msgs/LaserScan`` messages of a robot's sensors carry
besides their readings, as plain values: one place for the bag writer
(:mod:`omnikin.io.bag_sensors`) and the ROS node (:mod:`omnikin.ros.node`).

- Imu: orientation unknown (``orientation_covariance[0] = -1``, REP 145; the identity
  quaternion), the angular velocity's and linear acceleration's covariances the white noise's
  variance per sample, ``noise_density^2 rate``, on the diagonal (row-major 3x3);
- LaserScan: ``angle_min``, ``angle_max`` (the last beam), ``angle_increment`` as
  :meth:`~omnikin.kinematics.sensors.Lidar.angles`, ``scan_time`` ``1 / rate``,
  ``time_increment`` ``scan_time / beams`` (a turning head), ``range_min``, ``range_max``;
- topics: ``imu`` and ``scan``, or ``imu/NAME`` and ``scan/NAME`` when the robot has several.
"""

from __future__ import annotations

from ..kinematics.sensors import Imu, Lidar


def imu_fields(imu: Imu) -> dict:
    """The constant fields of ``imu``'s messages: ``orientation`` (x, y, z, w),
    ``orientation_covariance``, ``angular_velocity_covariance`` and
    ``linear_acceleration_covariance`` (9 floats each, row-major)."""
    gyro = imu.gyro.noise_density**2 * imu.rate
    accel = imu.accel.noise_density**2 * imu.rate
    return {
        "orientation": (0.0, 0.0, 0.0, 1.0),
        "orientation_covariance": [-1.0] + [0.0] * 8,
        "angular_velocity_covariance": [gyro, 0.0, 0.0, 0.0, gyro, 0.0, 0.0, 0.0, gyro],
        "linear_acceleration_covariance": [accel, 0.0, 0.0, 0.0, accel, 0.0, 0.0, 0.0, accel],
    }


def scan_fields(lidar: Lidar) -> dict:
    """The constant fields of ``lidar``'s messages (module docstring), floats."""
    angles = lidar.angles()
    period = 1.0 / lidar.rate
    return {
        "angle_min": float(angles[0]),
        "angle_max": float(angles[-1]),
        "angle_increment": float(lidar.angle_increment),
        "time_increment": period / lidar.beams,
        "scan_time": period,
        "range_min": float(lidar.range_min),
        "range_max": float(lidar.range_max),
    }


def sensor_topic(kind: str, name: str, several: bool) -> str:
    """The topic (relative) of sensor ``name`` of ``kind`` (``imu``, ``scan``): ``kind``, or
    ``kind/name`` when the robot has several of that kind."""
    return f"{kind}/{name}" if several else kind
