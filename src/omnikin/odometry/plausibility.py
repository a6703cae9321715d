"""The physical rules on wheel increments: a wheel cannot turn or change its speed faster than
it can (``docs/conventions.md``, Odometry).

Two physical rules turn a counter that wraps without a declared width into an error instead of
a wrong pose, and refuse corrupted samples:

* **speed**: each wheel has a speed bound ``V`` [rad/s]: ``JUMP_MARGIN`` times an explicit
  ``max_wheel_speed``, else ``JUMP_MARGIN`` times the wheel's ``max_speed``, else a rim speed of
  :data:`DEFAULT_RIM_SPEED` over the wheel radius. An increment ``d`` over ``dt`` is impossible
  when ``|d| > V dt / |rad_per_tick| + QUANTISATION_SLACK`` ticks (or ``|d| > max_jump`` when an
  explicit ``max_jump`` [ticks] is given); with a counter width also when
  ``|d| > 2**(bits-1) - 0.5`` (exactly half the range: direction undecidable);
* **change of speed**: each wheel has an acceleration bound ``A`` [rad/s^2]: ``JUMP_MARGIN`` times
  an explicit ``max_wheel_accel``, else a rim acceleration of :data:`DEFAULT_RIM_ACCEL` over the
  radius (``inf`` switches the rule off). With ``A`` and ``s = QUANTISATION_SLACK`` in ticks, two
  consecutive increments ``d0`` over ``dt0`` and ``d1`` over ``dt1`` are impossible when
  ``|d1 - d0| > min(|dt1 - dt0| (|d0| + s) / dt0 + A dt1 (dt0 + dt1) / 2,
  |dt1 - dt0| (|d1| + s) / dt1 + A dt0 (dt0 + dt1) / 2) + 2 s`` (:func:`change_limit`).
  Derivation: the mean speeds ``v0``, ``v1`` of two adjacent intervals differ by at most
  ``A (dt0 + dt1) / 2``, and ``d1 - d0 = (dt1 - dt0) v0 + dt1 (v1 - v0) = (dt1 - dt0) v1 +
  dt0 (v1 - v0)`` with ``|v0| <= (|d0| + s) / dt0``, ``|v1| <= (|d1| + s) / dt1``: the first
  terms absorb intervals of different lengths (a missed sample) and timestamp jitter in
  proportion to the speed. For equal intervals ``dt`` the bound is ``A dt^2 + 2 s``. A counter
  of ``b`` bits that wraps changes one increment by ``2**b``: this rule catches it whenever
  ``2**b`` exceeds twice the bound (``docs/conventions.md`` lists which widths at which rates).
  Wheel angles have this rule only with an explicit ``max_wheel_accel``: they come unwrapped
  from drivers, and a live controller must not stop at an impact.

This module is the single source of those rules: batch odometry applies them through
:mod:`omnikin.odometry.increments`, the streaming estimator through :class:`CounterRule`, and the
generated streaming kernel evaluates the same expressions (:mod:`omnikin.odometry._stream_kernel`).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ..common.arrays import range_problem
from ..common.messages import shorten
from ..errors import InputError, OdometryInputError
from ..kinematics.se2 import MAX_ANGLE
from ..kinematics.wheels import MAX_SPEED_RANGE
from .counters import check_bits, exact_value, in_counter_range, show_number, wrap_exact

JUMP_MARGIN = 1.5


"""A wheel may turn (or change its speed) this much faster than its stated limit before a
sample is impossible."""


QUANTISATION_SLACK = 2.0


"""Ticks allowed on top of the speed bound (quantisation at both ends of an interval)."""


DEFAULT_RIM_SPEED = 50.0


"""Rim speed [m/s] (180 km/h) bounding a wheel without ``max_speed``. Indoor and service robots
drive below 3 m/s and scaled autonomous race cars (F1TENTH) stay near 20 m/s; only full-size
autonomous race cars (the Indy Autonomous Challenge cars pass 70 m/s) are faster, and they give
their wheels' ``max_speed`` (or ``max_wheel_speed``)."""


DEFAULT_RIM_ACCEL = 30.0


"""Rim acceleration [m/s^2] (about 3 g) bounding how fast a wheel's speed changes. Traction
limits a wheel rolling on the floor to about 1 g (rubber on dry concrete, friction coefficient
0.8 to 1); 3 g leaves a margin of three for wheels that slip, spin free or are braked by an
impact. Between two intervals of ``dt`` the mean rim speed may then change by ``30 dt`` m/s
(1.5 m/s at 20 Hz, 0.3 m/s at 100 Hz) plus the quantisation. Data that changes faster (a robot
banging into walls at speed, hand-made logs with instantaneous speed steps) needs a larger
``max_wheel_accel`` (``math.inf``: no rule)."""


