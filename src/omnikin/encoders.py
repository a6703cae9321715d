"""Encoder ticks -> wheel angle increments: every rule on counters, wrap-around and jumps
(``docs/conventions.md``, Odometry).

``angle = 2 pi ticks / (ticks_per_rev gear_ratio)``, negated when ``invert``.

Readings are exact integers (or, from the library, floats). A counter of ``bits`` bits
(``counter_bits``) wraps: the increment between two samples is the difference taken
modulo ``2**bits`` into ``[-2**(bits-1), 2**(bits-1))``; its readings may be stored
signed or unsigned, so they must lie in ``[-2**(bits-1), 2**bits)``. Integer arithmetic
is exact for readings of any integer type and size (int64, uint64 beyond 2**63, Python
ints of any length).

A jump no wheel could make in one sample is refused. Each wheel has a speed bound
[rad/s]: ``JUMP_MARGIN`` times an explicit ``max_wheel_speed``, else ``JUMP_MARGIN`` times the
wheel's ``max_speed``, else a rim speed of :data:`DEFAULT_RIM_SPEED` over the wheel radius.
An increment is impossible when ``|d| > bound * dt / |rad_per_tick| + QUANTISATION_SLACK``
ticks (or ``|d| > max_jump`` when an explicit ``max_jump`` [ticks] is given); with a counter
width also when ``|d| > 2**(bits-1) - 0.5`` (exactly half the range: direction undecidable).
Without a counter width this is what turns a wrapped counter into an error instead of a
wrong pose: a 16-bit wrap is a jump of about 65 000 ticks.

This module is the single source of those rules: batch odometry uses the array functions
(:func:`checked_increments`), the streaming estimator :class:`CounterRule`,
:func:`wrap_scalar` and :func:`in_counter_range`, and the generated streaming kernel the same
expressions (:mod:`omnikin._stream_kernel`).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from .errors import InputError, OdometryInputError

JUMP_MARGIN = 1.5
"""A wheel may turn this much faster than its speed limit before a jump is impossible."""
QUANTISATION_SLACK = 2.0
"""Ticks allowed on top of the speed bound (quantisation at both ends of an interval)."""
DEFAULT_RIM_SPEED = 100.0
"""Rim speed [m/s] no wheel of a mobile robot reaches (360 km/h; fast mobile robots drive
5-10 m/s): the speed bound of a wheel without ``max_speed``. At 100 Hz it lets a 4 cm wheel
with 600 ticks/rev move 2300 ticks per sample, while a wrapped 16-bit counter jumps by
about 65 000."""
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
UINT64_END = 2**64
FLOAT_EXACT = 2**53
"""Integers beyond this are not all floats: readings there must stay integers."""


# --- options ----------------------------------------------------------------------------------
def check_bits(bits, what: str = "counter_bits") -> int | None:
    if bits is None:
        return None
    if isinstance(bits, (bool, np.bool_)) or not isinstance(bits, (int, np.integer)) or not 2 <= bits <= 64:
        raise OdometryInputError(f"{what} must be a whole number from 2 to 64, got {bits!r}")
    return int(bits)


def check_max_jump(max_jump) -> float | None:
    return _positive(max_jump, "max_jump", "a finite number of ticks > 0")


def check_max_wheel_speed(speed) -> float | None:
    return _positive(speed, "max_wheel_speed", "a finite wheel speed > 0 [rad/s]")


def _positive(value, name: str, what: str) -> float | None:
    if value is None:
        return None
    if (
        isinstance(value, (bool, np.bool_))
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
        or value <= 0
    ):
        raise OdometryInputError(f"{name} must be {what}, got {value!r}")
    return float(value)


# --- the rule of one wheel --------------------------------------------------------------------
@dataclass(frozen=True)
class CounterRule:
    """How the readings of one encoded wheel are differenced and checked.

    ``bits``: counter width (None: no wrap-around); ``rad_per_tick`` [rad] (negative when
    inverted); ``speed``: the wheel speed bound [rad/s] (margin included) and ``source``
    where it comes from; ``max_jump`` [ticks]: an explicit bound replacing the speed bound.
    """

    wheel: str
    bits: int | None
    rad_per_tick: float
    speed: float
    source: str
    max_jump: float | None = None

    @property
    def rate(self) -> float:
        """Speed bound in ticks per second."""
        return self.speed / abs(self.rad_per_tick)

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

    def jump_message(self, delta, dt, unit: str = "ticks") -> str:
        """Why ``delta`` [``unit``: ticks, or rad for wheel angles] over ``dt`` [s] is
        impossible, with the way out (one line)."""
        if self.max_jump is not None:
            why = f"more than max_jump={self.max_jump:g} ticks"
        else:
            why = f"faster than {self.speed:.6g} rad/s ({self.source})"
        if unit != "ticks":
            return f"impossible jump of {show_number(delta)} {unit} in {dt:.6g} s, wheel {self.wheel!r}: {why}"
        if self.bits is not None:
            return (
                f"impossible jump of {show_number(delta)} {unit} in {dt:.6g} s, wheel {self.wheel!r}: {why}, "
                f"or half the range of its {self.bits}-bit counter"
            )
        return (
            f"impossible jump of {show_number(delta)} {unit} in {dt:.6g} s, wheel {self.wheel!r}: {why}; "
            f"if its counter wraps, give the counter width (counter_bits, --counter-bits or encoder.counter_bits)"
        )

    def range_message(self, value) -> str:
        half = 1 << ((self.bits or 1) - 1)
        return (
            f"tick reading {show_number(value)} outside the range of a {self.bits}-bit counter "
            f"({-half} .. {2 * half - 1}), wheel {self.wheel!r}"
        )


def counter_rules(wheels, counter_bits=None, max_jump=None, max_wheel_speed=None) -> tuple[CounterRule, ...]:
    """One :class:`CounterRule` per encoded wheel.

    ``counter_bits`` applies to every wheel; a wheel whose robot file gives another
    ``encoder.counter_bits`` is an error (neither is guessed to win). Without it each wheel
    uses its own ``encoder.counter_bits`` (or none).
    """
    bits = check_bits(counter_bits)
    max_jump = check_max_jump(max_jump)
    speed = check_max_wheel_speed(max_wheel_speed)
    rules = []
    for w in wheels:
        own = w.encoder.counter_bits
        if bits is not None and own is not None and own != bits:
            raise InputError(
                f"counter_bits={bits} contradicts encoder.counter_bits: {own} of wheel {w.name!r} "
                f"in the robot file; give one of them"
            )
        if speed is not None:
            bound, source = JUMP_MARGIN * speed, f"{JUMP_MARGIN:g} x max_wheel_speed {speed:g} rad/s"
        elif w.max_speed is not None:
            bound, source = JUMP_MARGIN * w.max_speed, f"{JUMP_MARGIN:g} x its max_speed {w.max_speed:g} rad/s"
        else:
            bound, source = DEFAULT_RIM_SPEED / w.radius, f"{DEFAULT_RIM_SPEED:g} m/s at the rim"
        rules.append(
            CounterRule(w.name, bits if bits is not None else own, w.encoder.rad_per_tick, bound, source, max_jump)
        )
    return tuple(rules)


def show_number(value) -> str:
    """A reading or increment for a message, bounded in length (Python ints may be huge)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        v = int(value)
        return str(v) if v.bit_length() <= 128 else f"<an integer of {v.bit_length()} bits>"
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return str(value)


