"""Wheel odometry: a streaming estimator and batch odometry over arrays.

Per sample (``docs/conventions.md``): encoder ticks -> wheel angle increments
(:mod:`omnikin.odometry.increments`) -> body increment by forward kinematics
(:meth:`omnikin.kinematics.robot.Robot.fk`, constant over the sample) -> pose update by the
SE(2) exponential (:mod:`omnikin.odometry.integration`; ``euler`` and ``midpoint`` are there
for comparison only). Odometry uses the rolling wheels that have an ``encoder``
in the robot file; with steerable wheels the steering angles of each sample are
needed too, and each interval uses the mean of its two end angles.

The streaming estimator lives in :mod:`omnikin.odometry.streaming`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import overload

import numpy as np

from ..common.arrays import as_real_array, container_problem
from ..errors import InputError, OdometryInputError
from ..kinematics.robot import STEER_LIMIT_SLACK, Robot, steering_beyond
from ..kinematics.se2 import MAX_ANGLE, wrap_angle
from .counters import as_float, as_floats, as_reading_array, counter_readings
from .increments import Carry, block_increments, wheel_increments
from .integration import STEP_BOUNDS, check_method, check_start_pose, integrate_components, step_problem
from .plausibility import SAFETY, counter_rules
from .samples import Problem, problem_at, timestamp_problem


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

    Attributes
    ----------
    t : ndarray, shape (..., N)
        Sample times [s].
    poses : ndarray, shape (..., N, 3)
        Poses ``(x, y, theta)`` [m, m, rad] of the body frame in the world frame (``odom``),
        the first at the start pose.
    increments : ndarray, shape (..., N-1, 3)
        Body displacement ``(a, b, phi)`` [m, m, rad] of each interval, in the body axes at
        its start.
    residual : ndarray, shape (..., N-1, n_rows)
        Forward-kinematics residual [rad/s] of each interval: one row per encoded wheel, then
        one per steerable wheel.
    twists : ndarray, shape (..., N-1, 3)
        Mean body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] of each interval.
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
    from ..kinematics.linalg import rank

    return rows.shape[-2] > rank(rows @ robot.admissible_basis)


def _fk_input(delta, scale, fk) -> np.ndarray:
    """Wheel angle increments ``delta * scale`` [rad], padded with zeros for the steering rows of ``fk``."""
    angles = delta * scale
    extra = fk.shape[-1] - angles.shape[-1]
    if extra:
        angles = np.concatenate([angles, np.zeros(angles.shape[:-1] + (extra,))], axis=-1)
    return angles


def fk_coefficients(f: np.ndarray, scale) -> list[list[float]]:
    """The rows (a, b, phi) of a constant forward-kinematics operator ``f`` ``(3, n)`` times
    ``scale`` per wheel, as Python floats: the body increment per tick (``scale``: rad per tick)
    or per radian (ones). The streaming kernels have them written in; batch odometry uses the
    same numbers."""
    return [[float(v) * float(k) for v, k in zip(row[: len(scale)], scale, strict=True)] for row in f]


def body_components(coefficients: list[list[float]], delta: np.ndarray) -> list[np.ndarray]:
    """Body increments ``a``, ``b``, ``phi`` ``(..., m)`` [m, m, rad] of wheel increments ``delta``
    ``(..., m, n)`` with the constant :func:`fk_coefficients`, each summed over the wheels in their
    order and without the terms of zero coefficient: the arithmetic of the streaming kernel
    (``omnikin.odometry._stream_kernel._fk_lines``), so that batch and streaming odometry compute the same
    body increments to the bit (and refuse the same steps, :func:`omnikin.odometry.integration.step_problem`)."""
    columns = [delta[..., j] for j in range(delta.shape[-1])]
    out = []
    for row in coefficients:
        acc = None
        for c, column in zip(row, columns, strict=True):
            if c != 0.0:
                if acc is None:
                    acc = c * column
                else:
                    acc += c * column
        out.append(np.zeros(delta.shape[:-1]) if acc is None else acc)
    return out


def body_steps(coefficients: list[list[float]], delta: np.ndarray) -> np.ndarray:
    """:func:`body_components` as one array ``(..., m, 3)``."""
    return np.stack(body_components(coefficients, delta), axis=-1)


def steered_steps(f: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Body increments ``(..., 3)`` = ``f`` ``(..., 3, k)`` times ``angles`` ``(..., k)``, summed
    in the order of the columns (one interval in streaming odometry, all of them in batch: the
    same arithmetic)."""
    acc = f[..., 0] * angles[..., None, 0]
    for j in range(1, f.shape[-1]):
        acc = acc + f[..., j] * angles[..., None, j]
    return acc


