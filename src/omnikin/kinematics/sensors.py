"""The sensors a robot carries besides its wheels' encoders: IMU, 2D lidar, bumpers
(``docs/sensors.md``; the robot file's ``sensors:``).

Pure data, checked as built: each field in its range, each error naming the sensor and the
field. SI units and radians here (degrees only in robot files, fields ending in ``_deg``). A
sensor's **mount** is its frame in the body frame: ``x, y, z`` [m] (z above the floor) and
``yaw`` [rad] about z; its axes are the body's turned by ``yaw`` (x forward, z up).

- :class:`Imu`: a 3-axis gyroscope and accelerometer sampled at ``rate`` [Hz], each axis with
  white noise of density ``noise_density``, a turn-on bias of standard deviation ``bias``, a
  bias random walk of density ``bias_walk``, a scale factor error of standard deviation
  ``scale`` and an axis misalignment of standard deviation ``misalignment`` [rad] (the errors of
  IEEE Std 952's model; units in :class:`ImuAxes`).
- :class:`Lidar`: a 2D scanner of ``beams`` beams equally spaced in angle over ``fov`` [rad]
  (as ``sensor_msgs/LaserScan`` declares them: :meth:`Lidar.angles`), ``range_min`` to
  ``range_max`` [m], a scan every ``1 / rate`` s, Gaussian range noise ``range_noise`` [m] and
  beams lost with probability ``dropout``.
- :class:`Bumper`: a contact switch pressed while the robot touches a body at a bearing (from
  the body origin, body frame) within ``arc`` [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..common.arrays import range_problem, whole_problem
from ..common.messages import shorten
from ..errors import InputError

MOUNT_LIMIT = 10.0
"""Largest ``|x|``, ``|y|`` of a mount [m] (as far as a wheel may sit)."""
MOUNT_HEIGHT = (0.0, 10.0)
"""Height of a mount above the floor [m]."""
IMU_RATE = (1.0, 2000.0)
"""Sample rate of an IMU [Hz]."""
LIDAR_RATE = (0.1, 100.0)
"""Scans per second of a lidar [Hz]."""
LIDAR_BEAMS = (1, 10_000)
"""Beams of one scan: a 0.036 deg resolution is the finest 2D lidars offer."""
RANGE_LIMITS = (1e-3, 1000.0)
"""``range_min`` and ``range_max`` of a lidar [m]."""
RANGE_NOISE = (0.0, 1.0)
"""Standard deviation of a lidar's range noise [m]."""
DROPOUT = (0.0, 0.99)
"""Probability that a beam returns nothing."""
GYRO_LIMITS = {
    "noise_density": (0.0, 1.0, "rad/s/sqrt(Hz)"),
    "bias": (0.0, 1.0, "rad/s"),
    "bias_walk": (0.0, 1.0, "rad/s^2/sqrt(Hz)"),
    "scale": (0.0, 0.5, ""),
    "misalignment": (0.0, 0.1, "rad"),
}
"""Ranges of a gyroscope's error parameters (a consumer MEMS gyro: noise density about 1e-4,
turn-on bias 1e-3 to 1e-2, bias walk 1e-5 to 1e-4)."""
ACCEL_LIMITS = {
    "noise_density": (0.0, 10.0, "m/s^2/sqrt(Hz)"),
    "bias": (0.0, 10.0, "m/s^2"),
    "bias_walk": (0.0, 10.0, "m/s^3/sqrt(Hz)"),
    "scale": (0.0, 0.5, ""),
    "misalignment": (0.0, 0.1, "rad"),
}
"""Ranges of an accelerometer's error parameters (consumer MEMS: noise density about 2e-3,
turn-on bias 1e-2 to 1e-1, bias walk 1e-4 to 1e-3)."""
SENSOR_TYPES = ("imu", "lidar", "bumper")
"""The ``type`` of a sensor in a robot file."""


def _check(owner: str, field: str, value, low: float, high: float, unit: str = "") -> float:
    problem = range_problem(value, low, high, unit)
    if problem:
        raise InputError(f"{owner}: field {field!r}: {problem}")
    return float(value)


RESERVED_FRAMES = ("base_link", "base_footprint", "odom", "map", "world", "earth")
"""Frame names of REP 105 and of the robot's base: a sensor's frame must be another."""


