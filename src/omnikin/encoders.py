"""Encoder ticks -> wheel angles (``docs/conventions.md``, Odometry).

``angle = 2 pi ticks / (ticks_per_rev gear_ratio)``, negated when ``invert``.
Counters of ``bits`` bits wrap: the increment between two samples is taken
modulo ``2**bits`` into ``[-2**(bits-1), 2**(bits-1))``; readings may be stored
signed or unsigned. A wrapped increment can never exceed half the counter range, so
a jump of more than half the range is caught only through a physical bound: an
explicit ``max_jump`` [ticks per sample], or the wheel's ``max_speed`` (bound
``JUMP_MARGIN * max_speed * dt / rad_per_tick + QUANTISATION_SLACK`` ticks), and an
increment of exactly half the range is refused (its direction is undecidable).

This module is the single source of those rules: batch odometry uses the array
functions, the streaming estimator :func:`jump_limit` and :func:`wrap_scalar`.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import OdometryInputError

JUMP_MARGIN = 1.5
"""A wheel may turn this much faster than its ``max_speed`` before a jump is impossible."""
QUANTISATION_SLACK = 2.0
"""Ticks allowed on top of the speed bound (quantisation at both ends of an interval)."""


def check_bits(bits: int | None) -> int | None:
    if bits is None:
        return None
    if isinstance(bits, bool) or not isinstance(bits, (int, np.integer)) or not 2 <= bits <= 64:
        raise OdometryInputError(f"counter_bits must be an integer from 2 to 64, got {bits!r}")
    return int(bits)


def check_max_jump(max_jump) -> float | None:
    if max_jump is None:
        return None
    if isinstance(max_jump, bool) or not isinstance(max_jump, (int, float, np.number)) \
            or not math.isfinite(max_jump) or max_jump <= 0:
        raise OdometryInputError(f"max_jump must be a finite number of ticks > 0, got {max_jump!r}")
    return float(max_jump)


def tick_rate(wheel, max_jump) -> float | None:
    """Bound on |ticks| per second of ``wheel`` from its ``max_speed`` (None if unbounded or
    when an explicit ``max_jump`` replaces it)."""
    if max_jump is not None or wheel.max_speed is None or wheel.encoder is None:
        return None
    return JUMP_MARGIN * wheel.max_speed / abs(wheel.encoder.rad_per_tick)


def jump_limit(max_jump: float | None, rate: float | None, dt, bits: int | None):
    """Largest plausible |increment| [ticks] over ``dt`` (scalar or array; inf if unbounded)."""
    if max_jump is not None:
        limit = max_jump + 0.0 * np.asarray(dt) if np.ndim(dt) else max_jump
    elif rate is not None:
        limit = rate * dt + QUANTISATION_SLACK
    else:
        limit = np.full(np.shape(dt), np.inf) if np.ndim(dt) else math.inf
    if bits is not None:
        half = 2.0 ** (bits - 1) - 0.5
        limit = np.minimum(limit, half) if np.ndim(limit) else min(limit, half)
    return limit


def wrap_scalar(delta, bits: int | None):
    """One increment (Python int or float) wrapped into the counter's range."""
    if bits is None:
        return delta
    half = 1 << (bits - 1)
    if isinstance(delta, int):
        return ((delta + half) & (2 * half - 1)) - half
    return (delta + half) % (2 * half) - half


def wrap_ticks(delta, bits: int | None):
    """Increments wrapped to ``[-2**(bits-1), 2**(bits-1))`` (unchanged if ``bits`` is None).

    int64 arrays wrap exactly: their arithmetic is modulo 2**64, and a mask reduces it
    to ``bits``; float arrays use a modulo.
    """
    if bits is None:
        return delta
    delta = np.asarray(delta)
    if delta.dtype == np.int64:
        if bits == 64:
            return delta
        half = np.int64(1 << (bits - 1))
        with np.errstate(over="ignore"):
            return ((delta + half) & np.int64((1 << bits) - 1)) - half
    full = float(2 ** bits)
    return (delta.astype(float) + full / 2) % full - full / 2


def as_counter_array(ticks, names) -> np.ndarray:
    """Readings as int64 (integer input, unsigned kept modulo 2**64) or float64."""
    tk = np.asarray(ticks)
    if tk.dtype == bool or not np.issubdtype(tk.dtype, np.number) or np.iscomplexobj(tk):
        raise OdometryInputError(f"ticks: expected real numbers for wheels {names}, got dtype {tk.dtype}")
    if np.issubdtype(tk.dtype, np.integer):
        return tk.astype(np.int64, casting="unsafe")
    return tk.astype(np.float64)


def tick_increments(wheels, t, ticks, bits: int | None = None, max_jump=None) -> np.ndarray:
    """Checked counter increments ``(..., N - 1, n)`` [ticks] between consecutive samples.

    ``t`` ``(..., N)`` [s] must increase strictly; ``ticks`` ``(..., N, n)`` are raw
    counter readings. Raises :class:`OdometryInputError` naming the sample and
    wheel for NaN, time going backwards or standing still, readings outside the
    counter range and impossible jumps.
    """
    names = [w.name for w in wheels]
    bits = check_bits(bits)
    max_jump = check_max_jump(max_jump)
    tk = as_counter_array(ticks, names)
    if tk.ndim < 2 or tk.shape[-1] != len(wheels):
        raise OdometryInputError(f"ticks: expected shape (..., N, {len(wheels)}) for wheels {names}, got {tk.shape}")
    if tk.shape[-2] < 1:
        raise OdometryInputError("ticks: no sample")
    t = np.asarray(t, dtype=float)
    if t.shape[-1:] != tk.shape[-2:-1]:
        raise OdometryInputError(f"t: expected {tk.shape[-2]} timestamps to match ticks {tk.shape}, got shape {t.shape}")
    first_bad(~np.isfinite(t), "t: non-finite timestamp")
    if tk.dtype == np.float64:
        first_bad(~np.isfinite(tk), "ticks: non-finite reading", names)
    if bits is not None and bits < 64:
        low, high = -(2 ** (bits - 1)), 2 ** bits
        if np.asarray(ticks).dtype != np.uint64:
            first_bad((tk < low) | (tk >= high), f"ticks: reading outside the range of a {bits}-bit counter", names)
    dt = np.diff(t, axis=-1)
    first_bad(dt <= 0, "t: timestamps must increase strictly (repeated or going back)", offset=1)
    with np.errstate(over="ignore"):
        delta = wrap_ticks(np.diff(tk, axis=-2), bits)
    if bits is not None or max_jump is not None or any(w.max_speed is not None for w in wheels):
        limit = np.stack([np.broadcast_to(jump_limit(max_jump, tick_rate(w, max_jump), dt, bits), dt.shape)
                          for w in wheels], axis=-1)
        half_range = (delta == -(2 ** (bits - 1))) if bits is not None else False
        first_bad((np.abs(delta) > limit) | half_range,
                   "ticks: impossible jump (faster than the wheel can turn, or half the counter range)",
                   names, offset=1)
    return delta.astype(float, copy=False)


def first_bad(mask, what: str, names=None, offset: int = 0) -> None:
    """Raise naming the first sample (and trial and wheel) where ``mask`` is True."""
    if not np.any(mask):
        return
    idx = [int(i) for i in np.argwhere(mask)[0]]
    wheel = names[idx.pop()] if names is not None else None
    msg = f"{what} at sample {idx.pop() + offset}"
    if idx:
        msg += f" of trial {tuple(idx)}"
    if wheel is not None:
        msg += f", wheel {wheel!r}"
    raise OdometryInputError(msg)