SAFETY = 1.0 - 1e-12


"""Shrinks a bound used as a quick sufficient test by far more than float rounding (and the
rounding of increments beyond 2**53 to floats): it never accepts what the exact rule refuses."""


MAX_JUMP_TEXT = "a finite number of ticks > 0"


MAX_WHEEL_SPEED_TEXT = f"a wheel speed in [{MAX_SPEED_RANGE[0]:g}, {MAX_SPEED_RANGE[1]:g}] rad/s"


"""What ``max_wheel_speed`` must be: the range of a wheel's ``max_speed`` in a robot file
(:data:`omnikin.kinematics.wheels.MAX_SPEED_RANGE`; 1e4 rad/s is 95 000 rpm, beyond any wheel)."""


MAX_WHEEL_ACCEL_TEXT = "a wheel acceleration > 0 [rad/s^2] (or inf: no bound)"


def check_max_jump(max_jump) -> float | None:
    """``max_jump`` [ticks] > 0 (each wheel's bound in radians is checked by :func:`counter_rules`)."""
    return _positive(max_jump, "max_jump", MAX_JUMP_TEXT)


def check_max_wheel_speed(speed) -> float | None:
    """``max_wheel_speed`` [rad/s] within :data:`omnikin.kinematics.wheels.MAX_SPEED_RANGE`."""
    if speed is None:
        return None
    problem = range_problem(speed, *MAX_SPEED_RANGE, "rad/s")
    if problem is not None:
        raise OdometryInputError(f"max_wheel_speed {problem}")
    return float(speed)


def check_max_wheel_accel(accel) -> float | None:
    """``max_wheel_accel`` [rad/s^2] > 0; ``inf`` switches the change-of-speed rule off."""
    if isinstance(accel, numbers.Real) and not isinstance(accel, (bool, np.bool_)) and accel == math.inf:
        return math.inf
    return _positive(accel, "max_wheel_accel", MAX_WHEEL_ACCEL_TEXT)


def _positive(value, name: str, what: str) -> float | None:
    if value is None:
        return None
    if (
        isinstance(value, (bool, np.bool_))
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
        or value <= 0
    ):
        raise OdometryInputError(f"{name} must be {what}, got {shorten(value)}")
    return float(value)


