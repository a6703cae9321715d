"""Encoder ticks -> wheel angle increments: every rule on counters, wrap-around, jumps and
changes of speed (``docs/conventions.md``, Odometry).

``angle = 2 pi ticks / (ticks_per_rev gear_ratio)``, negated when ``invert``.

Readings are exact integers (or, from the library, floats). A counter of ``bits`` bits
(``counter_bits``) wraps: the increment between two samples is the difference taken
modulo ``2**bits`` into ``[-2**(bits-1), 2**(bits-1))``; its readings may be stored
signed or unsigned, so they must lie in ``[-2**(bits-1), 2**bits)``. The increment is
computed exactly and rounded once to a float: integer arithmetic for readings of any integer
type and size (int64, uint64 beyond 2**63, Python ints of any length), and for float readings
the exact difference of the two floats (Knuth's TwoSum), wrapped without rounding (the
subtraction of a multiple of ``2**bits`` is exact by Sterbenz's lemma), so a float reading of a
64-bit counter loses nothing a float can hold.

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

The rule is applied to the float increments (the exact increments rounded once), by batch and
streaming odometry alike, in the order of the samples. Within one sample the checks run in the
order of :data:`RANKS`, so both report the same first problem.

This module is the single source of those rules: batch odometry uses :func:`block_increments`,
the streaming estimator :class:`CounterRule`, :func:`exact_increment` and
:func:`in_counter_range`, and the generated streaming kernel the same expressions
(:mod:`omnikin.odometry._stream_kernel`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import partial

import numpy as np

from ..common.arrays import TEXT_TYPES, container_problem, range_problem, whole_problem
from ..common.messages import shorten
from ..errors import InputError, OdometryInputError
from ..kinematics.se2 import MAX_ANGLE
from ..kinematics.wheels import COUNTER_BITS_RANGE, MAX_SPEED_RANGE

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
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
UINT64_END = 2**64
FLOAT_EXACT = 2**53
"""Integers beyond this are not all floats: readings there must stay integers."""

SAFETY = 1.0 - 1e-12
"""Shrinks a bound used as a quick sufficient test by far more than float rounding (and the
rounding of increments beyond 2**53 to floats): it never accepts what the exact rule refuses."""

RANKS = {
    "time": 0,  # non-finite timestamp
    "reading": 1,  # non-finite reading or wheel angle
    "steer": 2,  # bad steering angle
    "range": 3,  # reading outside its counter's range
    "order": 4,  # timestamp not later than the previous one, or an infinite interval
    "jump": 5,  # the speed rule
    "change": 6,  # the change-of-speed rule
    "motion": 7,  # the body increment of the interval beyond the bounds of one step
}
"""Order of the checks of one sample (streaming runs them in this order; batch reports the
earliest sample and, within it, the lowest rank)."""


# --- options ----------------------------------------------------------------------------------
def check_bits(bits, what: str = "counter_bits") -> int | None:
    if bits is None:
        return None
    problem = whole_problem(bits, *COUNTER_BITS_RANGE)
    if problem:
        raise OdometryInputError(f"{what} {problem}")
    return int(bits)


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


# --- the rule of one wheel --------------------------------------------------------------------
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


def show_number(value) -> str:
    """A reading or increment for a message, bounded in length (Python ints may be huge)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        v = int(value)
        return str(v) if v.bit_length() <= 128 else f"<an integer of {v.bit_length()} bits>"
    if isinstance(value, Fraction):
        return repr(float(value)) if value.denominator != 1 else show_number(value.numerator)
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return shorten(value)


