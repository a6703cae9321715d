"""Memory and time limits of a job: the one check that refuses a job before it starts.

A job whose size the user controls (a simulation's rate and path, the messages of a bag, the
number of Monte Carlo trials) is sized first: its memory [bytes] and wall time [s] are
estimated from the sizes it is given, and :func:`require_within` refuses it when either
estimate is over its limit, with one line naming the estimate, the limit and what to change::

    simulate: about 6.1G of memory for 2.2e+07 samples, more than --max-memory 2G; lower
    --rate or shorten --path, or raise --max-memory

The command line (options ``--max-memory`` and ``--max-time``, :mod:`omnikin.cli.budget`) and
the Python entry points (arguments ``max_memory`` and ``max_time``,
:func:`omnikin.run_umbmark`) make the same check; each names the limits its own way
(:class:`LimitNames`). Sizes are written in powers of 1024 (``2G``, ``1.5G``, ``300M``:
:func:`format_bytes`), durations in s, min, h or days (:func:`format_seconds`).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from ..errors import InputError, ResourceLimitError
from .messages import shorten

DEFAULT_MEMORY = 2 * 1024**3
"""Default memory limit of a job [bytes]: 2 GiB."""

DEFAULT_TIME = 3600.0
"""Default time limit of a job [s]: one hour."""

SIZE_UNITS = {"": 1, "b": 1, "k": 1024, "m": 1024**2, "g": 1024**3, "t": 1024**4}
"""Size suffixes [bytes], powers of 1024 (``K``, ``M``, ``G``, ``T``)."""


@dataclass(frozen=True)
class LimitNames:
    """How a caller names its two limits in messages: ``memory`` (``"--max-memory"`` on the
    command line, ``"max_memory"`` in Python) and ``time``."""

    memory: str
    time: str


def check_limits(max_memory, max_time, names: LimitNames) -> tuple[float, float]:
    """``(max_memory [bytes], max_time [s])`` as floats, each a number > 0 (``inf``: no limit);
    else an :class:`~omnikin.errors.InputError` naming the limit as ``names`` does."""
    out = []
    for value, name, unit in ((max_memory, names.memory, "bytes"), (max_time, names.time, "seconds")):
        limit = _as_float(value) if isinstance(value, numbers.Real) and not isinstance(value, bool) else math.nan
        if not limit > 0:  # also NaN: not a number, or not one
            raise InputError(f"{name} must be a number of {unit} > 0 (inf: no limit), got {shorten(value)}")
        out.append(limit)
    return out[0], out[1]


def _as_float(value: numbers.Real) -> float:
    try:
        return float(value)
    except OverflowError:  # an integer beyond floats: as good as no limit, or as far below zero
        return -math.inf if value < 0 else math.inf


def require_within(
    what: str,
    *,
    memory: float | None = None,
    seconds: float | None = None,
    max_memory=DEFAULT_MEMORY,
    max_time=DEFAULT_TIME,
    names: LimitNames,
    hint: str,
    size: str = "",
) -> None:
    """Refuse (:class:`~omnikin.errors.ResourceLimitError`) a job estimated to need more than
    ``max_memory`` [bytes] or ``max_time`` [s], memory first, in one line (module docstring).

    ``what``: the job (``"simulate"``); ``memory`` [bytes] and ``seconds`` [s]: its estimates
    (None: not estimated); ``names``: how the caller names the limits; ``hint``: what to change
    (``"lower --rate or shorten --path"``); ``size``: the size in the job's own terms
    (``"2.2e+07 samples"``). The error carries ``needed``, ``limit`` and ``unit``
    (``"bytes"`` or ``"seconds"``). The limits are checked first (:func:`check_limits`).
    """
    max_memory, max_time = check_limits(max_memory, max_time, names)
    of = f" for {size}" if size else ""
    if memory is not None and not memory <= max_memory:
        raise ResourceLimitError(
            f"{what}: about {format_bytes(memory)} of memory{of}, more than {names.memory} "
            f"{format_bytes(max_memory)}; {hint}, or raise {names.memory}",
            needed=memory,
            limit=max_memory,
            unit="bytes",
        )
    if seconds is not None and not seconds <= max_time:
        raise ResourceLimitError(
            f"{what}: about {format_seconds(seconds)}{of}, more than {names.time} "
            f"{format_seconds(max_time)}; {hint}, or raise {names.time}",
            needed=seconds,
            limit=max_time,
            unit="seconds",
        )


def format_bytes(n: float) -> str:
    """A size [bytes] in powers of 1024, three significant digits: ``2G``, ``1.5G``, ``300M``,
    ``12K``, ``100 bytes``; ``inf`` (or ``nan``) as such."""
    if not math.isfinite(n):
        return str(n)
    for unit in ("T", "G", "M", "K"):
        scale = SIZE_UNITS[unit.lower()]
        if n >= scale:
            return f"{n / scale:.3g}{unit}"
    return f"{n:.0f} bytes"


def format_seconds(s: float) -> str:
    """A duration [s], three significant digits: ``45 s``, ``12 min``, ``3.5 h``, ``40 days``;
    ``inf`` (or ``nan``) as such."""
    if not math.isfinite(s):
        return str(s)
    if s < 120:
        return f"{s:.3g} s"
    if s < 3600:
        return f"{s / 60:.3g} min"
    if s < 3 * 86400:
        return f"{s / 3600:.3g} h"
    return f"{s / 86400:.3g} days"