def step_problem_at(steps: np.ndarray, dt: np.ndarray, offset: int) -> Problem | None:
    """The first interval (row ``r`` is sample ``offset + 1 + r``) whose body increment in
    ``steps`` ``(..., m, 3)`` over ``dt`` ``(..., m)`` [s] is refused by
    :func:`omnikin.odometry.integration.step_problem`, as a :class:`~omnikin.odometry.samples.Problem`."""
    with np.errstate(invalid="ignore"):
        beyond = np.any(~(np.abs(steps) <= STEP_BOUNDS), axis=-1)

    def describe(row, trial, _):
        lead = steps.shape[:-2]
        index = tuple(i if n > 1 else 0 for i, n in zip(trial[len(trial) - len(lead) :], lead, strict=True))
        a, b, phi = (float(v) for v in steps[index + (row,)])
        lead_dt = dt.shape[:-1]
        at = tuple(i if n > 1 else 0 for i, n in zip(trial[len(trial) - len(lead_dt) :], lead_dt, strict=True))
        return step_problem(a, b, phi, float(dt[at + (row,)])) or ""

    return problem_at(beyond, False, offset + 1, "motion", describe)


class StepCheck:
    """The ``motion`` check of :func:`omnikin.odometry.increments.block_increments` for robots without
    steerable wheels: the first interval whose body increment (:func:`body_steps`) is beyond
    the bounds of one step. A block whose longest interval lets no wheel reach them (every
    increment is within its jump limit there) is passed without computing them."""

    def __init__(self, coefficients: list[list[float]], rules, unit: str):
        self.coefficients = coefficients
        self.rules = rules
        self.unit = unit

    def __call__(self, dt: np.ndarray, delta: np.ndarray, offset: int) -> Problem | None:
        longest = float(np.max(dt))
        limits = [r.limit(longest) if self.unit == "ticks" else r.angle_limit(longest) for r in self.rules]
        reach = [sum(abs(c) * lim for c, lim in zip(row, limits, strict=True) if c) for row in self.coefficients]
        if all(x <= bound * SAFETY for x, bound in zip(reach, STEP_BOUNDS, strict=True)):
            return None
        with np.errstate(over="ignore", invalid="ignore"):
            return step_problem_at(body_steps(self.coefficients, delta), dt, offset)