# --- containers of readings (whether one has an order: omnikin.common.arrays.container_problem) -----
def _is_number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def nested_problem(value, names, what: str) -> OdometryInputError | None:
    """The first element of nested Python containers ``value`` ``(..., N, n)`` that cannot be a
    reading, as an error naming its sample (and trial and wheel), or None.

    Rows are the innermost sequences (depth found along the first items); a container where a
    number belongs, a non-number, or a row of the wrong length is reported.
    """
    depth, probe = 0, value
    while depth <= MAX_DIMS and container_problem(probe) is None and len_or_none(probe):
        depth, probe = depth + 1, next(iter(probe))
    if depth > MAX_DIMS:  # a list that holds itself, or deeper than any array
        return OdometryInputError(f"{what}: nested deeper than {MAX_DIMS} levels")
    depth = max(depth, 2)

    def walk(v, path):
        why = container_problem(v)
        if len(path) == depth:  # a reading
            if why is None or not _is_number(v):
                return path, f"reading {shorten(v, 40)} is not a number"
            return None
        if why is not None:
            return path, why
        if isinstance(v, np.ndarray) or hasattr(v, "__array__") or hasattr(v, "__array_interface__"):
            return None  # converted by NumPy, checked there
        if not isinstance(v, Sequence):
            return path, f"a {type(v).__name__} is not a sequence (give rows as lists, tuples or arrays)"
        if len(path) == depth - 1 and len(v) != len(names):
            return path, f"{len(v)} readings for {len(names)} wheels {names}"
        for i, item in enumerate(v):
            found = walk(item, path + (i,))
            if found is not None:
                return found
        return None

    found = walk(value, ())
    if found is None:
        return None
    path, why = found
    if len(path) == depth:
        sample, trial, wheel = path[-2], path[:-2], names[path[-1]] if path[-1] < len(names) else None
        detail = f"{what}: {why}" + (f", wheel {wheel!r}" if wheel is not None else "")
    elif len(path) == depth - 1:
        sample, trial = path[-1], path[:-1]
        detail = f"{what}: {why}"
    else:
        return OdometryInputError(f"{what}{list(path)}: {why}")
    return at_sample(detail, sample, trial)


MAX_DIMS = 64
"""NumPy's largest number of dimensions: deeper nesting is no array of readings."""


def len_or_none(value) -> int:
    """Length of a sequence (0 for anything else, iterators included: they are not walked)."""
    return len(value) if isinstance(value, Sequence) and not isinstance(value, TEXT_TYPES) else 0


# --- exact increments (scalars: the streaming estimator) -----------------------------------------
def wrap_exact(delta, bits: int | None):
    """An exact increment (int or Fraction) wrapped into ``[-2**(bits-1), 2**(bits-1))``."""
    if bits is None:
        return delta
    half = 1 << (bits - 1)
    if isinstance(delta, int):
        return ((delta + half) & (2 * half - 1)) - half
    return (delta + half) % (2 * half) - half


def wrap_scalar(delta, bits: int | None):
    """One increment (Python int or float) wrapped into the counter's range, exactly (a float
    result is the wrapped value of the float ``delta``, rounded once)."""
    if bits is None or isinstance(delta, int):
        return wrap_exact(delta, bits)
    return float(wrap_exact(Fraction(delta), bits))


def exact_value(value):
    """A finite reading as an exact number: integers (Python or NumPy) as Python ints, whole
    floats as ints, other floats as the Fraction they hold exactly (a Fraction as it is).

    The streaming estimator keeps its readings in this form, so that its generated kernel
    subtracts the next integer reading exactly (``int - float`` rounds twice beyond 2**53)."""
    if isinstance(value, (int, Fraction)):
        return value
    if isinstance(value, np.integer):
        return int(value)
    value = float(value)
    return int(value) if value.is_integer() else Fraction(value)


