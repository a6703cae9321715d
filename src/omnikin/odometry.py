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
from functools import cached_property
from typing import Optional

import numpy as np

from ._arrays import as_components, require_finite
from .encoders import first_bad, tick_increments
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
            f"encoder.ticks_per_rev on the measured wheels")
    robot.check_observable([w.name for w in wheels])
    return wheels


def mid_steer(steer: Optional[np.ndarray]) -> Optional[np.ndarray]:
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
    names = [w.name for w in wheels]
    a = np.asarray(angles, dtype=float)
    if a.ndim < 2 or a.shape[-1] != len(wheels) or a.shape[-2] < 1:
        raise OdometryInputError(f"angles: expected shape (..., N, {len(wheels)}) for wheels {names}, got {a.shape}")
    tt = np.asarray(t, dtype=float)
    if tt.shape[-1:] != a.shape[-2:-1]:
        raise OdometryInputError(f"t: expected {a.shape[-2]} timestamps to match angles {a.shape}, got shape {tt.shape}")
    first_bad(~np.isfinite(tt), "t: non-finite timestamp")
    first_bad(~np.isfinite(a), "angles: non-finite wheel angle", names)
    first_bad(np.diff(tt, axis=-1) <= 0, "t: timestamps must increase strictly (repeated or going back)", offset=1)
    return _integrate(robot, wheels, tt, np.diff(a, axis=-2), np.ones(len(wheels)), steer, method, start)


def _integrate(robot, wheels, t, delta, scale, steer, method, start) -> OdometryResult:
    """Forward kinematics of the increments ``delta * scale`` [rad], then pose integration."""
    check_method(method)
    names = [w.name for w in wheels]
    if robot.steerable:
        if steer is None:
            raise InputError(f"robot {robot.name!r}: steerable wheels {robot.steer_names} need steering "
                               f"angles (steer, shape (..., N, {len(robot.steerable)}))")
        s = as_components(steer, len(robot.steerable), "steer")
        want = delta.shape[:-2] + (delta.shape[-2] + 1, len(robot.steerable))
        if s.ndim < 2 or s.shape[-2] != want[-2] or np.broadcast_shapes(s.shape, want) != want:
            raise OdometryInputError(f"steer: expected shape {want} (one angle per steerable wheel and sample), "
                                     f"got {s.shape}")
        first_bad(~np.isfinite(s), "steer: non-finite steering angle", robot.steer_names)
        mid = mid_steer(s)
        f = robot.fk_matrix(mid, names)
        rows = robot.fk_rows(mid, names)
    else:
        if steer is not None:
            raise InputError(f"robot {robot.name!r} has no steerable wheel: do not pass steer")
        f = robot.fk_matrix(None, names)
        rows = robot.fk_rows(None, names)
    if robot.steerable:
        inc = np.einsum("...ij,...j->...i", f, _fk_input(delta, scale, f))
        comps = np.ascontiguousarray(np.swapaxes(inc, -1, -2))
        poses = integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :],
                                     None if start is None else _start(start), method)
    else:
        poses = _integrate_blocks(f * scale, delta, start, method)
    return OdometryResult(t, poses, delta, scale, f, rows)


def _start(start) -> np.ndarray:
    p = as_components(start, 3, "start")
    require_finite(p, "start")
    return p


def _integrate_blocks(f_ticks: np.ndarray, delta: np.ndarray, start, method: str) -> np.ndarray:
    """Poses from increments ``delta`` ``(..., M, n)`` and a constant FK ``f_ticks`` ``(3, n)``,
    :data:`CHUNK` samples at a time, each block starting where the previous one ended."""
    m = delta.shape[-2]
    start = None if start is None else _start(start)
    lead = delta.shape[:-2] if start is None else np.broadcast_shapes(delta.shape[:-2], start.shape[:-1])
    out = np.empty(lead + (m + 1, 3))
    pose = np.zeros(lead + (3,)) if start is None else np.broadcast_to(start, lead + (3,))
    out[..., 0, :] = pose
    for s0 in range(0, m, CHUNK):
        s1 = min(m, s0 + CHUNK)
        comps = np.matmul(f_ticks, np.swapaxes(delta[..., s0:s1, :], -1, -2))   # (..., 3, block)
        integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], pose, method,
                             out=out[..., s0:s1 + 1, :])
        pose = out[..., s1, :]
    return out