class SteeredSteps:
    """The ``motion`` check of :func:`omnikin.odometry.increments.block_increments` for robots with steerable
    wheels: the operator of each interval at its mean steering, the body increments
    (:func:`steered_steps`), kept block by block for the integration, and the first beyond the
    bounds of one step."""

    def __init__(self, robot: Robot, names, steer: np.ndarray, scale):
        self.robot, self.names, self.scale = robot, names, scale
        with np.errstate(invalid="ignore", over="ignore"):  # bad angles: refused at their sample
            self.mid = mid_steer(steer)
        self.blocks: list[tuple[np.ndarray, np.ndarray]] = []

    def __call__(self, dt: np.ndarray, delta: np.ndarray, offset: int) -> Problem | None:
        m = delta.shape[-2]
        f = self.robot.fk_matrix(self.mid[..., offset : offset + m, :], self.names)  # (3, k) if constant
        angles = _fk_input(delta, self.scale, f)
        with np.errstate(over="ignore", invalid="ignore"):
            steps = steered_steps(f if f.ndim > 2 else f[..., None, :, :], angles)
        self.blocks.append((angles, steps))
        return step_problem_at(steps, dt, offset)

    def joined(self) -> tuple[np.ndarray, np.ndarray]:
        """The wheel angles ``(..., N - 1, k)`` [rad] and body increments ``(..., N - 1, 3)`` of every
        interval."""
        if len(self.blocks) == 1:
            return self.blocks[0]
        angles, steps = zip(*self.blocks, strict=True)
        return np.concatenate(angles, axis=-2), np.concatenate(steps, axis=-2)


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
    max_wheel_accel=None,
) -> OdometryResult:
    """Odometry of whole logs: ``ticks`` ``(..., N, n_enc)`` at times ``t`` ``(..., N)``.

    Leading axes (trials) broadcast. ``steer`` ``(..., N, n_steer)`` [rad] is needed
    for robots with steerable wheels. The first sample is the zero of the ticks and
    sits at ``start`` (default origin; :func:`omnikin.odometry.integration.check_start_pose`). Readings of
    any integer type are exact (see :func:`omnikin.odometry.counters.counter_readings`);
    ``counter_bits`` (else each wheel's ``encoder.counter_bits``), ``max_jump`` [ticks],
    ``max_wheel_speed`` [rad/s] and ``max_wheel_accel`` [rad/s^2] are the counter, jump and
    change-of-speed rules of :mod:`omnikin.odometry.plausibility`; the body increment of an interval must lie
    within :func:`omnikin.odometry.integration.step_problem`. The earliest bad sample raises
    :class:`OdometryInputError` with its index in ``.sample`` (the same sample the streaming
    estimator refuses). The increments and twists are the streaming estimator's (to the bit
    without steerable wheels: :func:`body_components`), the poses agree with its poses to
    rounding (cumulative sums here, one step at a time there; ``docs/conventions.md``, "Batch
    and streaming odometry agree").

    Per interval: wheel angle increments -> body increment by forward kinematics, constant over
    the interval (:meth:`omnikin.kinematics.robot.Robot.fk`; with steerable wheels at the mean of the two end
    steering angles) -> pose update by the SE(2) exponential (:mod:`omnikin.odometry.integration`).

    Parameters
    ----------
    robot : Robot
        The robot; odometry reads its rolling wheels that have an ``encoder``, in file order
        (``n_enc`` of them), which must observe every motion.
    t : array_like, shape (..., N)
        Sample times [s], strictly increasing along the last axis.
    ticks : array_like, shape (..., N, n_enc)
        Raw counter readings of the encoded wheels (integers of any type, exact; or floats).
    steer : array_like, shape (..., N, n_steer), optional
        Steering angles [rad] of the steerable wheels at each sample; required when the robot
        has any, refused otherwise.
    method : {"exact", "midpoint", "euler"}, default "exact"
        Pose integration; ``midpoint`` and ``euler`` are for comparison only.
    counter_bits : int, optional
        Counter width (2 .. 64) for every wheel; default each wheel's ``encoder.counter_bits``.
    start : array_like, shape (..., 3), optional
        Pose ``(x, y, theta)`` [m, m, rad] of the first sample in the world frame; default the
        origin.
    max_jump : float, optional
        Largest change [ticks] of a wheel between two samples; replaces the bound from the
        wheel speed.
    max_wheel_speed : float, optional
        Wheel speed [rad/s] that, with the margin :data:`~omnikin.odometry.plausibility.JUMP_MARGIN`, bounds
        each wheel's change between two samples; default each wheel's ``max_speed``, else
        :data:`~omnikin.odometry.plausibility.DEFAULT_RIM_SPEED` at its rim.
    max_wheel_accel : float, optional
        Wheel acceleration [rad/s^2] that, with the same margin, bounds each wheel's change of
        speed between two intervals; default :data:`~omnikin.odometry.plausibility.DEFAULT_RIM_ACCEL` at its
        rim.

    Returns
    -------
    OdometryResult
        Times ``(..., N)``, poses ``(..., N, 3)``, increments and residuals ``(..., N-1, ...)``.

    Raises
    ------
    OdometryInputError
        The earliest sample that cannot be integrated (its index in ``.sample``).
    InputError
        A robot without encoders or whose encoders do not observe every motion, an unknown
        ``method``, a bad ``start`` or rule value.
    """
    wheels = encoded_wheels(robot)
    rules = counter_rules(wheels, counter_bits, max_jump, max_wheel_speed, max_wheel_accel)
    names = [w.name for w in wheels]
    tk = counter_readings(ticks, names)
    tt, pending = _timestamps(t, tk, "ticks", names)
    scale = np.array([r.rad_per_tick for r in rules])
    check_method(method)
    start_pose = None if start is None else check_start_pose(start)
    if robot.steerable:
        return _steered_odometry(robot, names, rules, tt, tk, "ticks", scale, pending, steer, method, start_pose)
    _no_steer(robot, steer)
    f = robot.fk_matrix(None, names)
    rows = robot.fk_rows(None, names)
    out = _pose_array(tk.shape[:-2], tt.shape[:-1], tk.shape[-2], start_pose)
    lead, m = out.shape[:-2], tk.shape[-2] - 1
    inc = np.empty(lead + (m, 3))
    residual = np.empty(lead + (m, rows.shape[-2])) if _redundant(robot, rows) else None
    pose = out[..., 0, :]
    check = StepCheck(fk_coefficients(f, scale), rules, "ticks")
    carry = Carry()
    for s0 in range(0, m, CHUNK):
        s1 = min(m, s0 + CHUNK)
        dt, d = block_increments(
            rules, tt[..., s0 : s1 + 1], tk[..., s0 : s1 + 1, :], s0, carry, "ticks", pending, check
        )
        a, b, phi = body_components(check.coefficients, d)
        integrate_components(a, b, phi, pose, method, out=out[..., s0 : s1 + 1, :])
        inc[..., s0:s1, 0], inc[..., s0:s1, 1], inc[..., s0:s1, 2] = a, b, phi
        if residual is not None:
            residual[..., s0:s1, :] = _residual(_fk_input(d, scale, f), rows, inc[..., s0:s1, :], dt)
        pose = out[..., s1, :]
    if pending is not None:  # a single sample: no block
        raise pending.error()
    if residual is None:
        residual = np.broadcast_to(np.zeros(()), lead + (m, rows.shape[-2]))
    return OdometryResult(tt, out, inc, residual)