def as_float(value) -> float:
    """A real number (Python int of any size, Fraction, NumPy scalar) as a float, +-inf
    beyond the float range (``float(10**400)`` raises OverflowError)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def as_floats(values: np.ndarray) -> np.ndarray:
    """An array of real numbers as float64, each converted by :func:`as_float` (an object
    array may hold integers beyond the float range)."""
    if values.dtype != object:
        return values.astype(np.float64)
    out = np.empty(values.shape)
    out.reshape(-1)[:] = [as_float(v) for v in values.reshape(-1)]
    return out


def exact_increment(new, old, bits: int | None):
    """``new - old`` wrapped to a ``bits``-bit counter, exactly (int or Fraction)."""
    return wrap_exact(exact_value(new) - exact_value(old), bits)


def in_counter_range(value, bits: int | None) -> bool:
    """True if a reading fits a ``bits``-bit counter, stored signed or unsigned."""
    return bits is None or -(1 << (bits - 1)) <= value < (1 << bits)


# --- arrays (batch odometry) ----------------------------------------------------------------------
def counter_readings(ticks, names) -> np.ndarray:
    """Readings ``(..., N, n)`` as an array that keeps them exact.

    NumPy integer arrays are kept as they are (no copy); lists of Python integers become
    int64, uint64 (beyond 2**63, e.g. a 64-bit unsigned counter) or, when they fit neither,
    an object array of Python ints, never float64 (which would round them beyond 2**53).
    Floats are allowed: float64 when every integer among them is a float exactly, else (floats
    mixed with integers beyond 2**53) an object array of the exact numbers (ints, and the
    Fraction a non-integral float holds), so that the increments are exact, as the streaming
    estimator takes them. Bools, complex numbers, text, unordered containers (sets, dicts) and
    anything else are refused, naming the sample.
    """
    arr = as_reading_array(ticks, names, "ticks")
    if arr.dtype.kind == "O" or (arr.dtype.kind == "f" and not isinstance(ticks, np.ndarray)):
        arr = _exact_from_python(ticks, arr, names)  # float64 or object only when not all integers fit
    kind = arr.dtype.kind
    if kind not in "iufO":
        raise OdometryInputError(f"ticks: expected real numbers for wheels {names}, got dtype {arr.dtype}")
    if kind == "f" and arr.dtype != np.float64:
        arr = arr.astype(np.float64)
    return arr


def as_reading_array(values, names, what: str) -> np.ndarray:
    """``values`` as a NumPy array; Python containers are checked first (:func:`nested_problem`)."""
    if isinstance(values, np.ndarray):
        return values
    why = container_problem(values) or (
        f"a {type(values).__name__} is not a sequence" if isinstance(values, Iterator) else None
    )
    if why is not None:
        raise OdometryInputError(f"{what}: {why}; give readings as a list, tuple or array (..., N, {len(names)})")
    try:
        arr = np.asarray(values)
    except (ValueError, TypeError):
        arr = None
    if arr is None or arr.dtype.kind in "OSUV":
        problem = nested_problem(values, names, what)
        if problem is not None:
            raise problem
        if arr is None:
            raise OdometryInputError(f"{what}: expected an array (..., N, {len(names)}) of numbers for wheels {names}")
    return arr


def _exact_from_python(ticks, converted: np.ndarray, names) -> np.ndarray:
    """Integer readings given as Python objects: int64, uint64 or object of ints, exactly."""
    obj = np.array(ticks, dtype=object)
    if obj.dtype != object or obj.ndim == 0:
        return converted
    flat = obj.ravel()
    integral = [isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) for v in flat]
    if not all(integral):
        for v in flat:
            if not _is_number(v):
                raise OdometryInputError(f"ticks: reading {show_number(v)} for wheels {names} is not a number")
        if any(ok and abs(int(v)) > FLOAT_EXACT for ok, v in zip(integral, flat, strict=True)):
            # floats would round these integers: every reading as the exact number it is
            # (non-finite floats stay floats and are refused at their sample)
            exact = np.empty(len(flat), dtype=object)
            exact[:] = [v if ok else _exact_or_non_finite(float(v)) for ok, v in zip(integral, flat, strict=True)]
            return exact.reshape(obj.shape)
        return obj.astype(np.float64)
    values = [int(v) for v in flat]
    if not values or (min(values) >= INT64_MIN and max(values) <= INT64_MAX):
        return np.array(values, dtype=np.int64).reshape(obj.shape)
    if min(values) >= 0 and max(values) < UINT64_END:
        return np.array(values, dtype=np.uint64).reshape(obj.shape)
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out.reshape(obj.shape)


def _exact_or_non_finite(value: float):
    """A float reading as the exact number it holds (:func:`exact_value`), or itself if NaN or inf."""
    return exact_value(value) if math.isfinite(value) else value


# --- the first problem of a block -------------------------------------------------------------------
@dataclass(frozen=True, order=True)
class Problem:
    """A refused sample: ordered by sample, then rank (:data:`RANKS`), trial and wheel.
    ``describe()`` gives the message, only for the problem reported (a later one may involve
    values that cannot be described, such as the difference of a NaN)."""

    sample: int
    rank: int
    trial: tuple = ()
    wheel: int = -1
    describe: Callable[[], str] = field(default=str, compare=False)

    def error(self) -> OdometryInputError:
        return at_sample(self.describe(), self.sample, self.trial)


def at_sample(detail: str, sample: int, trial: tuple = ()) -> OdometryInputError:
    """:class:`OdometryInputError` for ``sample`` (of ``trial``), with ``detail`` kept apart."""
    if trial:
        detail += f" (trial {trial})"
    return OdometryInputError(f"sample {sample}: {detail}", sample=sample, detail=detail)


def raise_at(detail: str, sample: int, trial: tuple = ()) -> None:
    raise at_sample(detail, sample, trial)


def earliest(mask: np.ndarray, wheels: bool):
    """``(row, trial, wheel)`` of the first True of ``mask`` ``(..., rows[, n])`` in row order
    (then trial, then wheel; wheel -1 without a wheel axis), or None."""
    if not np.any(mask):
        return None
    rows_first = np.moveaxis(mask, -2 if wheels else -1, 0)
    idx = [int(i) for i in np.unravel_index(int(np.argmax(np.ascontiguousarray(rows_first))), rows_first.shape)]
    row = idx.pop(0)
    wheel = idx.pop() if wheels else -1
    return row, tuple(idx), wheel


def problem_at(mask, wheels: bool, offset: int, rank: str, describe) -> Problem | None:
    """The first True of ``mask`` as a :class:`Problem` (row r is sample ``r + offset``);
    ``describe(row, trial, wheel)`` gives its detail."""
    found = earliest(mask, wheels)
    if found is None:
        return None
    row, trial, wheel = found
    return Problem(row + offset, RANKS[rank], trial, wheel, lambda: describe(row, trial, wheel))


def first_bad(mask, what: str, names=None, offset: int = 0) -> None:
    """Raise naming the first sample (and trial and wheel) where ``mask`` ``(..., m[, n])`` is True."""
    wheels = names is not None
    found = earliest(mask, wheels)
    if found is not None:
        row, trial, wheel = found
        raise_at(what + (f", wheel {names[wheel]!r}" if wheels else ""), row + offset, trial)


def timestamp_problem(value) -> str | None:
    """Why ``value`` cannot be a timestamp [s]: a bool, text, a complex number or any other
    object that is no real number (None if it is one; finiteness is checked with the intervals).
    The streaming estimator asks this of each timestamp, batch odometry of each it cannot read
    as a float, so both refuse the same sample."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        return f"timestamp must be a number [s], got {shorten(value)}"
    return None


