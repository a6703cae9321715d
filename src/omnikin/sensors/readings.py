"""What a robot's sensors read over a run (``docs/sensors.md``, "Readings of a run").

:func:`kinematic_readings` takes a run of the kinematic engine (its times and the true poses in
the world frame, a constant twist between samples) and gives every IMU's readings at its rate
(:func:`omnikin.sensors.imu.kinematic_truth`, :func:`omnikin.sensors.imu.read`) and every
lidar's scans at its rate (:func:`omnikin.sensors.lidar.scan`, the first at the run's start).
The random errors come from one stream, drawn sensor by sensor in the robot file's order (an
IMU's whole record, then a lidar's scans in time order), so the same seed gives the same
readings bit for bit; no stream (``--noise none``) gives the exact readings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import between, compose, exp, log
from ..kinematics.sensors import Imu, Lidar
from ..world.shapes import Shapes
from .imu import ImuStream, kinematic_truth
from .lidar import measured, true_ranges

MAX_SCAN_VALUES = 50_000_000
"""Most ranges of one run's scans, all lidars together (400 MB as float64): a run that would
hold more is refused before it starts (:func:`scan_values`)."""


@dataclass(frozen=True)
class ImuReadings:
    """One IMU's record: ``t`` ``(n,)`` [s], ``gyro`` ``(n, 3)`` [rad/s] and ``accel`` ``(n, 3)``
    [m/s^2] in the sensor frame (each the mean over the interval before its time)."""

    sensor: Imu
    t: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray


@dataclass(frozen=True)
class ScanReadings:
    """One lidar's scans: ``t`` ``(m,)`` [s] and ``ranges`` ``(m, beams)`` [m] (REP 117's
    ``+inf``, ``-inf``, ``nan``: :mod:`omnikin.sensors.lidar`), beams at ``sensor.angles()``."""

    sensor: Lidar
    t: np.ndarray
    ranges: np.ndarray


@dataclass(frozen=True)
class Readings:
    """Every sensor's readings of a run, in the robot file's order within each kind."""

    imus: tuple[ImuReadings, ...] = ()
    scans: tuple[ScanReadings, ...] = ()

    @property
    def empty(self) -> bool:
        """True when the robot has no IMU and no lidar."""
        return not self.imus and not self.scans


IMU_SAMPLE_BYTES = 400.0
"""Memory [bytes] one IMU sample takes at a run's peak (measured: 143 in the kinematic engine;
the physics engine keeps the 13 floats of its interpolated chassis state besides)."""
IMU_SAMPLE_SECONDS = 2e-5
"""Computing time [s] of one IMU sample (measured: 0.55 us kinematic; the physics engine's chassis
states around it and its interpolation, about 20 us with Python's overhead)."""
RANGE_BYTES = 32.0
"""Memory [bytes] of one lidar range at a run's peak (measured 21: the true and the measured one)."""
RANGE_SECONDS = 1e-6
"""Computing time [s] of one lidar beam besides the bodies it is tested against (the physics
engine's ray casting about 0.6 us a beam)."""
RANGE_SHAPE_SECONDS = 3e-7
"""Computing time [s] of one beam against one body of the world (measured 0.24 us)."""
MAX_IMU_SAMPLES = 5_000_000
"""Most IMU samples of one run, all IMUs together (2 GB at :data:`IMU_SAMPLE_BYTES`): a run that
would hold more is refused before it starts (:func:`require_scan_room`)."""


def sensor_cost(robot: Robot, duration: float, shapes: int = 0) -> tuple[float, float]:
    """What reading ``robot``'s IMUs and lidars takes, from the measured costs per sample
    (:data:`IMU_SAMPLE_BYTES` and friends), for a run's estimate (``--max-memory``,
    ``--max-time``).

    Parameters
    ----------
    robot : Robot
        The robot as built, whose IMUs and lidars are read.
    duration : float
        Simulated time [s] of the run.
    shapes : int
        Bodies of the world (rectangles and circles) each beam is tested against.

    Returns
    -------
    tuple of float
        ``(bytes, seconds)``: memory at the run's peak and computing time.
    """
    imu = sum(math.floor(duration * s.rate + 1e-9) for s in robot.sensors if isinstance(s, Imu))
    ranges = scan_values(robot, duration)
    seconds = imu * IMU_SAMPLE_SECONDS + ranges * (RANGE_SECONDS + RANGE_SHAPE_SECONDS * max(0, int(shapes)))
    return imu * IMU_SAMPLE_BYTES + ranges * RANGE_BYTES, seconds


def scan_times(t: np.ndarray, rate: float) -> np.ndarray:
    """A lidar's scan times over the run's ``t`` [s]: ``t[0] + k / rate``, k = 0, 1, ... up to ``t[-1]``."""
    count = int(math.floor((float(t[-1]) - float(t[0])) * rate + 1e-9)) + 1
    return float(t[0]) + np.arange(count) / rate


def scan_values(robot: Robot, duration: float) -> float:
    """How many ranges the lidars of ``robot`` return over ``duration`` [s] (for the budget)."""
    return sum(math.floor(duration * s.rate + 1e-9 + 1) * s.beams for s in robot.sensors if isinstance(s, Lidar))


def require_scan_room(robot: Robot, duration: float) -> None:
    """Refuse, in one line, a run of ``duration`` [s] whose lidar scans would hold more than
    :data:`MAX_SCAN_VALUES` ranges, or whose IMUs more than :data:`MAX_IMU_SAMPLES` samples."""
    values = scan_values(robot, duration)
    if values > MAX_SCAN_VALUES:
        raise InputError(
            f"robot {robot.name!r}: its lidars would return {values:.3g} ranges over the {duration:.4g} s run, "
            f"more than the {MAX_SCAN_VALUES:.3g} a run keeps; shorten the path or lower the lidars' rate or beams"
        )
    samples = sum(math.floor(duration * s.rate + 1e-9) for s in robot.sensors if isinstance(s, Imu))
    if samples > MAX_IMU_SAMPLES:
        raise InputError(
            f"robot {robot.name!r}: its IMUs would read {samples:.3g} samples over the {duration:.4g} s run, "
            f"more than the {MAX_IMU_SAMPLES:.3g} a run keeps; shorten the path or lower the IMUs' rate"
        )


def poses_at(t: np.ndarray, poses: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``(k, 3)`` poses at ``times`` [s] of a body that moves through ``poses`` ``(N + 1, 3)`` at
    ``t`` with a constant twist between samples (exact SE(2) arcs)."""
    steps = log(between(poses[:-1], poses[1:]))
    dt = np.diff(t)
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(dt) - 1)
    return compose(poses[k], exp(steps[k] * ((times - t[k]) / dt[k])[:, None]))


@dataclass(frozen=True)
class ImuTruth:
    """What one IMU would read without errors: ``t`` ``(n,)`` [s], the mean ``rates`` ``(n, 3)``
    [rad/s] and mean specific ``forces`` ``(n, 3)`` [m/s^2] in its frame over each interval."""

    sensor: Imu
    t: np.ndarray
    rates: np.ndarray
    forces: np.ndarray


@dataclass(frozen=True)
class ScanTruth:
    """What one lidar would read without errors: ``t`` ``(m,)`` [s] and the true ``ranges``
    ``(m, beams)`` [m] (``inf`` where no body lies within ``range_max``)."""

    sensor: Lidar
    t: np.ndarray
    ranges: np.ndarray


class SensorStream:
    """The errors of ``robot``'s IMUs and lidars added to their truths chunk by chunk (a live
    robot's) or all at once (a run's): each sensor draws from ``rng`` in the robot file's order
    within a chunk, an IMU's chunk whole (:class:`~omnikin.sensors.imu.ImuStream`, its constant
    errors at its first chunk), a lidar's scans in time order
    (:func:`omnikin.sensors.lidar.measured`); ``rng`` None: exact. The one place both engines'
    readings get their errors, so a seed means the same draws in each."""

    def __init__(self, robot: Robot, rng: np.random.Generator | None):
        self.robot = robot
        self._rng = rng
        self._imus = {s.name: ImuStream(s, rng) for s in robot.sensors if isinstance(s, Imu)}

    def apply(self, truths) -> Readings:
        """The readings of ``truths`` (an :class:`ImuTruth` or :class:`ScanTruth` per sensor
        name, the next samples of each)."""
        imus, scans = [], []
        for sensor in self.robot.sensors:
            truth = truths.get(sensor.name)
            if isinstance(sensor, Imu) and isinstance(truth, ImuTruth):
                gyro, accel = self._imus[sensor.name].apply(truth.rates, truth.forces)
                imus.append(ImuReadings(sensor, truth.t, gyro, accel))
            elif isinstance(sensor, Lidar) and isinstance(truth, ScanTruth):
                ranges = np.empty((len(truth.t), sensor.beams))
                for k, row in enumerate(truth.ranges):
                    ranges[k] = measured(row, sensor, self._rng)
                scans.append(ScanReadings(sensor, truth.t, ranges))
        return Readings(tuple(imus), tuple(scans))


def measured_readings(robot: Robot, truths, rng: np.random.Generator | None) -> Readings:
    """The readings of a whole run of ``robot``'s IMUs and lidars given ``truths`` (by sensor
    name): :class:`SensorStream` in one chunk."""
    return SensorStream(robot, rng).apply(truths)


def kinematic_readings(robot: Robot, t, poses, shapes: Shapes | None, rng: np.random.Generator | None) -> Readings:
    """The readings of ``robot``'s IMUs and lidars over a kinematic run through ``poses``
    ``(N + 1, 3)`` (world frame) at times ``t`` [s] among ``shapes`` (None: an empty floor, every
    beam ``+inf``); ``rng`` the sensors' stream (None: exact). Module docstring."""
    t = np.asarray(t, dtype=float)
    poses = np.asarray(poses, dtype=float)
    truths: dict[str, ImuTruth | ScanTruth] = {}
    for sensor in robot.sensors:
        if isinstance(sensor, Imu):
            truths[sensor.name] = ImuTruth(sensor, *kinematic_truth(t, poses, sensor))
        elif isinstance(sensor, Lidar):
            times = scan_times(t, sensor.rate)
            seen = shapes if shapes is not None else Shapes.none()
            ranges = np.empty((len(times), sensor.beams))
            for k, pose in enumerate(poses_at(t, poses, times)):
                ranges[k] = true_ranges(seen, pose, sensor)[0]
            truths[sensor.name] = ScanTruth(sensor, times, ranges)
    return measured_readings(robot, truths, rng)
