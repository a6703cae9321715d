"""Wheel odometry: a streaming estimator and batch odometry over arrays.

Per sample (``docs/conventions.md``): encoder ticks -> wheel angle increments
(:mod:`omnikin.encoders`) -> body increment by forward kinematics
(:meth:`omnikin.model.Robot.fk`, constant over the sample) -> pose update by the
SE(2) exponential (:mod:`omnikin.integration`; ``euler`` and ``midpoint`` are there
for comparison only). Odometry uses the rolling wheels that have an ``encoder``
in the robot file; with steerable wheels the steering angles of each sample are
needed too, and each interval uses the mean of its two end angles.

The streaming estimator lives in :mod:`omnikin.streaming`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import overload

import numpy as np

from ._arrays import as_components, require_finite
from .encoders import (
    check_angle_jumps,
    check_times,
    checked_increments,
    counter_readings,
    counter_rules,
    first_bad,
    wheel_increments,
)
from .errors import InputError, OdometryInputError
from .geometry import wrap_angle
from .integration import check_method, integrate_components
from .model import Robot


def encoded_wheels(robot: Robot):
    """The rolling wheels with an encoder, in file order; checks they observe all motion."""
    wheels = list(robot.encoded)
    if not wheels:
        raise InputError(
            f"robot {robot.name!r}: no wheel has an 'encoder' entry; odometry from ticks needs "
            f"encoder.ticks_per_rev on the measured wheels"
        )
    robot.check_observable([w.name for w in wheels])
    return wheels


@overload
def mid_steer(steer: None) -> None: ...


@overload
def mid_steer(steer: np.ndarray) -> np.ndarray: ...


def mid_steer(steer: np.ndarray | None) -> np.ndarray | None:
    """Interval steering: circular mean of consecutive samples ``(..., N-1, n_steer)``."""
    if steer is None:
        return None
    return steer[..., :-1, :] + 0.5 * wrap_angle(np.diff(steer, axis=-2))


CHUNK = 1 << 14
"""Samples checked and integrated per block: the temporaries stay in cache and are the only
allocations besides the poses (see docs/performance.md)."""


@dataclass(frozen=True)
class OdometryResult:
    """Batch odometry: ``poses`` ``(..., N, 3)`` at the times ``t`` ``(..., N)``.

    ``increments`` ``(..., N-1, 3)`` are the body displacements of each interval [m, m, rad];
    ``twists`` their mean twists [m/s, m/s, rad/s]; ``residual`` ``(..., N-1, n_rows)`` the
    forward kinematics residual [rad/s] (zero for a square, full-rank layout: then a
    read-only array of zeros that takes no memory). All are computed with the poses, from
    the readings as they were at the call: changing the input array afterwards changes nothing.
    """

    t: np.ndarray
    poses: np.ndarray
    increments: np.ndarray
    residual: np.ndarray

    @property
    def twists(self) -> np.ndarray:
        return self.increments / np.diff(self.t, axis=-1)[..., None]


def _residual(angles: np.ndarray, rows: np.ndarray, increments: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Forward-kinematics residual ``(angles - A increments) / dt`` [rad/s] (``angles`` padded)."""
    pred = np.einsum("...ij,...j->...i", rows, increments)
    return (angles - pred) / dt[..., None]


def _redundant(robot: Robot, rows: np.ndarray) -> bool:
    """More fitted rows than the motions they observe: the residual can be non-zero."""
    from .linalg import rank

    return rows.shape[-2] > rank(rows @ robot.admissible_basis)


def _fk_input(delta, scale, fk) -> np.ndarray:
    """Wheel angle increments ``delta * scale`` [rad], padded with zeros for the steering rows of ``fk``."""
    angles = delta * scale
    extra = fk.shape[-1] - angles.shape[-1]
    if extra:
        angles = np.concatenate([angles, np.zeros(angles.shape[:-1] + (extra,))], axis=-1)
    return angles