def time_problems(t: np.ndarray, offset: int) -> tuple[np.ndarray, list[Problem]]:
    """Intervals ``(..., m)`` [s] of the timestamps ``t`` ``(..., m + 1)`` (row 0 is sample
    ``offset``), and the first non-finite timestamp and first interval that is not a positive
    finite number."""
    with np.errstate(over="ignore", invalid="ignore"):  # refused below
        dt = np.diff(t, axis=-1)
    if np.all(dt > 0) and np.all(dt < np.inf):
        return dt, []
    found = [
        problem_at(~np.isfinite(t), False, offset, "time", lambda *_: "t: non-finite timestamp"),
        problem_at(
            ~(dt > 0),
            False,
            offset + 1,
            "order",
            lambda *_: "t: timestamps must increase strictly (repeated or going back)",
        ),
        problem_at(~(dt < np.inf), False, offset + 1, "order", lambda *_: "t: interval between timestamps too long"),
    ]
    return dt, [p for p in found if p is not None]


def check_times(t: np.ndarray, offset: int) -> np.ndarray:
    """Intervals ``(..., m)`` [s] of ``t`` ``(..., m + 1)``; raises for the first bad timestamp."""
    dt, problems = time_problems(t, offset)
    if problems:
        raise min(problems).error()
    return dt


@dataclass
class Carry:
    """What the next block needs of the previous one: its last increment ``(..., 1, n)`` and
    interval ``(..., 1)``, for the change-of-speed rule across the block boundary."""

    delta: np.ndarray | None = None
    dt: np.ndarray | None = None


