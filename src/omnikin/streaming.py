"""Streaming odometry: :class:`Odometry`, fed one sample at a time (the core's only mutable state).

Per sample (``docs/conventions.md``): counter increments (:mod:`omnikin.encoders`, which
holds every rule on wrap-around and jumps), forward kinematics with the robot's constant
(or, with steerable wheels, per-interval) operator, and the pose update of
:mod:`omnikin.integration`. Without steerable wheels the update is a generated, unrolled
function (:mod:`omnikin._stream_kernel`) whose every doubt falls back to the general path
here, which either integrates the sample the same way or raises.

An update that raises leaves the estimator exactly as it was. "Sample k" in messages
counts every sample fed so far that was accepted or skipped as a duplicate.
"""

from __future__ import annotations

import math
import numbers
import warnings
from typing import Optional

import numpy as np

from ._arrays import as_components
from ._stream_kernel import compile_advance, compile_update
from .encoders import (check_bits, check_max_jump, jump_limit, tick_rate, wrap_scalar)
from .errors import InputError, OdometryInputError
from .geometry import wrap_angle
from .integration import check_method
from .linalg import rank
from .model import Robot
from .odometry import encoded_wheels, mid_steer


class Odometry:
    """Streaming odometry fed encoder ticks (or wheel angles) and timestamps.

    >>> odo = Odometry(robot)                       # doctest: +SKIP
    >>> odo.update(0.00, [0, 0, 0]); odo.update(0.01, [12, -3, 7])   # doctest: +SKIP

    The first sample is the zero (pose stays at ``start``). Each later sample must come
    later in time; a sample repeating the previous timestamp, readings and steering is a
    duplicate: skipped, counted in ``duplicates`` and warned about once. Anything else
    that cannot be integrated raises :class:`OdometryInputError` and changes nothing.

    After each update: ``pose`` (x, y, theta) [m, m, rad; theta in [-pi, pi)], ``twist``
    (mean body twist over the last interval), ``residual`` (forward-kinematics residual
    [rad/s], one entry per fitted row: the wheels, then centred steerable wheels), ``t``.
    """

    def __init__(self, robot: Robot, *, method: str = "exact", counter_bits: int | None = None,
                 start=(0.0, 0.0, 0.0), max_jump=None):
        self.robot = robot
        self.method = check_method(method)
        self.bits = check_bits(counter_bits)
        self._max_jump = check_max_jump(max_jump)
        self._wheels = encoded_wheels(robot)
        self.wheel_names = [w.name for w in self._wheels]
        self._n = len(self._wheels)
        self._scale = [w.encoder.rad_per_tick for w in self._wheels]
        self._rates = [tick_rate(w, self._max_jump) for w in self._wheels]
        self._steerable = bool(robot.steerable)
        self._advance = compile_advance(self, self.method)
        rows = robot.fk_rows(np.zeros(len(robot.steerable)), self.wheel_names)
        self._n_rows = rows.shape[0]
        self.reset(start)
        if not self._steerable:
            self._rows = rows
            self._fk = robot.fk_matrix(None, self.wheel_names)
            redundant = rows.shape[0] > rank(rows @ robot.admissible_basis)
            fk_ticks = [[float(v) * s for v, s in zip(row, self._scale)] for row in self._fk]
            self.update = compile_update(self, self._n, fk_ticks, self.method, self.bits, self._max_jump,
                                         self._rates, self._update_general, self._not_later,
                                         self._set_residual if redundant else None)

    def reset(self, pose=(0.0, 0.0, 0.0)) -> None:
        """Forget the previous sample; the next one is the new zero, at ``pose``."""
        p = as_components(pose, 3, "pose")
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InputError(f"pose: expected 3 finite numbers, got {pose!r}")
        self._x, self._y, self._th = float(p[0]), float(p[1]), float(wrap_angle(p[2]))
        self._t = None
        self._ticks = None
        self._steer = None
        self.twist = (0.0, 0.0, 0.0)
        self.residual = [0.0] * self._n_rows
        self.samples = 0
        self.duplicates = 0
        self._warned = False

    @property
    def pose(self) -> tuple[float, float, float]:
        return (self._x, self._y, self._th)

    @property
    def t(self) -> Optional[float]:
        return self._t

    @property
    def _index(self) -> int:
        return self.samples + self.duplicates

    def update(self, t: float, ticks, steer=None) -> tuple[float, float, float]:
        """Feed one sample: time [s], raw counter readings of the encoded wheels in file
        order, and (steerable robots) their steering angles [rad]. Returns the pose."""
        return self._update_general(t, ticks, steer)

    def update_angles(self, t: float, angles, steer=None) -> tuple[float, float, float]:
        """Feed one sample of wheel angles [rad] (encoded wheels, file order)."""
        if self.bits is not None:
            raise InputError("update_angles works without counter wrap-around: create Odometry with counter_bits=None")
        values = self._numbers(angles, "wheel angle")
        return self.update(t, [a / s for a, s in zip(values, self._scale)], steer)

    # --- the general path: first sample, steering, numpy scalars, anything doubtful ------------
    def _numbers(self, values, what: str) -> tuple:
        """Readings as a tuple of Python ints/floats, or an error naming the sample and wheel."""
        try:
            seq = list(values)
        except TypeError:
            raise OdometryInputError(f"sample {self._index}: expected {self._n} {what}s for wheels "
                                     f"{self.wheel_names}, got {values!r}") from None
        if len(seq) != self._n:
            raise OdometryInputError(f"sample {self._index}: expected {self._n} {what}s for wheels "
                                     f"{self.wheel_names}, got {len(seq)}")
        out = []
        for name, v in zip(self.wheel_names, seq):
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise OdometryInputError(f"sample {self._index}: {what} {v!r} of wheel {name!r} is not a number")
            v = int(v) if isinstance(v, numbers.Integral) else float(v)
            if isinstance(v, float) and not math.isfinite(v):
                raise OdometryInputError(f"sample {self._index}: non-finite {what} {v!r}, wheel {name!r}")
            out.append(v)
        return tuple(out)

    def _time(self, t) -> float:
        if isinstance(t, (bool, np.bool_)) or not isinstance(t, numbers.Real):
            raise OdometryInputError(f"sample {self._index}: timestamp must be a number [s], got {t!r}")
        if not math.isfinite(float(t)):
            raise OdometryInputError(f"sample {self._index}: non-finite timestamp {t!r}")
        return float(t)

    def _update_general(self, t, ticks, steer):
        t = self._time(t)
        values = self._numbers(ticks, "tick reading")
        s = self._check_steer(steer)
        if self._ticks is None:
            return self._first(t, values, s)
        dt = t - self._t
        if not dt > 0.0:
            return self._not_later(t, dt, values, s)
        deltas = [wrap_scalar(a - b, self.bits) for a, b in zip(values, self._ticks)]
        self._check(deltas, dt, values)
        dangle = np.array([d * k for d, k in zip(deltas, self._scale)], dtype=float)
        if self._steerable:
            mid = mid_steer(np.stack([self._steer, s]))[0]
            fk = self.robot.fk(dangle, mid, self.wheel_names)
            inc, residual = fk.twist, fk.residual
        else:
            inc = self._fk @ np.concatenate([dangle, np.zeros(self._n_rows - self._n)])
            residual = self._residual_of(dangle, inc)
        self._ticks = values
        self._steer = s
        self.residual = [float(v) / dt for v in residual]
        a, b, phi = (float(v) for v in inc)
        return self._advance(t, dt, a, b, phi)

    def _first(self, t, values, steer):
        self._check_range(values)
        self._steer = steer
        self._t = t
        self._ticks = values
        self.samples = 1
        return self.pose

    def _not_later(self, t, dt, ticks, steer):
        values = ticks if isinstance(ticks, tuple) else self._numbers(ticks, "tick reading")
        same_steer = steer is None or (self._steer is not None and np.array_equal(steer, self._steer))
        if dt == 0.0 and values == self._ticks and same_steer:
            self.duplicates += 1
            if not self._warned:
                warnings.warn(f"odometry: duplicate sample at t={t!r} skipped (counted in .duplicates)",
                              RuntimeWarning, stacklevel=3)
                self._warned = True
            return self.pose
        t = self._time(t)
        what = "repeats" if dt == 0.0 else "goes back from"
        differs = " with different readings or steering" if dt == 0.0 else ""
        raise OdometryInputError(f"sample {self._index}: timestamp {t!r} {what} the previous one {self._t!r}{differs}")

    def _check(self, deltas, dt, ticks):
        """Raise naming the sample and wheel if an increment cannot be integrated."""
        self._check_range(ticks)
        half = 2 ** (self.bits - 1) if self.bits is not None else None
        for j, d in enumerate(deltas):
            name = self.wheel_names[j]
            if abs(d) > jump_limit(self._max_jump, self._rates[j], dt, self.bits) or (half is not None and d == -half):
                raise OdometryInputError(
                    f"sample {self._index}: impossible jump of {d} ticks in {dt:.6g} s, wheel {name!r} "
                    f"(faster than the wheel can turn, or half the counter range)")

    def _check_range(self, ticks) -> None:
        """Raise if a reading lies outside a ``bits``-bit counter (signed or unsigned)."""
        if self.bits is None:
            return
        for name, v in zip(self.wheel_names, ticks):
            if not -(2 ** (self.bits - 1)) <= v < 2 ** self.bits:
                raise OdometryInputError(f"sample {self._index}: tick reading {v!r} outside the range of a "
                                         f"{self.bits}-bit counter, wheel {name!r}")

    def _check_steer(self, steer):
        if not self._steerable:
            if steer is not None:
                raise InputError(f"robot {self.robot.name!r} has no steerable wheel: do not pass steer")
            return None
        if steer is None:
            raise InputError(f"robot {self.robot.name!r}: steerable wheels {self.robot.steer_names} need "
                               f"their steering angles (steer=...)")
        s = as_components(steer, len(self.robot.steerable), "steer")
        if s.shape != (len(self.robot.steerable),):
            raise OdometryInputError(f"sample {self._index}: steer: expected {len(self.robot.steerable)} angles "
                                     f"for {self.robot.steer_names}, got shape {s.shape}")
        if not np.all(np.isfinite(s)):
            raise OdometryInputError(f"sample {self._index}: non-finite steering angle {list(s)}")
        return s

    def _residual_of(self, dangle, inc) -> np.ndarray:
        b = np.concatenate([dangle, np.zeros(self._n_rows - self._n)])
        return b - self._rows @ inc

    def _set_residual(self, deltas, a, b, phi, dt):
        """Residual of the generated path (redundant layouts only)."""
        dangle = np.array([d * k for d, k in zip(deltas, self._scale)], dtype=float)
        self.residual = [float(v) / dt for v in self._residual_of(dangle, np.array([a, b, phi]))]