def batch_odometry(
    robot: Robot,
    t,
    ticks,
    *,
    steer=None,
    method: str = "exact",
    counter_bits: int | None = None,
    start=None,
    max_jump=None,
    max_wheel_speed=None,
) -> OdometryResult:
    """Odometry of whole logs: ``ticks`` ``(..., N, n_enc)`` at times ``t`` ``(..., N)``.

    Leading axes (trials) broadcast. ``steer`` ``(..., N, n_steer)`` [rad] is needed
    for robots with steerable wheels. The first sample is the zero of the ticks and
    sits at ``start`` (default origin). Readings of any integer type are exact (see
    :func:`omnikin.encoders.counter_readings`); ``counter_bits`` (else each wheel's
    ``encoder.counter_bits``), ``max_jump`` [ticks] and ``max_wheel_speed`` [rad/s] are the
    counter and jump rules of :mod:`omnikin.encoders`. Every bad sample raises
    :class:`OdometryInputError` with its index in ``.sample``.
    """
    wheels = encoded_wheels(robot)
    rules = counter_rules(wheels, counter_bits, max_jump, max_wheel_speed)
    names = [w.name for w in wheels]
    tk = counter_readings(ticks, names)
    tt = _timestamps(t, tk, "ticks", names)
    scale = np.array([r.rad_per_tick for r in rules])
    check_method(method)
    delta = partial(wheel_increments, rules, tt, tk, CHUNK)
    if robot.steerable:
        return _integrate(robot, wheels, tt, delta, scale, steer, method, start)
    _no_steer(robot, steer)
    f = robot.fk_matrix(None, names)
    rows = robot.fk_rows(None, names)
    out = _pose_array(tk.shape[:-2], tt.shape[:-1], tk.shape[-2], start)
    lead, m = out.shape[:-2], tk.shape[-2] - 1
    inc = np.empty(lead + (m, 3))
    residual = np.empty(lead + (m, rows.shape[-2])) if _redundant(robot, rows) else None
    pose = out[..., 0, :]
    f_ticks = f * scale
    for s0 in range(0, m, CHUNK):
        s1 = min(m, s0 + CHUNK)
        dt = check_times(tt[..., s0 : s1 + 1], s0)
        d = checked_increments(rules, tk[..., s0 : s1 + 1, :], dt, s0)
        comps = np.matmul(f_ticks, np.swapaxes(d, -1, -2))  # (..., 3, block)
        integrate_components(
            comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], pose, method, out=out[..., s0 : s1 + 1, :]
        )
        inc[..., s0:s1, :] = np.swapaxes(comps, -1, -2)
        if residual is not None:
            residual[..., s0:s1, :] = _residual(_fk_input(d, scale, f), rows, inc[..., s0:s1, :], dt)
        pose = out[..., s1, :]
    if residual is None:
        residual = np.broadcast_to(np.zeros(()), lead + (m, rows.shape[-2]))
    return OdometryResult(tt, out, inc, residual)


def batch_odometry_from_angles(
    robot: Robot, t, angles, *, steer=None, method: str = "exact", start=None, max_jump=None, max_wheel_speed=None
) -> OdometryResult:
    """Like :func:`batch_odometry` but from wheel angles ``(..., N, n_enc)`` [rad] (no counters;
    the same physical jump rule)."""
    wheels = encoded_wheels(robot)
    rules = counter_rules(wheels, None, max_jump, max_wheel_speed)
    names = [w.name for w in wheels]
    a = np.asarray(angles, dtype=float)
    tt = _timestamps(t, a, "angles", names)
    first_bad(~np.isfinite(a), "angles: non-finite wheel angle", names)
    dt = check_times(tt, 0)
    delta = np.diff(a, axis=-2)
    check_angle_jumps(rules, delta, dt)
    return _integrate(robot, wheels, tt, lambda: delta, np.ones(len(wheels)), steer, method, start)