def block_increments(
    rules,
    t: np.ndarray,
    values: np.ndarray,
    offset: int,
    carry: Carry,
    unit: str = "ticks",
    pending=None,
    motion=None,
) -> tuple[np.ndarray, np.ndarray]:
    """Checked increments of one block: ``(dt (..., m), delta (..., m, n))`` [s, ``unit`` as
    float] of ``values`` ``(..., m + 1, n)`` (readings from :func:`counter_readings`, or wheel
    angles [rad] for ``unit="rad"``) at times ``t`` ``(..., m + 1)``; row 0 is sample ``offset``.

    Raises :class:`OdometryInputError` for the earliest refused sample (module docstring), or
    ``pending`` (a :class:`Problem` found elsewhere, e.g. a steering angle) if it comes first
    and lies in this block. ``motion(dt, delta, offset)``, if given, is called with the
    intervals before the first of those problems and returns the first whose body increment is
    refused (a :class:`Problem` of rank ``"motion"``) or None. ``carry`` links the blocks and is
    updated. Increments beyond the float range are +-inf (refused by ``motion``).
    """
    names = [r.wheel for r in rules]
    dt, found_in_times = time_problems(t, offset)
    problems: list[Problem | None] = list(found_in_times)
    unreadable = non_finite(values)
    if unreadable is not None:
        what = "ticks: non-finite reading" if unit == "ticks" else "angles: non-finite wheel angle"
        problems.append(problem_at(unreadable, True, offset, "reading", lambda r, tr, j: f"{what}, wheel {names[j]!r}"))
    if unit == "ticks":
        problems += _range_problems(rules, values, offset)
        exact = _exact_differences(rules, values)
        with np.errstate(over="ignore", invalid="ignore"):  # NaN readings, endless intervals: refused as such
            delta = as_floats(exact)
            bad = ~(np.abs(exact if exact.dtype == object else delta) <= _limits(rules, dt))
        for j, r in enumerate(rules):
            if r.bits == 64 and exact.dtype.kind == "i":  # -2**63: half the range, no float between it and the limit
                bad[..., j] |= exact[..., j] == INT64_MIN
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            exact = delta = np.diff(values, axis=-2)
            limit = np.stack([np.broadcast_to(r.angle_limit(dt), dt.shape) for r in rules], axis=-1)
            bad = ~(np.abs(delta) <= limit)

    def jump(row, trial, j):
        gap = _at(dt, trial, row)
        if unit != "ticks":
            return rules[j].jump_message(float(delta[_trial_index(delta, trial) + (row, j)]), gap, unit)
        d = _exact_difference_at(rules[j], values, trial, row, j)
        ends = _readings_at(values, trial, row, j)
        hint = rules[j].wrap_hint(d, gap, *_previous(delta, dt, carry, trial, row, j), readings=ends)
        return rules[j].jump_message(d, gap, hint=hint)

    problems.append(problem_at(bad, True, offset + 1, "jump", jump))
    problems.append(_change_problem(rules, dt, delta, values, offset, carry, unit))
    if pending is not None and pending.sample <= offset + dt.shape[-1]:
        problems.append(pending)
    found = [p for p in problems if p is not None]
    first = min(found) if found else None
    clean = dt.shape[-1] if first is None else first.sample - offset - 1  # intervals before it
    if motion is not None and clean > 0:
        refused = motion(dt[..., :clean], delta[..., :clean, :], offset)
        if refused is not None:
            raise refused.error()
    if first is not None:
        raise first.error()
    carry.delta, carry.dt = delta[..., -1:, :], dt[..., -1:]
    return dt, delta


def non_finite(values: np.ndarray) -> np.ndarray | None:
    """Mask of the readings that are not finite numbers (float NaN or inf, also inside an object
    array of exact readings, :func:`counter_readings`), or None for integer arrays."""
    if values.dtype.kind == "f":
        return ~np.isfinite(values)
    if values.dtype == object:
        flags = [isinstance(v, float) and not math.isfinite(v) for v in values.reshape(-1)]
        return np.array(flags, dtype=bool).reshape(values.shape)
    return None


def _at(array: np.ndarray, trial: tuple, row: int) -> float:
    """``array[trial + (row,)]`` of an array ``(..., m)`` that broadcasts against the trials."""
    lead = array.shape[:-1]
    index = tuple(i if n > 1 else 0 for i, n in zip(trial[len(trial) - len(lead) :], lead, strict=True))
    return float(array[index + (row,)])


