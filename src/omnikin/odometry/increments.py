"""Encoder ticks -> wheel angle increments over a block of samples, every rule applied
(``docs/conventions.md``, Odometry).

:func:`wheel_increments` turns the readings of a block ``(..., m, n)`` (``m`` samples of
``n`` wheels, any leading trial axes) into increments ``(..., m - 1, n)`` [ticks or rad]: the
exact differences of :mod:`omnikin.odometry.counters`, checked against the ranges, the speed
rule and the change-of-speed rule of :mod:`omnikin.odometry.plausibility`, the earliest
problem raised as of :mod:`omnikin.odometry.samples`. :class:`Carry` holds what one block
passes to the next (the last reading, increment and interval of each wheel), so a long log is
checked block by block with the same result as at once (:func:`block_increments`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import numpy as np

from .counters import INT64_MAX, INT64_MIN, UINT64_END, as_floats, exact_value, wrap_exact
from .plausibility import jump_limits, speed_changes
from .samples import RANKS, Problem, earliest, non_finite, problem_at, time_problems


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
    float] of ``values`` ``(..., m + 1, n)`` (readings from
    :func:`~omnikin.odometry.counters.counter_readings`, or wheel angles [rad] for
    ``unit="rad"``) at times ``t`` ``(..., m + 1)``; row 0 is sample ``offset``.

    Raises :class:`~omnikin.errors.OdometryInputError` for the earliest refused sample (module
    docstring), or ``pending`` (a :class:`Problem` found elsewhere, e.g. a steering angle) if it
    comes first and lies in this block. ``motion(dt, delta, offset)``, if given, is called with the
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
            bad = ~(np.abs(exact if exact.dtype == object else delta) <= jump_limits(rules, dt))
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
        bad = speed_changes(a, slack, d0, d1, dt0[..., None], dt1[..., None])

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