def _timestamps(t, readings: np.ndarray, what: str, names) -> np.ndarray:
    """Timestamps as float64 ``(..., N)`` after checking the shapes of ``readings`` ``(..., N, n)``."""
    n = len(names)
    if readings.ndim < 2 or readings.shape[-1] != n or readings.shape[-2] < 1:
        raise OdometryInputError(f"{what}: expected shape (..., N, {n}) for wheels {names}, got {readings.shape}")
    tt = np.asarray(t, dtype=float)
    if tt.shape[-1:] != readings.shape[-2:-1]:
        raise OdometryInputError(
            f"t: expected {readings.shape[-2]} timestamps to match {what} {readings.shape}, got shape {tt.shape}"
        )
    try:
        np.broadcast_shapes(tt.shape[:-1], readings.shape[:-2])
    except ValueError:
        raise OdometryInputError(
            f"t: leading shape {tt.shape[:-1]} does not broadcast with {what} {readings.shape[:-2]}"
        ) from None
    return tt


def _no_steer(robot, steer) -> None:
    if steer is not None:
        raise InputError(f"robot {robot.name!r} has no steerable wheel: do not pass steer")


def _pose_array(lead_a, lead_b, n: int, start) -> np.ndarray:
    """Empty poses ``(..., n, 3)`` with the first pose set to ``start`` (default origin)."""
    start = None if start is None else _start(start)
    lead = np.broadcast_shapes(lead_a, lead_b, () if start is None else start.shape[:-1])
    out = np.empty(lead + (n, 3))
    out[..., 0, :] = 0.0 if start is None else start
    return out


def _integrate(robot, wheels, t, delta, scale, steer, method, start) -> OdometryResult:
    """Forward kinematics of the increments ``delta() * scale`` [rad] (steerable robots: per
    interval), then pose integration."""
    check_method(method)
    names = [w.name for w in wheels]
    if not robot.steerable:
        _no_steer(robot, steer)
        f = robot.fk_matrix(None, names)
        d = delta()
        out = _pose_array(d.shape[:-2], t.shape[:-1], d.shape[-2] + 1, start)
        comps = np.matmul(f * scale, np.swapaxes(d, -1, -2))
        integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], out[..., 0, :], method, out=out)
        inc = np.swapaxes(comps, -1, -2)
        rows = robot.fk_rows(None, names)
        return OdometryResult(t, out, inc, _residual(_fk_input(d, scale, f), rows, inc, np.diff(t, axis=-1)))
    if steer is None:
        raise InputError(
            f"robot {robot.name!r}: steerable wheels {robot.steer_names} need steering "
            f"angles (steer, shape (..., N, {len(robot.steerable)}))"
        )
    d = delta()
    s = as_components(steer, len(robot.steerable), "steer")
    want = d.shape[:-2] + (d.shape[-2] + 1, len(robot.steerable))
    if s.ndim < 2 or s.shape[-2] != want[-2] or np.broadcast_shapes(s.shape, want) != want:
        raise OdometryInputError(
            f"steer: expected shape {want} (one angle per steerable wheel and sample), got {s.shape}"
        )
    first_bad(~np.isfinite(s), "steer: non-finite steering angle", robot.steer_names)
    mid = mid_steer(s)
    f = robot.fk_matrix(mid, names)
    rows = robot.fk_rows(mid, names)
    angles = _fk_input(d, scale, f)
    inc = np.einsum("...ij,...j->...i", f, angles)
    comps = np.ascontiguousarray(np.swapaxes(inc, -1, -2))
    poses = integrate_components(
        comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], None if start is None else _start(start), method
    )
    return OdometryResult(t, poses, inc, _residual(angles, rows, inc, np.diff(t, axis=-1)))


def _start(start) -> np.ndarray:
    p = as_components(start, 3, "start")
    require_finite(p, "start")
    return p