def _previous(delta, dt, carry: Carry, trial: tuple, row: int, j: int) -> tuple[float | None, float | None]:
    """(increment [float], interval [s]) before the interval ``row`` of this block (None, None
    before the first interval)."""
    if row > 0:
        return float(delta[_trial_index(delta, trial) + (row - 1, j)]), _at(dt, trial, row - 1)
    if carry.delta is None or carry.dt is None:
        return None, None
    return float(carry.delta[_trial_index(carry.delta, trial) + (0, j)]), _at(carry.dt, trial, 0)


def _trial_index(array: np.ndarray, trial: tuple) -> tuple:
    lead = array.shape[:-2]
    return tuple(i if n > 1 else 0 for i, n in zip(trial[len(trial) - len(lead) :], lead, strict=True))


def _change_problem(rules, dt, delta, values, offset: int, carry: Carry, unit: str) -> Problem | None:
    """The first pair of consecutive increments that breaks the change-of-speed rule: the pair
    across the block boundary (``carry``), then the pairs within the block."""
    bounds = [r.change_bounds(unit) for r in rules]
    if all(a == math.inf for a, _ in bounds):
        return None
    a, slack = (np.array([b[i] for b in bounds]) for i in range(2))
    if len(set(bounds)) == 1:
        a, slack = a[:1], slack[:1]  # one bound for all wheels: limits (..., m, 1)
    pairs = []  # (increments before, after, intervals before, after, interval index of `after` in the block)
    if carry.delta is not None and carry.dt is not None:
        pairs.append((carry.delta, delta[..., :1, :], carry.dt, dt[..., :1], 0))
    pairs.append((delta[..., :-1, :], delta[..., 1:, :], dt[..., :-1], dt[..., 1:], 1))
    for d0, d1, dt0, dt1, shift in pairs:
        if d1.shape[-2] == 0:
            continue
        bad = _speed_changes(a, slack, d0, d1, dt0[..., None], dt1[..., None])

        def describe(p, trial, j, d0=d0, d1=d1, dt0=dt0, dt1=dt1, shift=shift):
            before, after = float(d0[_trial_index(d0, trial) + (p, j)]), float(d1[_trial_index(d1, trial) + (p, j)])
            g0, g1 = _at(dt0, trial, p), _at(dt1, trial, p)
            if unit != "ticks":
                return rules[j].change_message(before, after, g0, g1, unit)
            exact = _exact_difference_at(rules[j], values, trial, p + shift, j)
            ends = _readings_at(values, trial, p + shift, j)
            hint = rules[j].wrap_hint(exact, g1, before, g0, readings=ends)
            return rules[j].change_message(before, exact, g0, g1, unit, hint)

        found = problem_at(bad, True, offset + 1 + shift, "change", describe)
        if found is not None:
            return found
    return None


def _speed_changes(a, slack, d0, d1, dt0, dt1) -> np.ndarray:
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


def _range_problems(rules, readings, offset: int) -> list[Problem]:
    out = []
    for bits, cols in _by_bits(rules):
        low, high = -(1 << (bits - 1)), 1 << bits
        block = readings[..., cols]
        if block.size == 0:
            continue
        if readings.dtype.kind == "f":
            ok = block.min() >= low and block.max() < high
        elif readings.dtype.kind in "iu":
            ok = int(block.min()) >= low and int(block.max()) < high
        else:  # exact Python numbers (ints, Fractions) and non-finite floats: compared one by one
            ok = False
        if ok:
            continue
        if readings.dtype.kind == "u":
            mask = block >= np.uint64(high) if high < UINT64_END else np.zeros(block.shape, bool)
        else:
            mask = ~((block >= low) & (block < high))
        found = earliest(mask, True)
        if found is None:
            continue
        row, trial, c = found
        j = cols[c]
        message = rules[j].range_message(readings[trial + (row, j)])
        out.append(Problem(row + offset, RANKS["range"], trial, j, partial(str, message)))
    return out