# --- scalars (the streaming estimator) ---------------------------------------------------------
def wrap_scalar(delta, bits: int | None):
    """One increment (Python int or float) wrapped into the counter's range."""
    if bits is None:
        return delta
    half = 1 << (bits - 1)
    if isinstance(delta, int):
        return ((delta + half) & (2 * half - 1)) - half
    return (delta + half) % (2 * half) - half


def in_counter_range(value, bits: int | None) -> bool:
    """True if a reading fits a ``bits``-bit counter, stored signed or unsigned."""
    return bits is None or -(1 << (bits - 1)) <= value < (1 << bits)


# --- arrays (batch odometry) ----------------------------------------------------------------------
def counter_readings(ticks, names) -> np.ndarray:
    """Readings ``(..., N, n)`` as an array that keeps them exact.

    NumPy integer arrays are kept as they are (no copy); lists of Python integers become
    int64, uint64 (beyond 2**63, e.g. a 64-bit unsigned counter) or, when they fit neither,
    an object array of Python ints, never float64 (which would round them beyond 2**53).
    Floats are allowed; bools, complex numbers and anything else are refused.
    """
    arr = ticks if isinstance(ticks, np.ndarray) else np.asarray(ticks)
    if arr.dtype.kind == "O" or (arr.dtype.kind == "f" and not isinstance(ticks, np.ndarray)):
        arr = _exact_from_python(ticks, arr, names)  # float64 or object only when not all integers fit
    kind = arr.dtype.kind
    if kind not in "iufO":
        raise OdometryInputError(f"ticks: expected real numbers for wheels {names}, got dtype {arr.dtype}")
    if kind == "f" and arr.dtype != np.float64:
        arr = arr.astype(np.float64)
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
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
                raise OdometryInputError(f"ticks: reading {show_number(v)} for wheels {names} is not a number")
        if any(ok and abs(int(v)) > FLOAT_EXACT for ok, v in zip(integral, flat, strict=True)):
            raise OdometryInputError(
                "ticks: integer readings beyond 2**53 mixed with floats would be rounded; give integers only"
            )
        return obj.astype(np.float64)
    values = [int(v) for v in flat]
    if not values or (min(values) >= INT64_MIN and max(values) <= INT64_MAX):
        return np.array(values, dtype=np.int64).reshape(obj.shape)
    if min(values) >= 0 and max(values) < UINT64_END:
        return np.array(values, dtype=np.uint64).reshape(obj.shape)
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out.reshape(obj.shape)


