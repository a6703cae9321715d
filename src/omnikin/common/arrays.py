"""Small input checks shared by the core: real numbers, ranges, shapes and finiteness with clear messages.

Every public function that takes numbers (twists, wheel speeds, poses, steering angles,
headings, times) reads them with :func:`as_real_array` or :func:`as_components`: only real
numbers are accepted (NumPy integer and floating types, Python ``int`` and ``float``).
Booleans, complex numbers, strings, ``None`` and other objects are refused with one line
saying what arrived, instead of being converted silently (``np.asarray(x, dtype=float)``
drops an imaginary part with only a ``ComplexWarning``, reads ``True`` as 1 and ``"0.5"`` as
0.5).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterator, Mapping, MappingView, Sequence
from collections.abc import Set as AbstractSet

import numpy as np

from ..errors import InputError
from .messages import digits_apart, one_line, shorten

REAL_KINDS = frozenset("iuf")
"""NumPy dtype kinds read as real numbers: signed and unsigned integers, floating point."""


def _is_real_scalar(x) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_))


def _holds_bool(value) -> bool:
    """Whether nested lists and tuples hold a boolean (which NumPy would turn into 0 or 1)."""
    if isinstance(value, (bool, np.bool_)):
        return True
    if isinstance(value, (list, tuple)):
        return any(_holds_bool(v) for v in value)
    return isinstance(value, np.ndarray) and value.dtype.kind == "b"


def as_real_array(value, name: str, error: type[InputError] = InputError) -> np.ndarray:
    """``value`` as a float64 array, refusing anything but real numbers (module docstring).

    ``name`` names the argument in the one-line message (``twist: expected real numbers,
    got complex128 values``); ``error`` is the class raised (a subclass of InputError, e.g.
    :class:`~omnikin.errors.OdometryInputError` for timestamps). Shapes are not checked here.
    """
    if isinstance(value, np.ndarray):
        arr = value
    else:
        try:
            arr = np.asarray(value)
        except (ValueError, TypeError) as exc:  # ragged nesting, unconvertible objects
            raise error(f"{name}: not a rectangular array of numbers ({one_line(exc, 120)})") from None
    kind = arr.dtype.kind
    if kind in REAL_KINDS:
        if isinstance(value, (list, tuple)) and _holds_bool(value):  # NumPy reads [0.2, True] as floats
            raise error(f"{name}: expected real numbers (int or float), got a boolean among them")
        return arr.astype(float, copy=False)
    if kind == "O":  # a list mixing Python ints beyond int64 with floats, Decimals, None, ...
        for bad in arr.reshape(-1):
            if not _is_real_scalar(bad):
                raise error(f"{name}: expected real numbers, got {type(bad).__name__} {shorten(bad, 40)}")
        try:
            return arr.astype(float)
        except OverflowError:
            raise error(f"{name}: a number too large for a float") from None
    what = {
        "b": "booleans",
        "c": "complex numbers",
        "U": "strings",
        "S": "bytes",
        "M": "datetimes",
        "m": "time deltas",
        "V": "structured values",
    }.get(kind, "values")
    raise error(f"{name}: expected real numbers (int or float), got {what} ({arr.dtype})")


def as_real_scalar(value, name: str, error: type[InputError] = InputError) -> float:
    """One real number (module docstring) as a Python float."""
    arr = as_real_array(value, name, error)
    if arr.ndim != 0:
        raise error(f"{name}: expected one number, got an array of shape {arr.shape}")
    return float(arr)


def as_components(value, size: int, name: str) -> np.ndarray:
    """Return ``value`` as a float array of shape ``(..., size)`` of real numbers.

    Raises :class:`~omnikin.errors.InputError` saying what was expected and what arrived, e.g.
    ``twist: expected shape (..., 3), got (4,)`` or ``twist: expected real numbers (int or
    float), got complex numbers (complex128)``.
    """
    arr = as_real_array(value, name)
    if arr.ndim == 0 or arr.shape[-1] != size:
        raise InputError(f"{name}: expected shape (..., {size}), got {arr.shape}")
    return arr


def require_finite(arr: np.ndarray, name: str) -> None:
    """Raise if ``arr`` holds NaN or infinity, naming the first bad index."""
    bad = ~np.isfinite(arr)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"{name}: non-finite value {float(arr[index])} at index {index}")


def range_problem(value, low: float, high: float, unit: str = "") -> str | None:
    """None if ``value`` is a finite real number in ``[low, high]``, else what is wrong with it.

    The one range check of omnikin's parameters (wheels, physical fields, robot files, UMBmark
    sides, rates): Python or NumPy ``int`` and ``float`` only (not ``bool``, not ``"0.5"``).
    The text starts with ``must`` so that the caller prefixes what it checks:
    ``f"wheel 'w1': radius {problem}"``. A value outside the range is printed with the digits
    that tell it from the bound (:func:`~omnikin.common.messages.digits_apart`), the bounds with as many
    or 10.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        return f"must be a number, got {shorten(value)}"
    try:
        x = float(value)
    except OverflowError:  # an int beyond the largest float: outside every range
        return f"{_span(low, high, unit, 10)}, got {shorten(value)}"
    if not math.isfinite(x):
        return f"must be finite, got {shorten(value)}"
    if not low <= x <= high:
        p = digits_apart(x, low if x < low else high)
        return f"{_span(low, high, unit, max(p, 10))}, got {x:.{p}g}"
    return None