@dataclass(frozen=True)
class CounterRule:
    """How the readings of one encoded wheel are differenced and checked.

    ``bits``: counter width (None: no wrap-around); ``rad_per_tick`` [rad] (negative when
    inverted); ``speed``: the wheel speed bound [rad/s] (margin included) and ``source``
    where it comes from; ``accel``: the bound on its rate of change [rad/s^2] (margin included,
    ``inf``: none) and ``accel_source``; ``max_jump`` [ticks]: an explicit bound replacing the
    speed bound on one increment.
    """

    wheel: str
    bits: int | None
    rad_per_tick: float
    speed: float
    source: str
    accel: float = math.inf
    accel_source: str = "no bound"
    max_jump: float | None = None
    accel_explicit: bool = False

    @property
    def rate(self) -> float:
        """Speed bound in ticks per second."""
        return self.speed / abs(self.rad_per_tick)

    @property
    def accel_rate(self) -> float:
        """Acceleration bound in ticks per second squared."""
        return self.accel / abs(self.rad_per_tick)

    @property
    def half(self) -> int | None:
        return None if self.bits is None else 1 << (self.bits - 1)

    @property
    def half_limit(self) -> float:
        """Largest |increment| a ``bits``-bit counter can tell apart (inf without a width)."""
        return math.inf if self.bits is None else 2.0 ** (self.bits - 1) - 0.5

    def limit(self, dt):
        """Largest plausible |increment| [ticks] over ``dt`` [s] (scalar or array)."""
        limit = self.max_jump if self.max_jump is not None else self.rate * dt + QUANTISATION_SLACK
        if self.bits is None:
            return limit
        return np.minimum(limit, self.half_limit) if np.ndim(limit) else min(limit, self.half_limit)

    def angle_limit(self, dt):
        """Largest plausible |increment| [rad] of the wheel angle over ``dt`` [s] (no counter)."""
        if self.max_jump is not None:
            return self.max_jump * abs(self.rad_per_tick)
        return self.speed * dt + QUANTISATION_SLACK * abs(self.rad_per_tick)

    def change_bounds(self, unit: str = "ticks") -> tuple[float, float]:
        """``(A, slack)`` of the change-of-speed rule in ``unit`` (ticks, or rad). Wheel angles
        have it only with an explicit ``max_wheel_accel`` (``A`` inf otherwise: no rule)."""
        if unit == "ticks":
            return self.accel_rate, QUANTISATION_SLACK
        return (self.accel if self.accel_explicit else math.inf), QUANTISATION_SLACK * abs(self.rad_per_tick)

    def change_limit(self, before, delta, dt_before, dt, unit: str = "ticks"):
        """Largest plausible ``|delta - before|`` [``unit``] of the increments ``before`` over
        ``dt_before`` then ``delta`` over ``dt`` [s] (:func:`change_limit`)."""
        a, slack = self.change_bounds(unit)
        return change_limit(a, slack, before, delta, dt_before, dt)

    def jump_message(self, delta, dt, unit: str = "ticks", hint: str = "") -> str:
        """Why ``delta`` [``unit``: ticks, or rad for wheel angles] over ``dt`` [s] is
        impossible, with the way out (one line)."""
        if self.max_jump is not None:
            why = f"more than max_jump={show_number(self.max_jump)} ticks"
        else:
            why = f"faster than {self.speed:.6g} rad/s ({self.source})"
        head = f"impossible jump of {show_number(delta)} {unit} in {dt:.6g} s, wheel {self.wheel!r}: {why}"
        if unit != "ticks":
            return head
        if self.bits is not None:
            return f"{head}, or half the range of its {self.bits}-bit counter"
        return f"{head}{hint}; {WRAP_ADVICE}"

    def change_message(self, before, delta, dt_before, dt, unit: str = "ticks", hint: str = "") -> str:
        """Why increments ``before`` then ``delta`` [``unit``] are impossible (one line)."""
        if unit == "ticks":
            before = exact_value(float(before))
        head = (
            f"impossible change of speed, wheel {self.wheel!r}: {show_number(before)} then {show_number(delta)} "
            f"{unit} in consecutive intervals of {dt_before:.6g} s and {dt:.6g} s, faster than "
            f"{self.accel:.6g} rad/s^2 ({self.accel_source})"
        )
        if unit != "ticks":
            return f"{head}; if this is real, raise max_wheel_accel"
        if self.bits is not None:
            return f"{head}; is its counter {self.bits} bits wide? If this is real, raise max_wheel_accel"
        return f"{head}{hint}; {WRAP_ADVICE}; if this is real, raise max_wheel_accel"

    def range_message(self, value) -> str:
        half = 1 << ((self.bits or 1) - 1)
        return (
            f"tick reading {show_number(value)} outside the range of a {self.bits}-bit counter "
            f"({-half} .. {2 * half - 1}), wheel {self.wheel!r}"
        )

    def wrap_hint(self, delta, dt, before=None, dt_before=None, readings=()) -> str:
        """For a wheel without counter width: ``"; read as a 12-bit counter it is 11 ticks"`` for
        the widest counter that makes the exact increment ``delta`` over ``dt`` plausible, and
        with the previous increment ``before`` over ``dt_before`` (the pair may hold the wrap in
        either interval) ``"; read as a 12-bit counter they are -1 then -4 ticks"``; else ``""``.
        A width is offered only if the ``readings`` of the interval lie in its counter's range."""
        if self.bits is not None:
            return ""
        first = None if before is None else exact_value(before)
        for bits in range(64, 1, -1):
            if not all(in_counter_range(v, bits) for v in readings):
                break  # out of range for this width, and for every narrower one
            top = 2.0 ** (bits - 1) - 0.5
            wrapped = wrap_exact(delta, bits)
            if abs(wrapped) > min(self.limit(dt), top):
                continue
            if first is None:
                if wrapped != delta:
                    return f"; read as a {bits}-bit counter it is {show_number(wrapped)} ticks"
                continue
            previous = wrap_exact(first, bits)
            if (previous, wrapped) == (first, delta) or abs(previous) > min(self.limit(dt_before), top):
                continue
            if abs(float(wrapped) - float(previous)) <= self.change_limit(
                float(previous), float(wrapped), dt_before, dt
            ):
                return (
                    f"; read as a {bits}-bit counter they are {show_number(previous)} then {show_number(wrapped)} ticks"
                )
        return ""


WRAP_ADVICE = "if its counter wraps, give the counter width (counter_bits, --counter-bits or encoder.counter_bits)"