def first_bad(mask, what: str, names=None, offset: int = 0) -> None:
    """Raise naming the first sample (and trial and wheel) where ``mask`` ``(..., m[, n])`` is
    True; row k of the mask is sample ``k + offset``."""
    if not np.any(mask):
        return
    idx = [int(i) for i in np.argwhere(mask)[0]]
    wheel = names[idx.pop()] if names is not None else None
    raise_at(what + (f", wheel {wheel!r}" if wheel is not None else ""), idx.pop() + offset, tuple(idx))


def raise_at(detail: str, sample: int, trial: tuple = ()) -> None:
    """Raise :class:`OdometryInputError` for ``sample`` (of ``trial``), with ``detail`` kept apart."""
    if trial:
        detail += f" (trial {trial})"
    raise OdometryInputError(f"sample {sample}: {detail}", sample=sample, detail=detail)


def check_times(t: np.ndarray, offset: int) -> np.ndarray:
    """Intervals ``(..., m)`` [s] of the timestamps ``t`` ``(..., m + 1)``; raises naming the
    sample if one is not finite or time does not increase strictly."""
    dt = np.diff(t, axis=-1)
    if np.all(dt > 0) and np.all(dt < np.inf):
        return dt
    first_bad(~np.isfinite(t), "t: non-finite timestamp", offset=offset)
    first_bad(dt <= 0, "t: timestamps must increase strictly (repeated or going back)", offset=offset + 1)
    first_bad(~np.isfinite(dt), "t: interval between timestamps too long", offset=offset + 1)
    return dt


def checked_increments(rules, readings: np.ndarray, dt: np.ndarray, offset: int) -> np.ndarray:
    """Checked counter increments ``(..., m, n)`` [ticks, float] between consecutive rows of
    ``readings`` ``(..., m + 1, n)`` (from :func:`counter_readings`), ``dt`` ``(..., m)`` [s].

    ``offset`` is the sample index of the first row (for messages). Raises
    :class:`OdometryInputError` naming sample, trial and wheel for a non-finite reading,
    a reading outside its counter's range and an impossible jump.
    """
    names = [r.wheel for r in rules]
    kind = readings.dtype.kind
    if kind == "f":
        first_bad(~np.isfinite(readings), "ticks: non-finite reading", names, offset)
    _check_ranges(rules, readings, offset)
    delta = _exact_differences(rules, readings)
    limit = _limits(rules, dt)
    if delta.dtype == object:
        bad = np.abs(delta) > limit
        d = delta.astype(np.float64)
    else:
        d = delta.astype(np.float64, copy=False)
        bad = np.abs(d) > limit
    if delta.dtype.kind != "f":
        for j, r in enumerate(rules):
            if r.bits == 64:  # -2**63, half a 64-bit range: no float between it and the limit
                bad[..., j] |= delta[..., j] == INT64_MIN
    delta = d
    if np.any(bad):
        idx = [int(i) for i in np.argwhere(bad)[0]]
        j = idx.pop()
        k = idx.pop()
        rule = rules[j]
        gap = float(np.broadcast_to(dt, bad.shape[:-1])[tuple(idx) + (k,)])
        raise_at(
            rule.jump_message(_exact_difference_at(rule, readings, tuple(idx), k, j), gap), k + 1 + offset, tuple(idx)
        )
    return delta


