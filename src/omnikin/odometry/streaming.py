"""Streaming odometry: :class:`Odometry`, fed one sample at a time (the core's only mutable state).

Per sample (``docs/conventions.md``): counter increments (:mod:`omnikin.odometry.counters` for readings and
wrap-around, :mod:`omnikin.odometry.plausibility` for jumps), forward kinematics with the robot's
constant (or, with steerable wheels, per-interval) operator, and the pose update of
:mod:`omnikin.odometry.integration`. Without steerable wheels a generated kernel
(:mod:`omnikin.odometry._stream_kernel`), a pure function of the state, takes every sample it has no
doubt about; the general path here takes the rest and either integrates it as the kernel
would, to the bit (the kernel's forward kinematics and pose update are its own), or raises.

The whole estimate lives in one immutable state tuple replaced on success, so an update
that raises leaves the estimator exactly as it was, and estimators copy
(:func:`copy.deepcopy`) and pickle as plain data. "Sample k" in messages counts every
sample fed so far that was accepted or skipped as a duplicate; the error carries it in
``.sample``.
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from ..common.arrays import as_real_array, container_problem
from ..common.messages import shorten
from ..errors import InputError, OdometryInputError
from ..kinematics.linalg import rank
from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle
from . import _stream_kernel as kernel
from ._stream_kernel import (
    KIND_ANGLES,
    KIND_NONE,
    KIND_TICKS,
    S_COUNT,
    S_DT,
    S_POSE,
    S_READ,
    state_kind,
    state_time,
)
from .batch import encoded_wheels, fk_coefficients, mid_steer, steer_problem, steered_steps
from .counters import as_float, exact_increment, exact_value, in_counter_range, show_number
from .integration import check_method, check_start_pose, step_problem
from .plausibility import counter_rules
from .samples import timestamp_problem

_WHAT = {KIND_TICKS: "tick reading", KIND_ANGLES: "wheel angle"}

STATE_FORMAT = 2
"""Version of the pickled state of :class:`Odometry` (its attributes and the layout of the state
tuple, :data:`omnikin.odometry._stream_kernel.S_POSE`); a pickle of another version is refused on load
rather than failing later or integrating wrongly. Pickles without it are format 1 (tick readings
kept as floats). Raise it whenever the state changes."""


def _times(t: float, kind: int) -> tuple[float, float]:
    """The two time slots of the state (see :data:`omnikin.odometry._stream_kernel.S_POSE`)."""
    return (t, math.nan) if kind == KIND_TICKS else (math.nan, t)


def _kept(values: tuple, kind: int) -> tuple:
    """Readings as the state keeps them: tick readings as exact numbers (ints, or the Fraction
    a non-integral float holds: :func:`omnikin.odometry.counters.exact_value`), so that the kernel's
    ``v - p`` of the next integer reading is exact; wheel angles as floats."""
    return tuple(exact_value(v) for v in values) if kind == KIND_TICKS else values


def _decline(state, t, values):
    """The kernel of robots with steerable wheels: every sample takes the general path."""
    return None


class Odometry:
    """Streaming odometry fed encoder ticks (or wheel angles) and timestamps.

    >>> odo = Odometry(robot)                       # doctest: +SKIP
    >>> odo.update(0.00, [0, 0, 0]); odo.update(0.01, [12, -3, 7])   # doctest: +SKIP

    The first sample is the zero (pose stays at ``start``). Each later sample must come
    later in time; a sample repeating the previous timestamp, readings and steering is a
    duplicate: skipped, counted in ``duplicates`` and warned about once. Anything else
    that cannot be integrated raises :class:`OdometryInputError` and changes nothing.

    Readings, in the order of the encoded wheels: a list, tuple, NumPy row, array-like or
    iterator (never a set, dict or text: :func:`omnikin.common.arrays.container_problem`) of Python
    ints of any size, NumPy integer scalars (exact), or floats. ``counter_bits`` (else each
    wheel's ``encoder.counter_bits``), ``max_jump`` [ticks], ``max_wheel_speed`` [rad/s] and
    ``max_wheel_accel`` [rad/s^2]: the counter, jump and change-of-speed rules of
    :mod:`omnikin.odometry.plausibility`, applied exactly as batch odometry applies them; a step beyond the
    bounds of :func:`omnikin.odometry.integration.step_problem` is refused too. ``start``: the pose of
    the first sample (:func:`omnikin.odometry.integration.check_start_pose`).

    Against :func:`omnikin.odometry.batch.batch_odometry` on the same samples: the same refused sample,
    the same wheel increments, body increments and twists (to the bit without steerable wheels),
    poses that agree to rounding; a repeated sample is skipped here, refused there
    (``docs/conventions.md``, "Batch and streaming odometry agree"). Copies and pickles carry
    :data:`STATE_FORMAT`.

    After each update: ``pose`` (x, y, theta) [m, m, rad; theta in [-pi, pi)], ``twist``
    (mean body twist over the last interval), ``residual`` (forward-kinematics residual
    [rad/s], one entry per fitted row: the wheels, then steerable wheels), ``t``,
    ``samples``.

    Parameters
    ----------
    robot : Robot
        The robot; the estimator reads its rolling wheels that have an ``encoder``, in file
        order (``n_enc`` of them), which must observe every motion.
    method : {"exact", "midpoint", "euler"}, default "exact"
        Pose integration (:mod:`omnikin.odometry.integration`); ``midpoint`` and ``euler`` are for
        comparison only.
    counter_bits : int, optional
        Counter width (2 .. 64) for every wheel; default each wheel's ``encoder.counter_bits``.
    start : array_like, shape (3,), default (0, 0, 0)
        Pose ``(x, y, theta)`` [m, m, rad] of the first sample in the world frame (``odom``).
    max_jump : float, optional
        Largest change [ticks] of a wheel between two samples.
    max_wheel_speed : float, optional
        Wheel speed [rad/s] bounding each wheel's change between two samples (with the margin
        :data:`~omnikin.odometry.plausibility.JUMP_MARGIN`); default each wheel's ``max_speed``, else
        :data:`~omnikin.odometry.plausibility.DEFAULT_RIM_SPEED` at its rim.
    max_wheel_accel : float, optional
        Wheel acceleration [rad/s^2] bounding each wheel's change of speed between two
        intervals; default :data:`~omnikin.odometry.plausibility.DEFAULT_RIM_ACCEL` at its rim.

    Attributes
    ----------
    pose : tuple of float
        ``(x, y, theta)`` [m, m, rad] in the world frame, ``theta`` in ``[-pi, pi)``.
    twist : tuple of float
        Mean body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] over the last interval.
    residual : list of float
        Forward-kinematics residual [rad/s] of the last interval, one per fitted row.
    t : float or None
        Time [s] of the last accepted sample; None before the first.
    samples : int
        Samples accepted since the last reset (duplicates not counted).
    duplicates : int
        Repeated samples skipped since the last reset.
    wheel_names : list of str
        The encoded wheels, in the order readings are given.

    Raises
    ------
    InputError
        A robot without encoders or whose encoders do not observe every motion, an unknown
        ``method``, a bad ``start`` or rule value.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        method: str = "exact",
        counter_bits: int | None = None,
        start=(0.0, 0.0, 0.0),
        max_jump=None,
        max_wheel_speed=None,
        max_wheel_accel=None,
    ):
        self.robot = robot
        self.method = check_method(method)
        wheels = encoded_wheels(robot)
        self.rules = counter_rules(wheels, counter_bits, max_jump, max_wheel_speed, max_wheel_accel)
        self.wheel_names = [w.name for w in wheels]
        self.counter_bits = tuple(r.bits for r in self.rules)
        """Counter width of each encoded wheel (None: no wrap-around)."""
        self._n = len(wheels)
        self._scale = [r.rad_per_tick for r in self.rules]
        self._steerable = bool(robot.steerable)
        rows = robot.fk_rows(np.zeros(len(robot.steerable)), self.wheel_names)
        self._n_rows = rows.shape[0]
        self._rows: np.ndarray | None = None if self._steerable else rows
        self._fk: np.ndarray | None = None if self._steerable else robot.fk_matrix(None, self.wheel_names)
        self._redundant = not self._steerable and rows.shape[0] > rank(rows @ robot.admissible_basis)
        self._build()
        self._start(start, "start")

    def _build(self) -> None:
        """Compile (or fetch) the kernels of this configuration."""
        fk_angles = fk_ticks = None
        if self._fk is not None:
            fk_angles = fk_coefficients(self._fk, [1.0] * self._n)
            fk_ticks = fk_coefficients(self._fk, self._scale)
        self._kernels = kernel.build(
            self._n,
            fk_ticks,
            fk_angles,
            kernel.tick_bounds(self.rules),
            kernel.angle_bounds(self.rules),
            kernel.change_bounds(self.rules, "ticks"),
            kernel.change_bounds(self.rules, "rad"),
            [r.bits for r in self.rules],
            self.method,
        )
        self._step_ticks = self._kernels.step_ticks or _decline
        self._step_angles = self._kernels.step_angles or _decline

    # --- copy and pickle: the kernels are rebuilt from the configuration --------------------------
    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        for name in ("_kernels", "_step_ticks", "_step_angles"):
            state.pop(name, None)
        state["_format"] = STATE_FORMAT
        return state

    def __setstate__(self, state: dict) -> None:
        found = state.get("_format", 1) if isinstance(state, dict) else None
        if found != STATE_FORMAT:
            raise InputError(
                f"cannot load this Odometry: it was pickled in state format {shorten(found, 20)} (another omnikin "
                f"version), this version reads format {STATE_FORMAT}; create the estimator anew"
            )
        state = dict(state)
        del state["_format"]
        self.__dict__.update(state)
        self._build()

    def reset(self, pose=(0.0, 0.0, 0.0)) -> None:
        """Forget the previous sample; the next one is the new zero, at ``pose``
        (:func:`omnikin.odometry.integration.check_start_pose`).

        Parameters
        ----------
        pose : array_like, shape (3,), default (0, 0, 0)
            Pose ``(x, y, theta)`` [m, m, rad] of the next sample in the world frame.

        Raises
        ------
        InputError
            Not three finite numbers within the bounds of a start pose.
        """
        self._start(pose, "pose")

    def _start(self, pose, what: str) -> None:
        p = check_start_pose(pose, what)
        if p.shape != (3,):
            raise InputError(f"{what}: expected 3 numbers (x, y, theta), got shape {p.shape}")
        start = (float(p[0]), float(p[1]), float(wrap_angle(p[2])))
        self._state: tuple[Any, ...] = (start, math.nan, math.nan, 0, math.nan) + (0,) * self._n + (0.0,) * self._n
        self._steer: np.ndarray | None = None
        self._steer_increment: tuple[float, float, float] | None = None
        self._steer_residual: list[float] | None = None
        self.duplicates = 0
        self._warned = False

    # --- what the estimate is -------------------------------------------------------------------
    @property
    def pose(self) -> tuple[float, float, float]:
        return self._state[S_POSE]

    @property
    def t(self) -> float | None:
        return None if state_kind(self._state) == KIND_NONE else state_time(self._state)

    @property
    def samples(self) -> int:
        """Samples accepted since the last reset (duplicates not counted)."""
        return self._state[S_COUNT]

    def _increment(self) -> tuple[float, float, float]:
        """Body increment (a, b, phi) [m, m, rad] of the last interval: as integrated (the
        kernels' forward kinematics of the kept wheel increments, or the steering one)."""
        if self._steer_increment is not None:
            return self._steer_increment
        st = self._state
        body_increment = self._kernels.fk_ticks if state_kind(st) == KIND_TICKS else self._kernels.fk_angles
        assert body_increment is not None  # built for every robot without steerable wheels
        return body_increment(*st[S_READ + self._n :])

    @property
    def twist(self) -> tuple[float, float, float]:
        """Mean body twist (vx, vy, omega) [m/s, m/s, rad/s] over the last interval."""
        st = self._state
        if st[S_COUNT] < 2:
            return (0.0, 0.0, 0.0)
        dt = st[S_DT]
        a, b, phi = self._increment()
        return (a / dt, b / dt, phi / dt)

    @property
    def residual(self) -> list[float]:
        """Forward-kinematics residual [rad/s] of the last interval (zeros for square layouts)."""
        st = self._state
        if st[S_COUNT] < 2:
            return [0.0] * self._n_rows
        if self._steer_residual is not None:
            return list(self._steer_residual)
        if not self._redundant or self._rows is None:
            return [0.0] * self._n_rows
        delta = np.array(st[S_READ + self._n :], dtype=float)
        angles = delta * self._scale if state_kind(st) == KIND_TICKS else delta
        b = np.concatenate([angles, np.zeros(self._n_rows - self._n)])
        inc = np.array(self._increment())
        return [float(v) / st[S_DT] for v in b - self._rows @ inc]

    @property
    def _index(self) -> int:
        return self.samples + self.duplicates

    # --- feeding it -------------------------------------------------------------------------------
    def update(self, t: float, ticks, steer=None) -> tuple[float, float, float]:
        """Feed one sample: time [s], raw counter readings of the encoded wheels in file
        order, and (steerable robots) their steering angles [rad]. Returns the pose.

        Parameters
        ----------
        t : float
            Sample time [s], later than the previous sample's.
        ticks : sequence of int or float, length n_enc
            Raw counter readings of the encoded wheels, file order (Python or NumPy integers
            are exact).
        steer : sequence of float, length n_steer, optional
            Steering angles [rad] of the steerable wheels; required when the robot has any.

        Returns
        -------
        tuple of float
            The pose ``(x, y, theta)`` [m, m, rad] after this sample, in the world frame.

        Raises
        ------
        OdometryInputError
            A sample that cannot be integrated (its index in ``.sample``); the estimator is left
            unchanged.
        """
        if steer is None:
            new = self._step_ticks(self._state, t, ticks)
            if new is not None:
                self._state = new
                return new[0]
        return self._update_general(t, ticks, steer, KIND_TICKS)

    def update_angles(self, t: float, angles, steer=None) -> tuple[float, float, float]:
        """Feed one sample of wheel angles [rad] (encoded wheels, file order; they do not wrap).

        Parameters
        ----------
        t : float
            Sample time [s], later than the previous sample's.
        angles : sequence of float, length n_enc
            Wheel angles [rad] of the encoded wheels, file order.
        steer : sequence of float, length n_steer, optional
            Steering angles [rad] of the steerable wheels; required when the robot has any.

        Returns
        -------
        tuple of float
            The pose ``(x, y, theta)`` [m, m, rad] after this sample, in the world frame.

        Raises
        ------
        OdometryInputError
            A sample that cannot be integrated (its index in ``.sample``); the estimator is left
            unchanged.
        """
        if steer is None:
            new = self._step_angles(self._state, t, angles)
            if new is not None:
                self._state = new
                return new[0]
        return self._update_general(t, angles, steer, KIND_ANGLES)

    # --- the general path: first sample, steering, floats, anything doubtful -----------------------
    def _fail(self, detail: str):
        k = self._index
        return OdometryInputError(f"sample {k}: {detail}", sample=k, detail=detail)

    def _time(self, t) -> float:
        problem = timestamp_problem(t)
        if problem is not None:
            raise self._fail(problem)
        value = as_float(t)
        if not math.isfinite(value):
            raise self._fail(f"non-finite timestamp {show_number(t)}")
        return value

    def _numbers(self, values, kind: int) -> tuple:
        """Readings as a tuple of Python ints (exact) or floats, or an error naming the wheel."""
        what = _WHAT[kind]
        why = container_problem(values)
        if why is not None:
            raise self._fail(f"{what}s: {why}; give one per wheel {self.wheel_names} as a list, tuple or array")
        if not isinstance(values, (np.ndarray, Sequence, Iterator)):  # an array-like (__array__)
            try:
                values = np.asarray(values)
            except (TypeError, ValueError):
                raise self._fail(f"{what}s: expected numbers for wheels {self.wheel_names}") from None
        if isinstance(values, np.ndarray):
            if values.dtype.kind not in "iuf":
                raise self._fail(f"{what}s: expected numbers for wheels {self.wheel_names}, got dtype {values.dtype}")
            seq = values.tolist()
        else:
            try:
                seq = list(values)
            except TypeError:
                raise self._fail(
                    f"expected {self._n} {what}s for wheels {self.wheel_names}, got {shorten(values)}"
                ) from None
        if not isinstance(seq, list) or len(seq) != self._n:
            got = len(seq) if isinstance(seq, list) else shorten(seq)
            raise self._fail(f"expected {self._n} {what}s for wheels {self.wheel_names}, got {got}")
        out: list[int | float] = []
        for name, v in zip(self.wheel_names, seq, strict=True):
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise self._fail(f"{what} {shorten(v)} of wheel {name!r} is not a number")
            if isinstance(v, numbers.Integral) and kind == KIND_TICKS:
                out.append(int(v))
                continue
            number = as_float(v)
            if not math.isfinite(number):
                raise self._fail(f"non-finite {what} {show_number(v)}, wheel {name!r}")
            out.append(number)
        return tuple(out)

    def _update_general(self, t, readings, steer, kind: int):
        t = self._time(t)
        values = self._numbers(readings, kind)
        s = self._check_steer(steer)
        st = self._state
        if kind == KIND_TICKS:
            self._check_range(values)
        fed = state_kind(st)
        if fed == KIND_NONE:
            return self._first(t, values, s, kind)
        if fed != kind:
            raise InputError(
                f"this estimator was fed {_WHAT[fed]}s since its last reset: reset() before feeding {_WHAT[kind]}s"
            )
        previous = st[S_READ : S_READ + self._n]
        dt = t - state_time(st)
        if not dt > 0.0:
            return self._not_later(t, dt, values, previous, s)
        if dt == math.inf:
            raise self._fail("t: interval between timestamps too long")
        linked = st[S_COUNT] > 1  # a previous interval to compare the speeds with
        before = st[S_READ + self._n :]
        exact: Sequence[Any]  # the increments as exact numbers (ticks) or floats (wheel angles)
        if kind == KIND_TICKS:
            exact = [exact_increment(v, p, r.bits) for v, p, r in zip(values, previous, self.rules, strict=True)]
            for d, r, b, v, p in zip(exact, self.rules, before, values, previous, strict=True):
                if abs(d) > r.limit(dt) or (r.half is not None and d == -r.half):
                    ends = (exact_value(p), exact_value(v))
                    hint = r.wrap_hint(d, dt, b, st[S_DT], ends) if linked else r.wrap_hint(d, dt, readings=ends)
                    raise self._fail(r.jump_message(d, dt, hint=hint))
            deltas = tuple(as_float(d) for d in exact)  # +-inf beyond the float range: refused below
        else:
            exact = deltas = tuple(v - p for v, p in zip(values, previous, strict=True))
            for d, r in zip(deltas, self.rules, strict=True):
                if abs(d) > r.angle_limit(dt):
                    raise self._fail(r.jump_message(d, dt, "rad"))
        if linked:
            self._check_changes(exact, deltas, before, st[S_DT], dt, kind, values, previous)
        residual = increment = None
        if self._steer is not None and s is not None:  # steerable wheels
            a, b, phi, residual = self._steered_increment(deltas, s, dt, kind)
            increment = (a, b, phi)
        else:
            body_increment = self._kernels.fk_ticks if kind == KIND_TICKS else self._kernels.fk_angles
            assert body_increment is not None  # built for every robot without steerable wheels
            a, b, phi = body_increment(*deltas)
        problem = step_problem(a, b, phi, dt)
        if problem is not None:
            raise self._fail(problem)
        pose = self._kernels.move(st[S_POSE], a, b, phi)
        self._state = (pose,) + _times(t, kind) + (st[S_COUNT] + 1, dt, *_kept(values, kind), *deltas)
        self._steer = s
        self._steer_increment = increment
        self._steer_residual = residual
        return pose

    def _steered_increment(self, deltas, steer, dt: float, kind: int):
        """Body increment (a, b, phi) [m, m, rad] of wheel increments ``deltas`` [ticks or rad]
        at the mean steering of the interval, and the residual [rad/s]: the operator and the
        arithmetic of batch odometry (:class:`omnikin.odometry.batch.SteeredSteps`) on one interval."""
        assert self._steer is not None  # the steering of the previous sample
        scale = self._scale if kind == KIND_TICKS else [1.0] * self._n
        mid = mid_steer(np.stack([self._steer, steer]))
        # (1, 3, k) and (1, k, 3), or without the 1 when the encoded wheels do not steer
        f = self.robot.fk_matrix(mid, self.wheel_names).reshape(3, -1)
        rows = self.robot.fk_rows(mid, self.wheel_names).reshape(-1, 3)
        angles = np.zeros(f.shape[-1])
        angles[: self._n] = [d * k for d, k in zip(deltas, scale, strict=True)]
        with np.errstate(over="ignore", invalid="ignore"):
            inc = steered_steps(f, angles)
            residual = [float(v) / dt for v in angles - rows @ inc]
        a, b, phi = (float(v) for v in inc)
        return a, b, phi, residual

    def _first(self, t, values, steer, kind):
        st = self._state
        self._state = (st[S_POSE],) + _times(t, kind) + (1, math.nan, *_kept(values, kind)) + (0.0,) * self._n
        self._steer = steer
        return self.pose

    def _not_later(self, t, dt, values, previous, steer):
        same_steer = steer is None or (self._steer is not None and np.array_equal(steer, self._steer))
        if dt == 0.0 and values == previous and same_steer:
            self.duplicates += 1
            if not self._warned:
                warnings.warn(
                    f"odometry: duplicate sample at t={t!r} skipped (counted in .duplicates)",
                    RuntimeWarning,
                    stacklevel=4,
                )
                self._warned = True
            return self.pose
        what = "repeats" if dt == 0.0 else "goes back from"
        differs = " with different readings or steering" if dt == 0.0 else ""
        raise self._fail(f"timestamp {t!r} {what} the previous one {state_time(self._state)!r}{differs}")

    def _check_changes(self, exact, deltas, before, dt_before: float, dt: float, kind: int, values, previous) -> None:
        """Raise if a wheel's increment changes faster than its change-of-speed rule allows
        (:func:`omnikin.odometry.plausibility.change_limit`, the expression batch odometry evaluates)."""
        unit = "ticks" if kind == KIND_TICKS else "rad"
        for e, d, b, r, v, p in zip(exact, deltas, before, self.rules, values, previous, strict=True):
            if not abs(d - b) <= r.change_limit(b, d, dt_before, dt, unit):
                ends = (exact_value(p), exact_value(v)) if unit == "ticks" else ()
                hint = r.wrap_hint(e, dt, b, dt_before, ends) if unit == "ticks" else ""
                raise self._fail(r.change_message(b, e, dt_before, dt, unit, hint))

    def _check_range(self, values) -> None:
        """Raise if a reading lies outside its wheel's counter (signed or unsigned)."""
        for v, r in zip(values, self.rules, strict=True):
            if r.bits is not None and not in_counter_range(v, r.bits):
                raise self._fail(r.range_message(v))

    def _check_steer(self, steer):
        if not self._steerable:
            if steer is not None:
                raise InputError(f"robot {self.robot.name!r} has no steerable wheel: do not pass steer")
            return None
        if steer is None:
            raise InputError(
                f"robot {self.robot.name!r}: steerable wheels {self.robot.steer_names} need "
                f"their steering angles (steer=...)"
            )
        why = container_problem(steer)
        if why is not None:
            raise self._fail(f"steer: {why}; give one angle per wheel {self.robot.steer_names} as a list or array")
        try:
            s = as_real_array(steer, "steer")
        except InputError as exc:  # complex, bool, text, ragged: named at this sample
            raise self._fail(str(exc)) from None
        if s.shape != (len(self.robot.steerable),):
            raise self._fail(
                f"steer: expected {len(self.robot.steerable)} angles for {self.robot.steer_names}, got shape {s.shape}"
            )
        for k, value in enumerate(s.tolist()):
            problem = steer_problem(self.robot, k, value)
            if problem is not None:
                raise self._fail(problem)
        return s