def _span(low: float, high: float, unit: str, digits: int) -> str:
    """``must lie in [low, high] unit``, the bounds printed with ``digits`` significant digits."""
    return f"must lie in [{low:.{digits}g}, {high:.{digits}g}]{' ' + unit if unit else ''}"


def whole_problem(value, low: int, high: int) -> str | None:
    """None if ``value`` is a whole number (Python or NumPy integer, not ``bool``, not ``2.0``)
    in ``[low, high]``, else what is wrong with it (phrased like :func:`range_problem`)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        return f"must be a whole number from {low} to {high}, got {shorten(value)}"
    return None


TEXT_TYPES = (str, bytes, bytearray, memoryview)
"""Text and bytes: sequences, but of characters, never numbers."""


def container_problem(value, order: str = "the wheels' order") -> str | None:
    """Why ``value`` cannot hold numbers in a defined order (``order``: what the order means,
    for the message), or None if it can.

    Lists, tuples and other sequences, NumPy arrays, array-likes (``__array__``) and iterators
    (a generator, ``map``) give their items in a defined order. A set or a dict (or its views)
    does not: ``{0.5, 3.0, 0.25}`` iterates in hash order, not as written. Text and bytes are
    not numbers (``b'\\x05\\x07\\x09'`` would be taken as 5, 7, 9). Anything else is not a sequence.
    """
    if isinstance(value, np.ndarray):
        return None
    if isinstance(value, TEXT_TYPES):
        return f"{type(value).__name__} {shorten(value, 40)} is text, not numbers"
    if isinstance(value, (AbstractSet, Mapping, MappingView)):
        return f"a {type(value).__name__} has no defined order ({order} would be lost)"
    if isinstance(value, (Sequence, Iterator)) or hasattr(value, "__array__") or hasattr(value, "__array_interface__"):
        return None
    return f"a {type(value).__name__} is not a sequence"


def frozen(array) -> np.ndarray:
    """A read-only copy of ``array`` that stays read-only: its data lives in an immutable
    ``bytes`` object, so ``setflags(write=True)`` raises ``ValueError`` on it, on its ``base``
    and on every view of it (an array owning its data could be made writeable again).

    For arrays an object keeps and hands out (a robot's cached matrices and limits): a caller
    cannot change the object's state through them; copy one to modify it."""
    a = np.ascontiguousarray(array)
    return np.frombuffer(a.tobytes(), dtype=a.dtype).reshape(a.shape)