def change_limit(a, slack, d0, d1, dt0, dt1):
    """Largest plausible ``|d1 - d0|`` for the increments ``d0`` over ``dt0`` then ``d1`` over
    ``dt1`` [s] of a wheel whose speed changes at most at ``a`` [per s^2] and whose increments
    are off by up to ``slack`` (module docstring):

    ``min(|dt1 - dt0| (|d0| + slack) / dt0 + a dt1 (dt0 + dt1) / 2,
    |dt1 - dt0| (|d1| + slack) / dt1 + a dt0 (dt0 + dt1) / 2) + 2 slack``.

    The same expression, in the same order, for Python floats (streaming) and arrays (batch),
    so both round alike."""
    gap = np.abs(dt1 - dt0)
    span = dt0 + dt1
    via0 = gap * (np.abs(d0) + slack) / dt0 + a * 0.5 * (dt1 * span)
    via1 = gap * (np.abs(d1) + slack) / dt1 + a * 0.5 * (dt0 * span)
    return np.minimum(via0, via1) + 2.0 * slack


def counter_rules(
    wheels, counter_bits=None, max_jump=None, max_wheel_speed=None, max_wheel_accel=None
) -> tuple[CounterRule, ...]:
    """One :class:`CounterRule` per encoded wheel.

    ``counter_bits`` applies to every wheel; a wheel whose robot file gives another
    ``encoder.counter_bits`` is an error (neither is guessed to win). Without it each wheel
    uses its own ``encoder.counter_bits`` (or none). ``max_wheel_speed`` lies in the range of a
    robot file's ``max_speed``, and ``max_jump`` may not let a wheel turn more than
    :data:`~omnikin.kinematics.se2.MAX_ANGLE` in one interval: physical bounds, so that no option
    lets a corrupt sample through (the body increment of an interval has its own bounds,
    :func:`omnikin.odometry.integration.step_problem`).
    """
    bits = check_bits(counter_bits)
    max_jump = check_max_jump(max_jump)
    speed = check_max_wheel_speed(max_wheel_speed)
    accel = check_max_wheel_accel(max_wheel_accel)
    rules = []
    for w in wheels:
        own = w.encoder.counter_bits
        if bits is not None and own is not None and own != bits:
            raise InputError(
                f"counter_bits={bits} contradicts encoder.counter_bits: {own} of wheel {w.name!r} "
                f"in the robot file; give one of them"
            )
        if max_jump is not None and max_jump * abs(w.encoder.rad_per_tick) > MAX_ANGLE:
            raise OdometryInputError(
                f"max_jump={show_number(max_jump)} ticks would let wheel {w.name!r} turn "
                f"{max_jump * abs(w.encoder.rad_per_tick):.6g} rad in one interval, beyond the "
                f"{MAX_ANGLE:g} rad bound on every angle the core takes"
            )
        if speed is not None:
            bound, source = JUMP_MARGIN * speed, f"{JUMP_MARGIN:g} x max_wheel_speed {speed:g} rad/s"
        elif w.max_speed is not None:
            bound, source = JUMP_MARGIN * w.max_speed, f"{JUMP_MARGIN:g} x its max_speed {w.max_speed:g} rad/s"
        else:
            bound, source = DEFAULT_RIM_SPEED / w.radius, f"{DEFAULT_RIM_SPEED:g} m/s at the rim"
        if accel is not None:
            change, change_source = JUMP_MARGIN * accel, f"{JUMP_MARGIN:g} x max_wheel_accel {accel:g} rad/s^2"
        else:
            change, change_source = DEFAULT_RIM_ACCEL / w.radius, f"{DEFAULT_RIM_ACCEL:g} m/s^2 at the rim"
        rules.append(
            CounterRule(
                w.name,
                bits if bits is not None else own,
                w.encoder.rad_per_tick,
                bound,
                source,
                change,
                change_source,
                max_jump,
                accel is not None,
            )
        )
    return tuple(rules)


def speed_changes(a, slack, d0, d1, dt0, dt1) -> np.ndarray:
    """Mask of the pairs breaking :func:`change_limit`. A cheap sufficient bound first (both
    terms of the limit are at least ``a min(dt0, dt1) (dt0 + dt1) / 2``, shrunk by
    :data:`SAFETY`); the exact limit only where that does not settle it (as the streaming kernel)."""
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # bad intervals: refused by their own check
        change = np.abs(d1 - d0)
        span = np.minimum(dt0, dt1) * (dt0 + dt1)
        cheap = (a * (0.5 * SAFETY)) * span + (2.0 * SAFETY) * slack
        if np.all(change <= cheap):
            return np.zeros(change.shape, dtype=bool)
        return ~(change <= change_limit(a, slack, d0, d1, dt0, dt1))


def jump_limits(rules, dt: np.ndarray) -> np.ndarray:
    """Per-wheel jump limits ``(..., m, n)`` or ``(..., m, 1)`` when all wheels share one."""
    if len(set((r.rate, r.max_jump, r.bits) for r in rules)) == 1:
        return np.asarray(rules[0].limit(dt))[..., None]
    return np.stack([np.broadcast_to(r.limit(dt), dt.shape) for r in rules], axis=-1)