def _exact_differences(rules, readings: np.ndarray) -> np.ndarray:
    """Row-to-row differences, wrapped per wheel, exact: int64 or object (ints), or float64
    (the exact difference rounded once)."""
    kind = readings.dtype.kind
    if kind == "f":
        return _float_differences(rules, readings)
    if kind == "O":
        delta = np.diff(readings, axis=-2)
        for bits, cols in _by_bits(rules):
            half = 1 << (bits - 1)
            delta[..., cols] = (delta[..., cols] + half) % (2 * half) - half
        return delta
    wide = readings.dtype in (np.int64, np.uint64)
    if not wide:
        readings = readings.astype(np.int64)
    unsigned = readings.view(np.uint64)
    du = np.subtract(unsigned[..., 1:, :], unsigned[..., :-1, :])  # modulo 2**64: exact for wrapping
    delta = du.view(np.int64)
    for bits, cols in _by_bits(rules):
        if bits < 64:
            half = 1 << (bits - 1)
            delta[..., cols] = ((du[..., cols] + np.uint64(half)) & np.uint64(2 * half - 1)).view(np.int64) - half
    plain = [j for j, r in enumerate(rules) if r.bits is None]
    if wide and plain and readings.shape[-2] > 1:
        values = readings if len(plain) == len(rules) else readings[..., plain]
        if int(values.max()) - int(values.min()) > INT64_MAX:
            # a true difference may not fit int64: redo these columns with Python ints
            exact = delta.astype(object)
            exact[..., plain] = np.diff(readings[..., plain].astype(object), axis=-2)
            return exact
    return delta


def _float_differences(rules, readings: np.ndarray) -> np.ndarray:
    """Wrapped differences of float readings, each the exact wrapped difference rounded once.

    Without a width ``b - a`` is that already (IEEE subtraction is correctly rounded). With a
    width ``2**bits``: TwoSum gives ``b - a = s + e`` exactly (Knuth, TAOCP vol. 2, 4.2.2);
    ``s - n 2**bits`` with ``n = rint(s / 2**bits)`` in -2..2 is exact (Sterbenz: ``s`` lies within
    a factor 2 of ``n 2**bits``), and adding ``e`` rounds once. ``(s + half) % full - half``,
    the old way, lost every increment of a 64-bit counter: ``s + 2**63`` has no bits left for it.
    """
    a, b = readings[..., :-1, :], readings[..., 1:, :]
    delta = b - a
    for bits, cols in _by_bits(rules):
        full = 2.0**bits
        ra, rb, s = a[..., cols], b[..., cols], delta[..., cols]
        b_virtual = s + ra
        a_virtual = s - b_virtual
        e = (rb - b_virtual) + (-ra - a_virtual)
        delta[..., cols] = (s - np.rint(s / full) * full) + e
    return delta


def _exact_difference_at(rule, readings, trial: tuple, k: int, j: int):
    """The wrapped increment between rows k and k+1 of wheel j, as an exact Python number."""
    a, b = _readings_at(readings, trial, k, j)
    return wrap_exact(b - a, rule.bits)


def _readings_at(readings, trial: tuple, k: int, j: int) -> tuple:
    """Rows k and k+1 of wheel j as exact Python numbers (:func:`exact_value`)."""
    index = _trial_index(readings, trial)
    return exact_value(readings[index + (k, j)]), exact_value(readings[index + (k + 1, j)])


def _by_bits(rules):
    for bits in sorted({r.bits for r in rules if r.bits is not None}):
        yield bits, [j for j, r in enumerate(rules) if r.bits == bits]


def _limits(rules, dt: np.ndarray) -> np.ndarray:
    """Per-wheel jump limits ``(..., m, n)`` or ``(..., m, 1)`` when all wheels share one."""
    if len(set((r.rate, r.max_jump, r.bits) for r in rules)) == 1:
        return np.asarray(rules[0].limit(dt))[..., None]
    return np.stack([np.broadcast_to(r.limit(dt), dt.shape) for r in rules], axis=-1)


def wheel_increments(rules, t, values, block: int, unit: str = "ticks", pending=None, motion=None) -> np.ndarray:
    """All checked increments ``(..., N - 1, n)`` [``unit``], computed ``block`` samples at a time
    (:func:`block_increments`)."""
    m = values.shape[-2] - 1
    lead = np.broadcast_shapes(values.shape[:-2], t.shape[:-1])
    out = np.empty(lead + (m, len(rules)))
    carry = Carry()
    for s0 in range(0, m, block):
        s1 = min(m, s0 + block)
        _, out[..., s0:s1, :] = block_increments(
            rules, t[..., s0 : s1 + 1], values[..., s0 : s1 + 1, :], s0, carry, unit, pending, motion
        )
    if pending is not None:  # in the last block at the latest, unless there is no interval
        raise pending.error()
    return out