def _check_ranges(rules, readings, offset: int) -> None:
    for bits in sorted({r.bits for r in rules if r.bits is not None}):
        cols = [j for j, r in enumerate(rules) if r.bits == bits]
        low, high = -(1 << (bits - 1)), 1 << bits
        block = readings[..., cols]
        if block.size == 0:
            continue
        if readings.dtype.kind == "f":
            ok = block.min() >= low and block.max() < high
        else:
            ok = int(block.min()) >= low and int(block.max()) < high
        if not ok:
            if readings.dtype.kind == "u":
                mask = block >= np.uint64(high) if high < UINT64_END else np.zeros(block.shape, bool)
            else:
                mask = (block < low) | (block >= high)
            idx = [int(i) for i in np.argwhere(mask)[0]]
            j = cols[idx.pop()]
            k = idx.pop()
            raise_at(rules[j].range_message(readings[tuple(idx) + (k, j)]), k + offset, tuple(idx))


def _exact_differences(rules, readings: np.ndarray) -> np.ndarray:
    """Row-to-row differences, wrapped per wheel, exact: int64 or object (ints), or float64."""
    kind = readings.dtype.kind
    if kind == "f":
        delta = np.diff(readings, axis=-2)
        for bits, cols in _by_bits(rules):
            full = float(2**bits)
            delta[..., cols] = (delta[..., cols] + full / 2) % full - full / 2
        return delta
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


def _exact_difference_at(rule, readings, trial: tuple, k: int, j: int):
    """The wrapped increment between rows k and k+1 of wheel j, as an exact Python number."""
    a, b = readings[trial + (k, j)], readings[trial + (k + 1, j)]
    if readings.dtype.kind == "f":
        return wrap_scalar(float(b) - float(a), rule.bits)
    return wrap_scalar(int(b) - int(a), rule.bits)


def _by_bits(rules):
    for bits in sorted({r.bits for r in rules if r.bits is not None}):
        yield bits, [j for j, r in enumerate(rules) if r.bits == bits]


def _limits(rules, dt: np.ndarray) -> np.ndarray:
    """Per-wheel jump limits ``(..., m, n)`` or ``(..., m, 1)`` when all wheels share one."""
    if len(set((r.rate, r.max_jump, r.bits) for r in rules)) == 1:
        return np.asarray(rules[0].limit(dt))[..., None]
    return np.stack([np.broadcast_to(r.limit(dt), dt.shape) for r in rules], axis=-1)


def wheel_increments(rules, t, readings, block: int) -> np.ndarray:
    """All checked increments ``(..., N - 1, n)`` [ticks], computed ``block`` samples at a time."""
    m = readings.shape[-2] - 1
    lead = np.broadcast_shapes(readings.shape[:-2], t.shape[:-1])
    out = np.empty(lead + (m, len(rules)))
    for s0 in range(0, m, block):
        s1 = min(m, s0 + block)
        dt = check_times(t[..., s0 : s1 + 1], s0)
        out[..., s0:s1, :] = checked_increments(rules, readings[..., s0 : s1 + 1, :], dt, s0)
    return out


def check_angle_jumps(rules, delta: np.ndarray, dt: np.ndarray, offset: int = 0) -> None:
    """Raise for a wheel-angle increment [rad] no wheel could make (the speed bounds above)."""
    limit = np.stack([np.broadcast_to(r.angle_limit(dt), dt.shape) for r in rules], axis=-1)
    bad = ~(np.abs(delta) <= limit)
    if np.any(bad):
        idx = [int(i) for i in np.argwhere(bad)[0]]
        j, k = idx.pop(), idx.pop()
        gap = float(np.broadcast_to(dt, bad.shape[:-1])[tuple(idx) + (k,)])
        raise_at(rules[j].jump_message(float(delta[tuple(idx) + (k, j)]), gap, "rad"), k + 1 + offset, tuple(idx))