def batch_odometry_from_angles(
    robot: Robot,
    t,
    angles,
    *,
    steer=None,
    method: str = "exact",
    start=None,
    max_jump=None,
    max_wheel_speed=None,
    max_wheel_accel=None,
) -> OdometryResult:
    """Like :func:`batch_odometry` but from wheel angles ``(..., N, n_enc)`` [rad] (no counters;
    the same physical rules on speed and its changes).

    Parameters
    ----------
    robot : Robot
        The robot; odometry reads its rolling wheels that have an ``encoder``, in file order.
    t : array_like, shape (..., N)
        Sample times [s], strictly increasing along the last axis.
    angles : array_like, shape (..., N, n_enc)
        Wheel angles [rad] of the encoded wheels (they do not wrap), positive when the wheel
        drives its hub along its drive direction.
    steer : array_like, shape (..., N, n_steer), optional
        Steering angles [rad]; required when the robot has steerable wheels.
    method : {"exact", "midpoint", "euler"}, default "exact"
        Pose integration.
    start : array_like, shape (..., 3), optional
        Pose ``(x, y, theta)`` [m, m, rad] of the first sample; default the origin.
    max_jump, max_wheel_speed, max_wheel_accel : float, optional
        The rules of :func:`batch_odometry` (``max_jump`` in ticks of each wheel's encoder; the
        change-of-speed rule applies only with an explicit ``max_wheel_accel``).

    Returns
    -------
    OdometryResult
        As :func:`batch_odometry`.

    Raises
    ------
    OdometryInputError
        The earliest sample that cannot be integrated (its index in ``.sample``).
    InputError
        As :func:`batch_odometry`.
    """
    wheels = encoded_wheels(robot)
    rules = counter_rules(wheels, None, max_jump, max_wheel_speed, max_wheel_accel)
    names = [w.name for w in wheels]
    a = _angle_array(angles, names)
    tt, pending = _timestamps(t, a, "angles", names)
    check_method(method)
    start_pose = None if start is None else check_start_pose(start)
    ones = np.ones(len(wheels))
    if robot.steerable:
        return _steered_odometry(robot, names, rules, tt, a, "rad", ones, pending, steer, method, start_pose)
    _no_steer(robot, steer)
    f = robot.fk_matrix(None, names)
    check = StepCheck(fk_coefficients(f, ones), rules, "rad")
    d = wheel_increments(rules, tt, a, CHUNK, "rad", pending, check)
    out = _pose_array(d.shape[:-2], tt.shape[:-1], d.shape[-2] + 1, start_pose)
    comps = body_components(check.coefficients, d)
    integrate_components(comps[0], comps[1], comps[2], out[..., 0, :], method, out=out)
    inc = np.stack(comps, axis=-1)
    rows = robot.fk_rows(None, names)
    return OdometryResult(tt, out, inc, _residual(_fk_input(d, ones, f), rows, inc, np.diff(tt, axis=-1)))


