"""Wheel odometry: a streaming estimator and batch odometry over arrays.

Per sample (``docs/conventions.md``): encoder ticks -> wheel angle increments
(:mod:`omnikin.encoders`) -> body increment by forward kinematics
(:meth:`omnikin.model.Robot.fk`, constant over the sample) -> pose update by the
SE(2) exponential (:mod:`omnikin.integration`; ``euler`` and ``midpoint`` are there
for comparison only). Odometry uses the rolling wheels that have an ``encoder``
in the robot file; with steerable wheels the steering angles of each sample are
needed too, and each interval uses the mean of its two end angles.

The streaming :class:`Odometry` is the only mutable state of the core. For a
layout without steerable wheels its update is plain Python float arithmetic on a
precomputed forward-kinematics matrix (no NumPy call on the hot path).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import cached_property
from typing import Optional

import numpy as np

from ._arrays import as_components
from .encoders import check_bits, tick_increments
from .errors import OdometryInputError, OmnikinError
from .geometry import wrap_angle
from .integration import check_method, integrate_components
from ._stream_kernel import compile_advance, compile_update
from .model import Robot


def encoded_wheels(robot: Robot):
    """The rolling wheels with an encoder, in file order; checks they observe all motion."""
    wheels = [w for w in robot.rolling if w.encoder is not None]
    if not wheels:
        raise OmnikinError(
            f"robot {robot.name!r}: no wheel has an 'encoder' entry; odometry from ticks needs "
            f"encoder.ticks_per_rev on the measured wheels")
    robot.check_observable([w.name for w in wheels])
    return wheels


def _mid_steer(steer: Optional[np.ndarray]) -> Optional[np.ndarray]:
    """Interval steering: circular mean of consecutive samples ``(..., N-1, n_steer)``."""
    if steer is None:
        return None
    return steer[..., :-1, :] + 0.5 * wrap_angle(np.diff(steer, axis=-2))


CHUNK = 1 << 14
"""Samples integrated per block: keeps the temporaries in cache (see docs/performance.md)."""


@dataclass(frozen=True)
class OdometryResult:
    """Batch odometry: ``poses`` ``(..., N, 3)`` at the times ``t`` ``(..., N)``.

    ``increments`` ``(..., N-1, 3)`` are the body displacements of each interval;
    ``twists`` their mean twists; ``residual`` ``(..., N-1, n_rows)`` the forward
    kinematics residual [rad/s] (zero for a square, full-rank layout). They are
    computed on first access.
    """

    t: np.ndarray
    poses: np.ndarray
    _delta: np.ndarray   # (..., N-1, n) wheel increments [ticks or rad] ...
    _scale: np.ndarray   # (n,) ... times this [rad per unit]
    _fk: np.ndarray      # ((..., N-1,) 3, n_rows) forward-kinematics operator
    _rows: np.ndarray    # ((..., N-1,) n_rows, 3) forward-kinematics rows A

    @cached_property
    def _angles(self) -> np.ndarray:
        return _fk_input(self._delta, self._scale, self._fk)

    @cached_property
    def increments(self) -> np.ndarray:
        return np.einsum("...ij,...j->...i", self._fk, self._angles)

    @cached_property
    def twists(self) -> np.ndarray:
        return self.increments / np.diff(self.t, axis=-1)[..., None]

    @cached_property
    def residual(self) -> np.ndarray:
        pred = np.einsum("...ij,...j->...i", self._rows, self.increments)
        return (self._angles - pred) / np.diff(self.t, axis=-1)[..., None]


def _fk_input(delta, scale, fk) -> np.ndarray:
    """Wheel angle increments ``delta * scale`` [rad], padded with zeros for the steering rows of ``fk``."""
    angles = delta * scale
    extra = fk.shape[-1] - angles.shape[-1]
    if extra:
        angles = np.concatenate([angles, np.zeros(angles.shape[:-1] + (extra,))], axis=-1)
    return angles


def batch_odometry(robot: Robot, t, ticks, *, steer=None, method: str = "exact",
                   counter_bits: int | None = None, start=None, max_jump=None) -> OdometryResult:
    """Odometry of whole logs: ``ticks`` ``(..., N, n_enc)`` at times ``t`` ``(..., N)``.

    Leading axes (trials) broadcast. ``steer`` ``(..., N, n_steer)`` [rad] is needed
    for robots with steerable wheels. The first sample is the zero of the ticks and
    sits at ``start`` (default origin). Checks as in
    :func:`omnikin.encoders.tick_increments`.
    """
    wheels = encoded_wheels(robot)
    dticks = tick_increments(wheels, t, ticks, counter_bits, max_jump)
    scale = np.array([w.encoder.rad_per_tick for w in wheels])
    return _integrate(robot, wheels, np.asarray(t, dtype=float), dticks, scale, steer, method, start)


def batch_odometry_from_angles(robot: Robot, t, angles, *, steer=None, method: str = "exact",
                               start=None) -> OdometryResult:
    """Like :func:`batch_odometry` but from wheel angles ``(..., N, n_enc)`` [rad]."""
    wheels = encoded_wheels(robot)
    a = np.asarray(angles, dtype=float)
    if a.ndim < 2 or a.shape[-1] != len(wheels):
        raise OdometryInputError(
            f"angles: expected shape (..., N, {len(wheels)}) for wheels {[w.name for w in wheels]}, got {a.shape}")
    tt = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(a)) or not np.all(np.isfinite(tt)):
        raise OdometryInputError("angles/t: non-finite values")
    if np.any(np.diff(tt, axis=-1) <= 0):
        raise OdometryInputError("t: timestamps must increase strictly")
    return _integrate(robot, wheels, tt, np.diff(a, axis=-2), np.ones(len(wheels)), steer, method, start)


def _integrate(robot, wheels, t, delta, scale, steer, method, start) -> OdometryResult:
    """Forward kinematics of the increments ``delta * scale`` [rad], then pose integration."""
    check_method(method)
    names = [w.name for w in wheels]
    if robot.steerable:
        if steer is None:
            raise OmnikinError(f"robot {robot.name!r}: steerable wheels {robot.steer_names} need steering "
                               f"angles (steer, shape (..., N, {len(robot.steerable)}))")
        s = as_components(steer, len(robot.steerable), "steer")
        if s.shape[-2] != delta.shape[-2] + 1:
            raise OdometryInputError(f"steer: expected {delta.shape[-2] + 1} samples, got shape {s.shape}")
        if not np.all(np.isfinite(s)):
            raise OdometryInputError("steer: non-finite steering angle")
        mid = _mid_steer(s)
        f = robot.fk_matrix(mid, names)
        rows = robot.fk_rows(mid, names)
    else:
        f = robot.fk_matrix(None, names)
        rows = robot.fk_rows(np.zeros(0), names)
    if robot.steerable:
        inc = np.einsum("...ij,...j->...i", f, _fk_input(delta, scale, f))
        comps = np.ascontiguousarray(np.swapaxes(inc, -1, -2))
        poses = integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], start, method)
    else:
        poses = _integrate_blocks(f * scale, delta, start, method)
    return OdometryResult(t, poses, delta, scale, f, rows)


def _integrate_blocks(f_ticks: np.ndarray, delta: np.ndarray, start, method: str) -> np.ndarray:
    """Poses from increments ``delta`` ``(..., M, n)`` and a constant FK ``f_ticks`` ``(3, n)``,
    :data:`CHUNK` samples at a time, each block starting where the previous one ended."""
    lead, m = delta.shape[:-2], delta.shape[-2]
    out = np.empty(lead + (m + 1, 3))
    pose = np.zeros(lead + (3,)) if start is None else np.broadcast_to(np.asarray(start, float), lead + (3,))
    out[..., 0, :] = pose
    for s0 in range(0, m, CHUNK):
        s1 = min(m, s0 + CHUNK)
        comps = np.matmul(f_ticks, np.swapaxes(delta[..., s0:s1, :], -1, -2))   # (..., 3, block)
        integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], pose, method,
                             out=out[..., s0:s1 + 1, :])
        pose = out[..., s1, :]
    return out


class Odometry:
    """Streaming odometry fed encoder ticks (or wheel angles) and timestamps.

    >>> odo = Odometry(robot)                       # doctest: +SKIP
    >>> odo.update(0.00, [0, 0, 0]); odo.update(0.01, [12, -3, 7])   # doctest: +SKIP

    The first sample is the zero (pose stays at ``start``). Each later sample
    must come later in time; a sample repeating the previous timestamp *and*
    readings is a duplicate: skipped, counted in ``duplicates`` and warned about
    once. Anything else that cannot be integrated raises
    :class:`OdometryInputError` and leaves the state unchanged.

    Attributes after each update: ``pose`` (x, y, theta) [m, m, rad, theta in
    [-pi, pi)], ``twist`` (mean body twist over the last interval), ``residual``
    (forward-kinematics residual [rad/s], zeros for square layouts), ``t``.
    For layouts without steerable wheels :meth:`update` is a generated,
    unrolled function (:mod:`omnikin._stream_kernel`).
    """

    def __init__(self, robot: Robot, *, method: str = "exact", counter_bits: int | None = None,
                 start=(0.0, 0.0, 0.0), max_jump=None):
        self.robot = robot
        self.method = check_method(method)
        self.bits = check_bits(counter_bits)
        self._wheels = encoded_wheels(robot)
        self.wheel_names = [w.name for w in self._wheels]
        self._n = len(self._wheels)
        self._scale = [w.encoder.rad_per_tick for w in self._wheels]
        self._max_jump = max_jump
        self._full = 2 ** self.bits if self.bits is not None else None
        self._steerable = bool(robot.steerable)
        self._rates = [(w.max_speed / abs(w.encoder.rad_per_tick)) if w.max_speed else None for w in self._wheels]
        if max_jump is not None:
            self._rates = [None] * self._n
        # static per-wheel jump limits [ticks]; a huge finite default also traps inf and NaN
        static = float(max_jump) if max_jump is not None else 1e300
        if self.bits is not None:
            static = min(static, 2 ** (self.bits - 1) - 0.5)
        self._lims = [static] * self._n
        self._advance = compile_advance(self, self.method)
        self.reset(start)
        if not self._steerable:
            f = robot.fk_matrix(None, self.wheel_names)
            self._rows = robot.fk_rows(np.zeros(0), self.wheel_names)
            redundant = self._rows.shape[0] > np.linalg.matrix_rank(self._rows)
            fk_ticks = [[float(v) * s for v, s in zip(row, self._scale)] for row in f]
            self.update = compile_update(self, self._n, fk_ticks, self.method, self._full, self._lims, self._rates,
                                         self._update_general, self._not_later, self._check,
                                         self._set_residual if redundant else None)

    def reset(self, pose=(0.0, 0.0, 0.0)) -> None:
        """Forget the previous sample; the next one is the new zero, at ``pose``."""
        p = as_components(pose, 3, "pose")
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise OmnikinError(f"pose: expected 3 finite numbers, got {pose!r}")
        self._x, self._y, self._th = float(p[0]), float(p[1]), float(wrap_angle(p[2]))
        self._t = None
        self._ticks = None
        self._steer = None
        self.twist = (0.0, 0.0, 0.0)
        self.residual = [0.0] * self._n
        self.samples = 0
        self.duplicates = 0
        self._warned = False

    @property
    def pose(self) -> tuple[float, float, float]:
        return (self._x, self._y, self._th)

    @property
    def t(self) -> Optional[float]:
        return self._t

    def update(self, t: float, ticks, steer=None) -> tuple[float, float, float]:
        """Feed one sample: time [s], raw counter readings of the encoded wheels in file
        order, and (steerable robots) their steering angles [rad]. Returns the pose."""
        return self._update_general(t, ticks, steer)

    def update_angles(self, t: float, angles, steer=None) -> tuple[float, float, float]:
        """Feed one sample of wheel angles [rad] (encoded wheels, file order)."""
        if self._full is not None:
            raise OmnikinError("update_angles works without counter wrap-around: create Odometry with counter_bits=None")
        return self.update(t, [a / s for a, s in zip(angles, self._scale)], steer)

    # --- slow paths (first sample, steering, errors) ---------------------------------
    def _update_general(self, t, ticks, steer):
        if len(ticks) != self._n:
            raise OdometryInputError(
                f"sample {self.samples}: expected {self._n} tick readings for wheels {self.wheel_names}, got {len(ticks)}")
        if self._ticks is None:
            return self._first(t, ticks, steer)
        dt = t - self._t
        if not dt > 0.0:
            return self._not_later(t, dt, ticks, steer)
        deltas = [a - b for a, b in zip(ticks, self._ticks)]
        if self._full is not None:
            half = self._full // 2
            deltas = [(d + half) % self._full - half for d in deltas]
        self._check(deltas, dt, ticks)
        s = self._check_steer(steer)
        dangle = np.array([d * k for d, k in zip(deltas, self._scale)], dtype=float)
        if self._steerable:
            mid = self._steer + 0.5 * wrap_angle(s - self._steer)
            fk = self.robot.fk(dangle, mid, self.wheel_names)
            self._steer = s
            self.residual = list(fk.residual / dt)
            a, b, phi = (float(v) for v in fk.twist)
        else:
            a, b, phi = (float(v) for v in self.robot.fk_matrix(None, self.wheel_names) @ dangle)
        self._ticks = tuple(ticks)
        return self._advance(t, dt, a, b, phi)

    def _first(self, t, ticks, steer):
        values = [float(v) for v in ticks]
        if not math.isfinite(float(t)) or not all(math.isfinite(v) for v in values):
            raise OdometryInputError(f"sample 0: non-finite time or tick reading (t={t!r}, ticks={list(ticks)!r})")
        if self._full is not None and not all(-self._full // 2 <= v < self._full for v in values):
            raise OdometryInputError(f"sample 0: tick reading outside the range of a {self.bits}-bit counter: {list(ticks)}")
        self._steer = self._check_steer(steer)
        self._t = float(t)
        self._ticks = tuple(ticks)
        self.samples = 1
        return self.pose

    def _not_later(self, t, dt, ticks, steer):
        if dt == 0.0 and tuple(ticks) == self._ticks:
            self.duplicates += 1
            if not self._warned:
                warnings.warn(f"odometry: duplicate sample at t={t!r} skipped (counted in .duplicates)",
                              RuntimeWarning, stacklevel=3)
                self._warned = True
            return self.pose
        if dt != dt:
            raise OdometryInputError(f"sample {self.samples}: non-finite timestamp {t!r}")
        what = "repeats" if dt == 0.0 else "goes back from"
        raise OdometryInputError(
            f"sample {self.samples}: timestamp {t!r} {what} the previous one {self._t!r} with different readings")

    def _check(self, deltas, dt, ticks):
        """Raise naming the sample and wheel if an increment cannot be integrated."""
        for j, d in enumerate(deltas):
            if d != d or d in (math.inf, -math.inf):
                raise OdometryInputError(
                    f"sample {self.samples}: non-finite tick reading {ticks[j]!r}, wheel {self.wheel_names[j]!r}")
            if self._full is not None and not -self._full // 2 <= ticks[j] < self._full:
                raise OdometryInputError(f"sample {self.samples}: tick reading {ticks[j]!r} outside the range "
                                         f"of a {self.bits}-bit counter, wheel {self.wheel_names[j]!r}")
            limit = self._lims[j] if self._rates[j] is None else 1.5 * self._rates[j] * dt + 2.0
            if abs(d) > limit:
                raise OdometryInputError(
                    f"sample {self.samples}: impossible jump of {d} ticks in {dt:.6g} s, wheel {self.wheel_names[j]!r} "
                    f"(faster than the wheel can turn, or half the counter range)")

    def _check_steer(self, steer):
        if not self._steerable:
            if steer is not None:
                raise OmnikinError(f"robot {self.robot.name!r} has no steerable wheel: do not pass steer")
            return None
        if steer is None:
            raise OmnikinError(f"robot {self.robot.name!r}: steerable wheels {self.robot.steer_names} need "
                               f"their steering angles (steer=...)")
        s = as_components(steer, len(self.robot.steerable), "steer")
        if not np.all(np.isfinite(s)):
            raise OdometryInputError(f"sample {self.samples}: non-finite steering angle {list(s)}")
        return s

    def _set_residual(self, deltas, a, b, phi, dt):
        dangle = np.array([d * k for d, k in zip(deltas, self._scale)], dtype=float)
        self.residual = list((dangle - self._rows @ np.array([a, b, phi])) / dt)
