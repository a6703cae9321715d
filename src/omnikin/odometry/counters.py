"""Encoder counters: readings as exact numbers and the increment of a counter that wraps
(``docs/conventions.md``, Odometry).

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

The streaming estimator uses the scalar forms (:func:`exact_increment`,
:func:`in_counter_range`, :func:`wrap_scalar`), batch odometry the arrays
(:func:`counter_readings`, :func:`wrap_exact`); the serial wheel link wraps its counts with
:func:`wrap_scalar`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Sequence
from fractions import Fraction

import numpy as np

from ..common.arrays import TEXT_TYPES, container_problem, whole_problem
from ..common.messages import shorten
from ..errors import OdometryInputError
from ..kinematics.encoder import COUNTER_BITS_RANGE
from .samples import at_sample

INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1


UINT64_END = 2**64


FLOAT_EXACT = 2**53


"""Integers beyond this are not all floats: readings there must stay integers."""


def check_bits(bits, what: str = "counter_bits") -> int | None:
    if bits is None:
        return None
    problem = whole_problem(bits, *COUNTER_BITS_RANGE)
    if problem:
        raise OdometryInputError(f"{what} {problem}")
    return int(bits)


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
    result is the wrapped value of the float ``delta``, rounded once).

    Parameters
    ----------
    delta : int or float
        The difference of two readings of the counter [ticks].
    bits : int or None
        The counter's width; None: a counter that does not wrap (``delta`` is returned as it is).

    Returns
    -------
    int or float
        ``delta`` wrapped into ``[-2**(bits-1), 2**(bits-1))`` [ticks]: an int for an int
        ``delta``, else a float.
    """
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