def _steered_odometry(robot, names, rules, t, values, unit: str, scale, pending, steer, method, start):
    """Batch odometry of a robot with steerable wheels: readings ``values`` ``(..., N, n_enc)``
    [``unit``: ticks or rad, times ``scale`` rad per unit] at times ``t`` ``(..., N)``, steering
    ``steer`` ``(..., N, n_steer)`` [rad]; the first problem (timestamps, steering, readings,
    steps) raised at its sample."""
    lead = np.broadcast_shapes(values.shape[:-2], t.shape[:-1])
    s, steering = _steering(robot, steer, lead, values.shape[-2])
    steps = SteeredSteps(robot, names, s, scale)
    wheel_increments(rules, t, values, CHUNK, unit, _earliest(pending, steering), steps)
    return _integrate_steered(robot, names, t, steps, lead, method, start)


def _earliest(*problems: Problem | None) -> Problem | None:
    """The first of the problems found before the increments (timestamps, steering), or None."""
    found = [p for p in problems if p is not None]
    return min(found) if found else None


def _angle_array(angles, names) -> np.ndarray:
    """Wheel angles ``(..., N, n)`` [rad] as float64 (+-inf beyond the float range: refused at
    their sample as non-finite); bools, text and unordered containers refused."""
    a = as_reading_array(angles, names, "angles")
    if a.dtype.kind not in "iufO":
        raise OdometryInputError(f"angles: expected real numbers [rad] for wheels {names}, got dtype {a.dtype}")
    try:
        return as_floats(a)
    except (TypeError, ValueError):
        raise OdometryInputError(f"angles: expected real numbers [rad] for wheels {names}") from None


def _timestamps(t, readings: np.ndarray, what: str, names) -> tuple[np.ndarray, Problem | None]:
    """Timestamps as float64 ``(..., N)`` after checking the shapes of ``readings`` ``(..., N, n)``,
    and the first timestamp that is no number as a pending :class:`~omnikin.odometry.samples.Problem`
    (it reads as 0 here; refused at its sample, as the streaming estimator refuses it). Integers
    beyond the float range read as +-inf (refused at their sample as non-finite)."""
    n = len(names)
    if readings.ndim < 2 or readings.shape[-1] != n or readings.shape[-2] < 1:
        raise OdometryInputError(f"{what}: expected shape (..., N, {n}) for wheels {names}, got {readings.shape}")
    why = None if isinstance(t, np.ndarray) else container_problem(t)
    if why is not None:
        raise OdometryInputError(f"t: {why}; give the timestamps as a list, tuple or array")
    pending = None
    try:
        tt = as_real_array(t, "t", OdometryInputError)
    except OdometryInputError:
        located = _located_times(t)
        if located is None:
            raise
        tt, pending = located
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
    return tt, pending


def _located_times(t) -> tuple[np.ndarray, Problem | None] | None:
    """Timestamps that are not all floats: as float64 (beyond the float range +-inf, no number 0)
    and the first that is no number (:func:`omnikin.odometry.samples.timestamp_problem`), or None if
    ``t`` is not a rectangular array of scalars (the caller's message stands)."""
    try:
        obj = np.array(t, dtype=object)
    except (TypeError, ValueError):
        return None
    flat = obj.reshape(-1)
    if obj.ndim == 0 or any(container_problem(v) is None and not isinstance(v, np.generic) for v in flat):
        return None  # nested unevenly: not a table of timestamps
    problems = [timestamp_problem(v) for v in flat]
    values = np.array([0.0 if p else as_float(v) for p, v in zip(problems, flat, strict=True)]).reshape(obj.shape)
    bad = np.array([p is not None for p in problems]).reshape(obj.shape)
    pending = problem_at(bad, False, 0, "time", lambda row, trial, _: f"t: {problems[_flat_index(obj, trial, row)]}")
    return values, pending


