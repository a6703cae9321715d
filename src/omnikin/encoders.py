"""Encoder ticks -> wheel angles (``docs/conventions.md``, Odometry).

``angle = 2 pi ticks / (ticks_per_rev gear_ratio)``, negated when ``invert``.
Counters of ``bits`` bits wrap: the increment between two samples is taken
modulo ``2**bits`` into ``[-2**(bits-1), 2**(bits-1))``. A wrapped increment can
never exceed half the counter range, so a jump of more than half the range is
detected only through a physical bound: ``max_jump`` ticks per sample, or the
wheel's ``max_speed`` (with a 50 % margin plus 2 ticks of quantisation), or an
increment equal to exactly half the range (its direction is undecidable).
"""

from __future__ import annotations

import numpy as np

from .errors import OdometryInputError


def wrap_ticks(delta, bits: int | None):
    """Counter increments wrapped to ``[-2**(bits-1), 2**(bits-1))`` (unchanged if None).

    Integer arrays are wrapped with a bit mask (exact, fast), others with a modulo.
    """
    if bits is None:
        return delta
    delta = np.asarray(delta)
    half = 2 ** (bits - 1)
    if np.issubdtype(delta.dtype, np.integer) and bits < 63:
        return ((delta + half) & (2 * half - 1)) - half
    full = float(2 * half)
    return (delta.astype(float) + full / 2) % full - full / 2


def check_bits(bits: int | None) -> int | None:
    if bits is None:
        return None
    if isinstance(bits, bool) or not isinstance(bits, (int, np.integer)) or not 2 <= bits <= 64:
        raise OdometryInputError(f"counter_bits must be an integer from 2 to 64, got {bits!r}")
    return int(bits)


def jump_limits(wheels, dt, bits: int | None, max_jump=None) -> np.ndarray:
    """Largest plausible |tick increment| per wheel for intervals ``dt`` ``(..., N)``.

    Shape ``(..., N, n)``; infinity where nothing bounds it.
    """
    dt = np.asarray(dt, dtype=float)
    out = np.full(dt.shape + (len(wheels),), np.inf)
    for j, w in enumerate(wheels):
        if max_jump is not None:
            out[..., j] = max_jump
        elif w.max_speed is not None and w.encoder is not None:
            out[..., j] = 1.5 * w.max_speed * dt / abs(w.encoder.rad_per_tick) + 2.0
    if bits is not None:
        out = np.minimum(out, 2.0 ** (bits - 1) - 0.5)
    return out


def tick_increments(wheels, t, ticks, bits: int | None = None, max_jump=None) -> np.ndarray:
    """Checked counter increments ``(..., N - 1, n)`` [ticks] between consecutive samples.

    ``t`` ``(..., N)`` [s] must increase strictly; ``ticks`` ``(..., N, n)`` are raw
    counter readings. Raises :class:`OdometryInputError` naming the sample and
    wheel for NaN, time going backwards or standing still, readings outside the
    counter range and impossible jumps.
    """
    names = [w.name for w in wheels]
    bits = check_bits(bits)
    tk = np.asarray(ticks)
    if tk.ndim < 2 or tk.shape[-1] != len(wheels):
        raise OdometryInputError(f"ticks: expected shape (..., N, {len(wheels)}) for wheels {names}, got {tk.shape}")
    if not np.issubdtype(tk.dtype, np.number):
        raise OdometryInputError(f"ticks: expected numbers, got dtype {tk.dtype}")
    t = np.asarray(t, dtype=float)
    if t.shape[-1:] != tk.shape[-2:-1]:
        raise OdometryInputError(f"t: expected {tk.shape[-2]} timestamps to match ticks {tk.shape}, got shape {t.shape}")
    _first_bad(~np.isfinite(t), "t: non-finite timestamp")
    if np.issubdtype(tk.dtype, np.floating):
        _first_bad(~np.isfinite(tk), "ticks: non-finite reading", names)
    if bits is not None:
        _first_bad((tk < -(2 ** (bits - 1))) | (tk >= 2 ** bits),
                   f"ticks: reading outside the range of a {bits}-bit counter", names)
    dt = np.diff(t, axis=-1)
    _first_bad(dt <= 0, "t: timestamps must increase strictly (repeated or going back)", offset=1)
    delta = wrap_ticks(np.diff(tk, axis=-2), bits)
    bounded = max_jump is not None or any(w.max_speed is not None for w in wheels)
    if bounded or bits is not None:
        limit = jump_limits(wheels, dt, bits, max_jump)
        _first_bad(np.abs(delta) > limit, "ticks: impossible jump (faster than the wheel can turn, or half the "
                   "counter range)", names, offset=1)
    return delta.astype(float, copy=False)


def ticks_to_angle_increments(wheels, t, ticks, bits: int | None = None, max_jump=None) -> np.ndarray:
    """Wheel angle increments ``(..., N - 1, n)`` [rad] between consecutive samples.

    See :func:`tick_increments` for the checks.
    """
    scale = np.array([w.encoder.rad_per_tick for w in wheels])
    return tick_increments(wheels, t, ticks, bits, max_jump) * scale


def _first_bad(mask, what: str, names=None, offset: int = 0) -> None:
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