def sensor_name_problem(name) -> str | None:
    """None if ``name`` can name a sensor (and its frame in ROS: a letter, then letters, digits
    and underscores, at most 64, none of :data:`RESERVED_FRAMES`), else why not."""
    if not isinstance(name, str) or not name or len(name) > 64:
        return f"must be 1 to 64 characters, got {shorten(name)}"
    if name in RESERVED_FRAMES:
        frames = ", ".join(RESERVED_FRAMES)
        return f"{name!r} is a frame of the robot's base or of REP 105 ({frames}): name the sensor's own frame"
    if not (name[0].isascii() and name[0].isalpha()) or not all(
        c.isascii() and (c.isalnum() or c == "_") for c in name
    ):
        return f"a letter, then letters, digits and underscores (a ROS frame name), got {shorten(name)}"
    return None


@dataclass(frozen=True)
class Mount:
    """A sensor's frame in the body frame: ``x``, ``y``, ``z`` [m] (z above the floor), ``yaw`` [rad]."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = 0.0

    def checked(self, owner: str) -> Mount:
        """This mount with every field checked (``owner`` names the sensor in messages)."""
        return Mount(
            _check(owner, "mount.x", self.x, -MOUNT_LIMIT, MOUNT_LIMIT, "m"),
            _check(owner, "mount.y", self.y, -MOUNT_LIMIT, MOUNT_LIMIT, "m"),
            _check(owner, "mount.z", self.z, *MOUNT_HEIGHT, "m"),
            _check(owner, "mount.yaw", self.yaw, -2.0 * math.pi, 2.0 * math.pi, "rad"),
        )


@dataclass(frozen=True)
class ImuAxes:
    """The errors of one triad (gyroscope or accelerometer), each axis alike. Units for the
    gyroscope (accelerometer): ``noise_density`` rad/s/sqrt(Hz) (m/s^2/sqrt(Hz)), ``bias`` rad/s
    (m/s^2), ``bias_walk`` rad/s^2/sqrt(Hz) (m/s^3/sqrt(Hz)), ``scale`` a fraction,
    ``misalignment`` rad; ``bias``, ``scale`` and ``misalignment`` are standard deviations of
    values drawn once per run."""

    noise_density: float = 0.0
    bias: float = 0.0
    bias_walk: float = 0.0
    scale: float = 0.0
    misalignment: float = 0.0

    def checked(self, owner: str, limits: dict) -> ImuAxes:
        """These errors with every field checked against ``limits`` (field -> (low, high, unit))."""
        return ImuAxes(**{f: _check(owner, f, getattr(self, f), *limits[f]) for f in limits})

    @property
    def is_zero(self) -> bool:
        """True when the triad has no error at all."""
        return not (self.noise_density or self.bias or self.bias_walk or self.scale or self.misalignment)


@dataclass(frozen=True)
class Imu:
    """An inertial measurement unit (module docstring): ``gyro`` and ``accel`` errors, ``rate`` [Hz]."""

    name: str
    mount: Mount = Mount()
    rate: float = 100.0
    gyro: ImuAxes = ImuAxes()
    accel: ImuAxes = ImuAxes()

    type = "imu"

    def __post_init__(self):
        owner = _owner(self.name)
        object.__setattr__(self, "mount", _mount(self.mount, owner))
        object.__setattr__(self, "rate", _check(owner, "rate", self.rate, *IMU_RATE, "Hz"))
        for field, limits in (("gyro", GYRO_LIMITS), ("accel", ACCEL_LIMITS)):
            value = getattr(self, field)
            if not isinstance(value, ImuAxes):
                raise InputError(f"{owner}: field {field!r}: must be ImuAxes, got {shorten(value)}")
            object.__setattr__(self, field, value.checked(f"{owner}: {field}", limits))


@dataclass(frozen=True)
class Lidar:
    """A 2D lidar (module docstring): ``beams`` over ``fov`` [rad], ``range_min`` to
    ``range_max`` [m], ``rate`` [Hz], ``range_noise`` [m], ``dropout``."""

    name: str
    mount: Mount = Mount()
    rate: float = 10.0
    beams: int = 360
    fov: float = 2.0 * math.pi
    range_min: float = 0.1
    range_max: float = 12.0
    range_noise: float = 0.0
    dropout: float = 0.0

    type = "lidar"

    def __post_init__(self):
        owner = _owner(self.name)
        object.__setattr__(self, "mount", _mount(self.mount, owner))
        object.__setattr__(self, "rate", _check(owner, "rate", self.rate, *LIDAR_RATE, "Hz"))
        problem = whole_problem(self.beams, *LIDAR_BEAMS)
        if problem:
            raise InputError(f"{owner}: field 'beams': {problem}")
        object.__setattr__(self, "beams", int(self.beams))
        object.__setattr__(self, "fov", _check(owner, "fov", self.fov, 1e-3, 2.0 * math.pi, "rad"))
        low = _check(owner, "range_min", self.range_min, *RANGE_LIMITS, "m")
        high = _check(owner, "range_max", self.range_max, *RANGE_LIMITS, "m")
        if not low < high:
            raise InputError(f"{owner}: range_min {low:g} m must be below range_max {high:g} m")
        object.__setattr__(self, "range_min", low)
        object.__setattr__(self, "range_max", high)
        object.__setattr__(self, "range_noise", _check(owner, "range_noise", self.range_noise, *RANGE_NOISE, "m"))
        object.__setattr__(self, "dropout", _check(owner, "dropout", self.dropout, *DROPOUT))

    @property
    def full_circle(self) -> bool:
        """True when the beams go all the way round (``fov`` = 2 pi): the last beam is not the first."""
        return self.fov >= 2.0 * math.pi

    @property
    def angle_increment(self) -> float:
        """Angle between beams [rad]: ``fov / beams`` all the way round, else ``fov / (beams - 1)``
        (the first and last beam on the edges of the field of view)."""
        if self.full_circle:
            return self.fov / self.beams
        return self.fov / (self.beams - 1) if self.beams > 1 else 0.0

    @property
    def angle_min(self) -> float:
        """Angle of the first beam in the sensor frame [rad]: ``-pi`` all the way round, else ``-fov / 2``."""
        return -math.pi if self.full_circle else -self.fov / 2.0

    def angles(self):
        """``(beams,)`` beam angles [rad] in the sensor frame, counter-clockwise:
        ``angle_min + k angle_increment`` (LaserScan's ``angle_min``, ``angle_increment``;
        its ``angle_max`` is the last of them)."""
        import numpy as np

        return self.angle_min + np.arange(self.beams) * self.angle_increment


@dataclass(frozen=True)
class Bumper:
    """A contact switch (module docstring): pressed while a contact lies at a bearing within
    ``arc`` (low, high) [rad], body frame, counter-clockwise from body +x."""

    name: str
    arc: tuple[float, float] = (-math.pi, math.pi)

    type = "bumper"

    def __post_init__(self):
        owner = _owner(self.name)
        arc = self.arc
        if not isinstance(arc, (list, tuple)) or len(arc) != 2:
            raise InputError(f"{owner}: field 'arc': must be (low, high) [rad], got {shorten(arc)}")
        low = _check(owner, "arc", arc[0], -2.0 * math.pi, 2.0 * math.pi, "rad")
        high = _check(owner, "arc", arc[1], -2.0 * math.pi, 2.0 * math.pi, "rad")
        if not low < high or high - low > 2.0 * math.pi:
            raise InputError(f"{owner}: field 'arc': need low < high within one turn, got {low:g} and {high:g} rad")
        object.__setattr__(self, "arc", (low, high))

    def presses(self, bearing: float) -> bool:
        """Whether a contact at ``bearing`` [rad, body frame] lies within :attr:`arc`."""
        low, high = self.arc
        turns = math.floor((bearing - low) / (2.0 * math.pi))
        return bearing - turns * 2.0 * math.pi <= high


Sensor = Imu | Lidar | Bumper
"""A sensor of a robot."""


def _owner(name) -> str:
    problem = sensor_name_problem(name)
    if problem:
        raise InputError(f"sensor name: {problem}")
    return f"sensor {name!r}"


def _mount(mount, owner: str) -> Mount:
    if not isinstance(mount, Mount):
        raise InputError(f"{owner}: field 'mount': must be a Mount, got {shorten(mount)}")
    return mount.checked(owner)
