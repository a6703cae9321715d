"""One wheel's kinematic constraints; a wheel knows nothing of robots.

Frames and signs follow ``docs/conventions.md``. A wheel sits at the point
``p = (x, y)`` of the body frame [m] (for steerable wheels and castors: the point
where the steering axis meets the floor), has the drive direction
``u = (cos delta, sin delta)`` (``delta`` = mounting ``drive`` plus steering angle)
and rolling radius ``r`` [m]. With the body twist ``(vx, vy, omega)`` the floor
point under ``p`` moves with ``v_p = (vx - omega y, vy + omega x)``.

Rows implemented here (each a ``(..., 3)`` array acting on the twist):

* rolling row, Swedish wheel of roller angle ``gamma`` (omni: 0), and with
  ``gamma = 0`` every other wheel (Muir & Neuman 1987; Campion, Bastin and
  d'Andrea-Novel 1996, eq. 2-7)::

      omega_i = [cos(a) vx + sin(a) vy + (x sin(a) - y cos(a)) omega] / (r cos gamma),
      a = delta + gamma

  It says that the contact cannot slip along the axis of the roller on the floor.
  For a castor or off-centred steerable wheel whose contact trails ``p`` by
  ``offset`` along ``-u``, the same row at ``p`` holds whatever the steering rate
  (the swivel moves the contact along ``u``'s normal only).
* sliding row, standard and centred-steerable wheels: no side slip,
  ``(-sin delta, cos delta) . v_p = 0`` i.e.
  ``[-sin delta, cos delta, x cos delta + y sin delta] . twist = 0`` [m/s];
  off-centred steerable wheels (``swivel_row``): the contact does not slide sideways,
  ``(-sin delta, cos delta) . v_p - offset omega = offset beta'`` at steering rate ``beta'``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..common.arrays import range_problem
from ..common.messages import digits_apart, shorten
from ..errors import InfeasibleTwistError, InputError
from .encoder import Encoder
from .physical import PhysicalWheel
from .se2 import wrap_angle

WHEEL_TYPES = ("omni", "mecanum", "swedish", "standard", "steerable", "castor")
SWEDISH_TYPES = ("omni", "mecanum", "swedish")

# --- what a wheel may be (docs/conventions.md, "Ranges" and "Names") ------------------------
NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")
"""Wheel names: a letter, then letters, digits or underscores, 64 characters at most, so that a
name is a CSV column and a ROS name as it stands (no quoting, no blanks, no separators)."""
RESERVED_NAMES = frozenset({"t"})
"""Names a wheel may not take: ``t`` is the time column of tick logs."""
DERIVED_SUFFIXES = {"_steer": "steering joint (joint_states)", "_steer_deg": "steering column (tick logs)"}
"""Names derived from a wheel name ``w`` and what they name: ``w_steer`` and ``w_steer_deg``; no
wheel may carry a name derived from another wheel's."""

RADIUS_RANGE = (1e-4, 10.0)
"""Rolling radius [m]: from a 0.1 mm micro-robot wheel to a 10 m mining-truck tyre."""
POSITION_LIMIT = 1e3
"""Largest ``|x|``, ``|y|`` of a wheel [m]: a wheel more than 1 km from the body origin is a typo."""
OFFSET_RANGE = (0.0, 10.0)
"""Castor trail / steering offset [m], bounded like the radius."""
ROLLER_LIMIT_DEG = 80.0
"""Largest ``|roller angle|`` [deg]: a Swedish wheel's speed is scaled by ``1/cos(gamma)``
(5.8 at 80 deg, infinite at 90 deg where the wheel cannot drive); built wheels use 0 and 45."""
MAX_SPEED_RANGE = (1e-3, 1e4)
"""Wheel speed limit [rad/s]: 1e4 rad/s is 95 000 rpm, beyond any wheel."""
MOTOR_TYPES = ("stepper", "dc")
"""What turns a driven wheel (docs/conventions.md, "Motors"): a ``stepper`` turns open loop, by
the steps commanded (its encoder only measures: an encoder scale error changes what the counts
say, not how the wheel turns); a ``dc`` motor's speed loop closes on the wheel's encoder (the
wheel turns so that the *counts* follow the command: an encoder scale error changes how far the
wheel turns)."""
DEFAULT_MOTOR = "stepper"
"""The motor of a wheel whose file says none: the seed robot's (Tomasi and Todt drive their
three omni wheels with NEMA 17 stepper motors, Sec. 4 of their paper)."""


