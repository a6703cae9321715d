"""Plain files of what a robot's sensors read (``docs/sensors.md``, "Files"): the IMU log (CSV)
and the scan log (NumPy ``.npz``), written atomically under the one output policy
(:mod:`omnikin.io.output`).

IMU log: ``#`` comment lines (what wrote it), then the header
``sensor,t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z`` and one row per reading: the IMU's
name, the time [s], the mean angular rate [rad/s] and the mean specific force [m/s^2] over the
interval before it, in the IMU's own frame (17 significant digits: read back exactly).

Scan log: an ``.npz`` archive with, for each lidar ``NAME``, the arrays ``NAME.t`` ``(m,)`` [s]
and ``NAME.ranges`` ``(m, beams)`` [m] (float32, REP 117's ``+inf``, ``-inf`` and ``nan`` kept),
and the scalars ``NAME.angle_min``, ``NAME.angle_increment`` [rad], ``NAME.range_min``,
``NAME.range_max`` [m] (float32, as the ranges: every finite range lies within them) and
``NAME.mount`` ``(x, y, z, yaw)`` [m, rad]: what
``sensor_msgs/LaserScan`` carries; ``numpy.load`` reads it with ``allow_pickle=False``.
"""

from __future__ import annotations

import io

import numpy as np

from ..sensors.readings import ImuReadings, ScanReadings
from .output import atomic_write, write_text

IMU_HEADER = "sensor,t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
"""The header row of an IMU log."""


def imu_log_text(imus: tuple[ImuReadings, ...], comment: str = "", start: float = 0.0) -> str:
    """The IMU log of ``imus`` (module docstring), times shifted by ``start`` [s]."""
    lines = [f"# {line}" for line in comment.splitlines()] + [IMU_HEADER]
    for record in imus:
        table = np.column_stack([record.t + start, record.gyro, record.accel])
        lines.extend(f"{record.sensor.name}," + ",".join(f"{v:.17g}" for v in row) for row in table)
    return "\n".join(lines) + "\n"


def write_imu_log(path, imus: tuple[ImuReadings, ...], comment: str = "", start: float = 0.0) -> None:
    """Write the IMU log of ``imus`` to ``path`` (``-``: standard output)."""
    write_text(path, imu_log_text(imus, comment, start))


def write_scan_log(path, scans: tuple[ScanReadings, ...], start: float = 0.0) -> None:
    """Write the scan log of ``scans`` to the file ``path`` (module docstring; a binary archive,
    never standard output), times shifted by ``start`` [s]."""
    arrays: dict[str, np.ndarray] = {}
    for record in scans:
        lidar, name = record.sensor, record.sensor.name
        m = lidar.mount
        arrays[f"{name}.t"] = record.t + start
        arrays[f"{name}.ranges"] = record.ranges.astype(np.float32)
        arrays[f"{name}.angle_min"] = np.float64(lidar.angle_min)
        arrays[f"{name}.angle_increment"] = np.float64(lidar.angle_increment)
        # float32 like the ranges (and LaserScan): rounding keeps every range within its limits
        arrays[f"{name}.range_min"] = np.float32(lidar.range_min)
        arrays[f"{name}.range_max"] = np.float32(lidar.range_max)
        arrays[f"{name}.mount"] = np.array([m.x, m.y, m.z, m.yaw])
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)  # type: ignore[arg-type]  # (NumPy's stub types allow_pickle alone)
    with atomic_write(path, "wb") as handle:
        handle.write(buffer.getvalue())