def _flat_index(array: np.ndarray, trial: tuple, row: int) -> int:
    return int(np.ravel_multi_index(trial + (row,), array.shape))


def _no_steer(robot, steer) -> None:
    if steer is not None:
        raise InputError(f"robot {robot.name!r} has no steerable wheel: do not pass steer")


def _pose_array(lead_a, lead_b, n: int, start: np.ndarray | None) -> np.ndarray:
    """Empty poses ``(..., n, 3)`` with the first pose set to ``start`` (default origin)."""
    lead = np.broadcast_shapes(lead_a, lead_b, () if start is None else start.shape[:-1])
    out = np.empty(lead + (n, 3))
    out[..., 0, :] = 0.0 if start is None else start
    return out


def steer_bounds(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest steering angle ``(n_steer,)`` [rad] of a sample: what the model takes
    (:meth:`omnikin.kinematics.robot.Robot.fk_matrix`: :attr:`~omnikin.kinematics.robot.Robot.steer_limits` with
    their round-off slack, or +-:data:`~omnikin.kinematics.se2.MAX_ANGLE` for a wheel that turns all
    the way round), so that odometry refuses a bad angle at its sample rather than deep in the
    kinematics."""
    lower, upper = robot.steer_limits
    return np.maximum(lower - STEER_LIMIT_SLACK, -MAX_ANGLE), np.minimum(upper + STEER_LIMIT_SLACK, MAX_ANGLE)


def steer_problem(robot: Robot, k: int, value: float) -> str | None:
    """Why steering angle ``value`` [rad] of steerable wheel ``k`` cannot be used (None if it
    can): not finite, or outside :func:`steer_bounds`."""
    lower, upper = steer_bounds(robot)
    if lower[k] <= value <= upper[k]:
        return None
    name = robot.steer_names[k]
    if not math.isfinite(value):
        return f"steer: non-finite steering angle {value!r}, wheel {name!r}"
    return f"steer: {steering_beyond(name, value, lower[k], upper[k])}"


def _steering(robot, steer, lead: tuple, n: int) -> tuple[np.ndarray, Problem | None]:
    """Steering angles ``(..., N, n_steer)`` [rad] of steerable robots, checked for shape, and
    the first sample with a bad angle as a pending :class:`~omnikin.odometry.samples.Problem`."""
    names = robot.steer_names
    if steer is None:
        raise InputError(
            f"robot {robot.name!r}: steerable wheels {names} need steering "
            f"angles (steer, shape (..., N, {len(robot.steerable)}))"
        )
    as_reading_array(steer, names, "steer")  # unordered containers and bad rows, named by sample
    s = as_real_array(steer, "steer", OdometryInputError)  # then real numbers only
    want = lead + (n, len(names))
    if s.ndim < 2 or s.shape[-2:] != want[-2:] or np.broadcast_shapes(s.shape, want) != want:
        raise OdometryInputError(
            f"steer: expected shape {want} (one angle per steerable wheel and sample), got {s.shape}"
        )
    lower, upper = steer_bounds(robot)
    pending = problem_at(
        ~((s >= lower) & (s <= upper)),
        True,
        0,
        "steer",
        lambda row, trial, j: steer_problem(robot, j, float(s[trial + (row, j)])) or "",
    )
    return s, pending


def _integrate_steered(robot, names, t, steps: SteeredSteps, lead: tuple, method, start) -> OdometryResult:
    """Pose integration of the body increments of each interval (:class:`SteeredSteps`, at the
    mean steering of its two ends), with the residual of the fitted rows. ``lead``: the
    leading shape of the readings and timestamps."""
    if not steps.blocks:  # a single sample: no interval
        steps(np.zeros(t.shape[:-1] + (0,)), np.zeros(lead + (0, len(names))), 0)
    angles, inc = steps.joined()
    rows = robot.fk_rows(steps.mid, names)
    comps = np.ascontiguousarray(np.swapaxes(inc, -1, -2))
    poses = integrate_components(comps[..., 0, :], comps[..., 1, :], comps[..., 2, :], start, method)
    return OdometryResult(t, poses, inc, _residual(angles, rows, inc, np.diff(t, axis=-1)))