def name_problem(name) -> str | None:
    """None if ``name`` is a valid wheel name (:data:`NAME_PATTERN`, not reserved), else why not."""
    if not isinstance(name, str):
        return f"must be a string, got {shorten(name)} (quote it in YAML: name: '1')"
    if not NAME_PATTERN.fullmatch(name):
        return (
            f"{shorten(name)} is not a valid wheel name: a letter, then letters, digits or underscores, "
            f"at most 64 characters (it names CSV columns and ROS joints)"
        )
    if name in RESERVED_NAMES:
        return f"{name!r} is reserved (the time column of tick logs)"
    return None


def motor_problem(motor, kind: str, encoded: bool) -> str | None:
    """None if ``motor`` (None or one of :data:`MOTOR_TYPES`) fits a wheel of type ``kind`` with
    (``encoded``) or without an encoder, else why not: a castor is passive, a ``dc`` motor's
    speed loop needs the wheel's encoder."""
    if motor is None:
        return None
    if not isinstance(motor, str) or motor not in MOTOR_TYPES:
        return f"must be one of {', '.join(MOTOR_TYPES)}, got {shorten(motor)}"
    if kind == "castor":
        return "a castor is passive: it has no motor"
    if motor == "dc" and not encoded:
        return "a dc motor's speed loop closes on the wheel's encoder: give the wheel an encoder, or use stepper"
    return None


def _require(problem: str | None, what: str) -> None:
    if problem is not None:
        raise InputError(f"{what} {problem}")


@dataclass(frozen=True)
class Steer:
    """Steering of a steerable wheel or castor.

    Parameters
    ----------
    offset : float, default 0.0
        Distance [m] by which the contact trails the steering axis against the drive direction,
        0 .. 10 (0: a centred wheel).
    lower, upper : float, default -pi, pi
        Steering limits [rad] relative to the mounting drive direction, each in ``[-pi, pi]``,
        ``lower < upper``.

    Raises
    ------
    InputError
        A value outside its range or ``lower >= upper``; the message names the field.
    """

    offset: float = 0.0
    lower: float = -np.pi
    upper: float = np.pi

    def __post_init__(self):
        _require(range_problem(self.offset, *OFFSET_RANGE, "m"), "steer: offset")
        _require(range_problem(self.lower, -math.pi, math.pi, "rad"), "steer: lower")
        _require(range_problem(self.upper, -math.pi, math.pi, "rad"), "steer: upper")
        if not self.lower < self.upper:
            p = digits_apart(self.lower, self.upper)
            raise InputError(f"steer: need lower < upper, got {self.lower:.{p}g} and {self.upper:.{p}g} rad")


