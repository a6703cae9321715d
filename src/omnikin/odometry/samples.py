"""The samples of a block of readings: timestamps, non-finite values and the first problem.

The rule is applied to the float increments (the exact increments rounded once), by batch and
streaming odometry alike, in the order of the samples. Within one sample the checks run in the
order of :data:`RANKS`, so both report the same first problem.

A :class:`Problem` is a refusal that has not been raised yet (its sample and rank); batch
odometry keeps the earliest (:func:`earliest`) and raises it as an
:class:`~omnikin.errors.OdometryInputError` naming the sample (:func:`at_sample`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..common.messages import shorten
from ..errors import OdometryInputError

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


def non_finite(values: np.ndarray) -> np.ndarray | None:
    """Mask of the readings that are not finite numbers (float NaN or inf, also inside an object
    array of exact readings, :func:`~omnikin.odometry.counters.counter_readings`), or None for integer arrays."""
    if values.dtype.kind == "f":
        return ~np.isfinite(values)
    if values.dtype == object:
        flags = [isinstance(v, float) and not math.isfinite(v) for v in values.reshape(-1)]
        return np.array(flags, dtype=bool).reshape(values.shape)
    return None