@dataclass(frozen=True)
class Wheel:
    """A wheel mounted on the body (SI units, radians).

    The robot file's wheel (docs/conventions.md, "Wheels"), its degrees converted to radians.

    Parameters
    ----------
    name : str
        Wheel name, ``[A-Za-z][A-Za-z0-9_]{0,63}``, not ``t`` (docs/conventions.md, "Names").
    type : str
        One of :data:`WHEEL_TYPES`: ``omni``, ``mecanum``, ``swedish``, ``standard``,
        ``steerable``, ``castor``.
    x, y : float
        Hub contact point ``p`` [m] in the body frame (``base_link``: x forward, y left), each
        within +-1000 m (for a steerable wheel or castor: where the steering axis meets the floor).
    drive : float
        Drive direction ``delta`` [rad] at zero steering, counter-clockwise from body +x.
    radius : float
        Rolling radius [m], 0.0001 .. 10.
    roller : float, default 0.0
        Roller angle ``gamma`` [rad] of a Swedish wheel, within +-80 deg (a robot file's mecanum
        wheel: +-45 deg); 0 for every other type.
    encoder : Encoder or None, default None
        The wheel's encoder; None: odometry does not read this wheel.
    max_speed : float or None, default None
        Largest wheel speed [rad/s], 0 .. 10000 (0: a locked wheel); None: unbounded.
    steer : Steer or None, default None
        Offset and steering limits of a steerable wheel or castor.
    physical : PhysicalWheel or None, default None
        Physical fields for physics engines (see the attribute below).
    motor : str or None, default None
        ``stepper`` or ``dc`` (see the attribute below).

    Raises
    ------
    InputError
        A bad name or type, a number outside its range, a roller angle on a wheel that is not
        Swedish, a part of the wrong class, or a motor the wheel cannot have; the message names
        the wheel and the field.
    """

    name: str
    type: str
    x: float
    y: float
    drive: float
    radius: float
    roller: float = 0.0
    encoder: Encoder | None = None
    max_speed: float | None = None
    steer: Steer | None = None
    physical: PhysicalWheel | None = None
    """Physical fields (width, mass, rollers, friction, motor torque) for physics engines; None:
    all derived from the layout (:mod:`omnikin.physics.description`)."""
    motor: str | None = None
    """The kind of motor that turns the wheel, one of :data:`MOTOR_TYPES` (None: :data:`DEFAULT_MOTOR`);
    ``dc`` needs an encoder (its speed loop closes on it), a castor has none."""

    def __post_init__(self):
        """Check the name and every number against the ranges above (docs/conventions.md)."""
        _require(name_problem(self.name), "wheel name:")
        who = f"wheel {self.name!r}:"
        if self.type not in WHEEL_TYPES:
            raise InputError(f"{who} unknown type {shorten(self.type)}; one of {list(WHEEL_TYPES)}")
        roller = math.radians(ROLLER_LIMIT_DEG)
        for field, low, high, unit in (
            ("x", -POSITION_LIMIT, POSITION_LIMIT, "m"),
            ("y", -POSITION_LIMIT, POSITION_LIMIT, "m"),
            ("drive", -math.inf, math.inf, "rad"),
            ("radius", *RADIUS_RANGE, "m"),
            ("roller", -roller, roller, "rad"),
        ):
            _require(range_problem(getattr(self, field), low, high, unit), f"{who} {field}")
        if self.roller and not self.is_swedish:
            raise InputError(f"{who} only Swedish wheels have a roller angle")
        if self.max_speed is not None:
            # 0 (a locked wheel) is allowed here; a robot file describes a drivable robot and needs the range
            _require(range_problem(self.max_speed, 0.0, MAX_SPEED_RANGE[1], "rad/s"), f"{who} max_speed")
        for part, kind in (("encoder", Encoder), ("steer", Steer), ("physical", PhysicalWheel)):
            value = getattr(self, part)
            if value is not None and not isinstance(value, kind):
                raise InputError(f"{who} {part} must be a {kind.__name__} or None, got {shorten(value)}")
        if self.physical is not None:
            self.physical.check(f"wheel {self.name!r}")
            if not self.is_swedish and (self.physical.rollers is not None or self.physical.rows is not None):
                raise InputError(f"{who} only Swedish wheels have rollers (physical.rollers, physical.rows)")
            if self.is_castor and self.physical.max_torque is not None:
                raise InputError(f"{who} a castor is passive: it has no motor (physical.max_torque)")
        _require(motor_problem(self.motor, self.type, self.encoder is not None), f"{who} motor")

    # --- classification ---------------------------------------------------
    @property
    def motor_kind(self) -> str:
        """The wheel's motor, :attr:`motor` or :data:`DEFAULT_MOTOR` when the file gave none."""
        return self.motor if self.motor is not None else DEFAULT_MOTOR

    @property
    def counts_close_loop(self) -> bool:
        """True when the wheel's speed loop closes on its encoder's counts (a ``dc`` motor): an
        encoder scale error then changes how far the wheel turns, not what the counts say."""
        return self.motor_kind == "dc" and self.encoder is not None

    @property
    def is_swedish(self) -> bool:
        return self.type in SWEDISH_TYPES

    @property
    def is_castor(self) -> bool:
        return self.type == "castor"

    @property
    def is_steerable(self) -> bool:
        """Actively steered (steering angle is a command / measurement)."""
        return self.type == "steerable"

    @property
    def is_fixed(self) -> bool:
        """Standard wheel with a fixed axle: its sliding row constrains the body."""
        return self.type == "standard"

    @property
    def is_centred_steerable(self) -> bool:
        """Steerable wheel whose steering axis passes through the contact point."""
        return self.is_steerable and (self.steer is None or self.steer.offset == 0.0)

    @property
    def offset(self) -> float:
        """Trail of the contact behind the steering axis [m] (0 without ``steer``)."""
        return self.steer.offset if self.steer is not None else 0.0

    # --- geometry -----------------------------------------------------------
    def direction(self, steer=0.0):
        """Drive direction ``delta`` [rad] at steering angle ``steer`` [rad].

        Parameters
        ----------
        steer : array_like, shape (...), default 0.0
            Steering angle [rad] relative to :attr:`drive` (0 for a wheel that is not steered).

        Returns
        -------
        ndarray, shape (...)
            ``drive + steer`` [rad], counter-clockwise from body +x.
        """
        return self.drive + np.asarray(steer, dtype=float)

    def contact_point(self, steer=0.0) -> np.ndarray:
        """Floor contact ``(..., 2)`` [m, body frame]: ``p - offset u(delta)``.

        Parameters
        ----------
        steer : array_like, shape (...), default 0.0
            Steering angle [rad] relative to :attr:`drive` (0 for a wheel that is not steered).

        Returns
        -------
        ndarray, shape (..., 2)
            Contact point ``(x, y)`` [m] in the body frame.
        """
        delta = self.direction(steer)
        out = np.empty(np.shape(delta) + (2,))
        out[..., 0] = self.x - self.offset * np.cos(delta)
        out[..., 1] = self.y - self.offset * np.sin(delta)
        return out

    def rolling_row(self, steer=0.0) -> np.ndarray:
        """Row ``(..., 3)`` mapping the body twist to this wheel's speed [rad/s].

        ``[cos a, sin a, x sin a - y cos a] / (r cos gamma)``, ``a = delta + gamma`` (module
        docstring; docs/conventions.md, "Wheels").

        Parameters
        ----------
        steer : array_like, shape (...), default 0.0
            Steering angle [rad] relative to :attr:`drive` (0 for a wheel that is not steered).

        Returns
        -------
        ndarray, shape (..., 3)
            Wheel speed [rad/s] per body twist component ``(vx, vy, omega)`` [m/s, m/s, rad/s].
        """
        a = self.direction(steer) + self.roller
        ca, sa = np.cos(a), np.sin(a)
        out = np.empty(np.shape(a) + (3,))
        scale = 1.0 / (self.radius * np.cos(self.roller))
        out[..., 0] = ca * scale
        out[..., 1] = sa * scale
        out[..., 2] = (self.x * sa - self.y * ca) * scale
        return out

    def sliding_row(self, steer=0.0) -> np.ndarray:
        """No-side-slip row ``(..., 3)`` [m/s per twist] of standard/steerable wheels.

        ``[-sin delta, cos delta, x cos delta + y sin delta]``: the hub's side speed, zero for an
        admissible twist.

        Parameters
        ----------
        steer : array_like, shape (...), default 0.0
            Steering angle [rad] relative to :attr:`drive` (0 for a wheel that is not steered).

        Returns
        -------
        ndarray, shape (..., 3)
            Side speed [m/s] per body twist component ``(vx, vy, omega)`` [m/s, m/s, rad/s].
        """
        delta = self.direction(steer)
        cd, sd = np.cos(delta), np.sin(delta)
        out = np.empty(np.shape(delta) + (3,))
        out[..., 0] = -sd
        out[..., 1] = cd
        out[..., 2] = self.x * cd + self.y * sd
        return out

    def swivel_row(self, steer=0.0) -> np.ndarray:
        """Sliding row ``(..., 3)`` [m/s per twist] of a steerable wheel, off-centred or not:
        ``n . v_p - offset * omega`` (``n = (-sin delta, cos delta)``), which equals
        ``offset * beta'`` at steering rate ``beta'`` (the contact, trailing ``p`` by ``offset``
        along ``-u``, does not slide sideways); for a centred wheel the plain
        :meth:`sliding_row` (= 0).

        Parameters
        ----------
        steer : array_like, shape (...), default 0.0
            Steering angle [rad] relative to :attr:`drive` (0 for a wheel that is not steered).

        Returns
        -------
        ndarray, shape (..., 3)
            Side speed [m/s] per body twist component ``(vx, vy, omega)`` [m/s, m/s, rad/s].
        """
        out = self.sliding_row(steer)
        out[..., 2] -= self.offset
        return out

    def roller_row(self) -> np.ndarray:
        """Row ``(3,)`` mapping the twist to the roller surface speed [m/s].

        The rollers move the hub along ``n = (-sin a, cos a)``, the normal of the
        roller axis; with the hub velocity ``v_p = r omega_i u + s n`` the roller
        speed is ``s = n . v_p + r omega_i sin(gamma)``.
        """
        a = self.drive + self.roller
        n = np.array([-np.sin(a), np.cos(a), self.x * np.cos(a) + self.y * np.sin(a)])
        return n + self.radius * np.sin(self.roller) * self.rolling_row()

    def hub_velocity(self, twist) -> np.ndarray:
        """Velocity ``(..., 2)`` [m/s, body axes] of the floor point under ``p``.

        ``v_p = (vx - omega y, vy + omega x)``.

        Parameters
        ----------
        twist : array_like, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes.

        Returns
        -------
        ndarray, shape (..., 2)
            ``v_p`` [m/s] in body axes.
        """
        t = np.asarray(twist, dtype=float)
        out = np.empty(t.shape[:-1] + (2,))
        out[..., 0] = t[..., 0] - t[..., 2] * self.y
        out[..., 1] = t[..., 1] + t[..., 2] * self.x
        return out

    def align(self, twist, hint=0.0, strict: bool = True):
        """Steering angle [rad] aligning this wheel with the motion, and a limit flag.

        Centred wheels align ``u`` with the hub velocity ``v_p``; off-centred ones
        (trail ``d``) take the steady swivel angle where no steering rate is needed,
        ``n . v_p = d omega``, i.e. ``delta = psi - asin(d omega / |v_p|)`` (forward)
        or ``psi + pi + asin(d omega / |v_p|)`` (reversed), ``psi`` the direction of
        ``v_p``. Of the branches within the steering limits the one closest to
        ``hint`` is taken; where the hub is still the angle stays at ``hint``.
        Returns ``(angle, limited)``: ``limited`` is True where neither branch fits. An
        off-centred wheel whose axis moves slower than ``offset * |omega|`` has no steady
        angle: ``strict`` raises :class:`InfeasibleTwistError`, otherwise it is flagged
        in ``limited`` and left at ``hint``.

        Parameters
        ----------
        twist : array_like, shape (..., 3)
            Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] in body axes.
        hint : array_like, shape (...), default 0.0
            Preferred steering angle [rad] relative to :attr:`drive`.
        strict : bool, default True
            Raise for a twist without a steady steering angle, instead of flagging it.

        Returns
        -------
        angle : ndarray, shape (...)
            Steering angle [rad] relative to :attr:`drive`, in ``[-pi, pi)`` (``hint`` where the
            hub is still or no steady angle exists).
        limited : ndarray of bool, shape (...)
            True where no branch lies within the steering limits, or no steady angle exists.

        Raises
        ------
        InfeasibleTwistError
            With ``strict``: an off-centred wheel whose axis moves slower than
            ``offset * |omega|``.
        """
        t = np.asarray(twist, dtype=float)
        hint = np.broadcast_to(np.asarray(hint, dtype=float), t.shape[:-1])
        v = self.hub_velocity(t)
        speed = np.hypot(v[..., 0], v[..., 1])
        psi = np.arctan2(v[..., 1], v[..., 0])
        moving = speed > 1e-12
        k = np.where(moving, self.offset * t[..., 2] / np.where(moving, speed, 1.0), 0.0)
        unsteady = np.abs(k) > 1.0 + 1e-12
        if strict and np.any(unsteady):
            bad = np.argwhere(unsteady)[0]
            raise InfeasibleTwistError(
                f"wheel {self.name!r}: no steady steering angle for twist {t[tuple(bad)].tolist()}: its "
                f"steering axis moves slower than offset*|omega|, so the wheel would keep swivelling"
            )
        a = np.arcsin(np.clip(k, -1.0, 1.0))
        cands = np.stack([psi - a, psi + np.pi + a], axis=-1) - self.drive
        cands = wrap_angle(cands)
        lo, hi = (self.steer.lower, self.steer.upper) if self.steer is not None else (-np.pi, np.pi)
        within = (cands >= lo - 1e-12) & (cands <= hi + 1e-12)
        dist = np.abs(wrap_angle(cands - hint[..., None]))
        dist = np.where(within, dist, dist + 10.0)
        pick = np.take_along_axis(cands, np.argmin(dist, axis=-1)[..., None], axis=-1)[..., 0]
        angle = np.where(moving & ~unsteady, pick, hint)
        limited = (moving & ~np.any(within, axis=-1)) | unsteady
        return angle, limited
