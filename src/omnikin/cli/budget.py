"""Memory and time budgets of the commands: ``--max-memory SIZE`` and ``--max-time DURATION``.

A simulation's rate and path, the messages of a bag, the length of a trajectory file, the
number of Monte Carlo trials: omnikin cannot bound these itself, and a hostile or mistyped
value (``--rate 1e4 --path 'line 1e4'``) would end in a ``MemoryError`` traceback, or a machine
swapping for an hour. A command estimates what the job needs from the sizes it is given and
calls :func:`require` before the work; a job over budget is refused with one line naming the
estimate, the limit, and what to change (the check of :mod:`omnikin.common.resource_limits`, which
the Python entry points make too, with the limits named as options here)::

    omnikin: error: simulate: about 6.1G of memory for 2.2e+07 samples, more than
    --max-memory 2G; lower --rate or shorten --path, or raise --max-memory

The limits are the options of :func:`add_budget_options`. Each command's estimates use
measured costs (memory rounded up; time per item on the fast side, so a job is refused for
time only when clearly too long). A job estimated to take longer than :data:`NOTE_AFTER`
seconds says so on standard error before it starts.

For ``--trials`` / ``--runs`` of ``omnikin umbmark``: ``add_budget_options(parser)`` and
``require(args, "umbmark", memory=..., seconds=..., hint="lower --trials or --runs")``.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import re
import sys
from dataclasses import dataclass

from ..common.messages import shorten
from ..common.number_text import PLAIN_NUMBER
from ..common.resource_limits import (
    DEFAULT_MEMORY,
    DEFAULT_TIME,
    LimitNames,
    format_bytes,
    format_seconds,
    require_within,
)
from ..errors import ResourceLimitError

OPTIONS = LimitNames("--max-memory", "--max-time")
"""The limits as the command line names them."""

NOTE_AFTER = 30.0
"""Jobs estimated to take longer than this [s] say so before starting."""

SIZE_SUFFIXES = {
    "": 1,
    "B": 1,
    **{f"{letter}{tail}": 1024**power for power, letter in enumerate("KMGT", 1) for tail in ("", "iB")},
    **{letter: 1024**power for power, letter in enumerate("kmgt", 1)},
}
"""The units of ``--max-memory`` [bytes per unit], exactly as written: none or ``B`` (bytes),
``K``, ``M``, ``G``, ``T`` (also lower-case) or ``KiB``, ``MiB``, ``GiB``, ``TiB``: powers of
1024. Not ``GB`` or ``Gb`` (10**9 bytes or bits elsewhere), nor anything else."""

SIZE_HELP = "bytes, or a number with K, M, G or T, powers of 1024 (also KiB, MiB, GiB, TiB), e.g. 512M, 2G"
"""How :data:`SIZE_SUFFIXES` is described in the help and in messages."""

TIME_SUFFIXES = {"": 1.0, "s": 1.0, "m": 60.0, "min": 60.0, "h": 3600.0, "d": 86400.0}
"""The units of ``--max-time`` [seconds per unit], exactly as written: none or ``s`` (seconds),
``m`` or ``min`` (minutes), ``h`` (hours), ``d`` (days)."""

TIME_HELP = "seconds, or a number with s, m (or min), h or d, e.g. 90, 10m, 2h"
"""How :data:`TIME_SUFFIXES` is described in the help and in messages."""

_UNIT = re.compile(r"[A-Za-z]*\Z")
"""The unit of a quantity: the ASCII letters that end it."""

# Measured costs of reading and writing bags (rosbags 0.11, CPython 3.11, tracemalloc peaks of
# 67,000-sample runs of mecanum4), shared by ``bag``, ``simulate --bag`` and ``view --replay``:
# memory rounded up; times on the fast side (measured 25 us per message written, 27 us read on a
# loaded 2-core machine), so that only clearly oversized jobs are refused.
POSE_BYTES = 600
"""Per pose (or joint-state) message read and its line of text [bytes] (``bag export``,
``view --replay``; measured 545)."""
MESSAGE_SECONDS = 10e-6
"""Reading (deserializing) or writing (serializing) one message [s]."""
RUN_SAMPLE_SECONDS = 4 * MESSAGE_SECONDS
"""A run's bag (``simulate --bag``, ``track --bag``): per sample, its four messages made and
written."""
LOG_ROW_SECONDS = 5e-6
"""A tick log (``simulate --log``, ``track --log``): per sample, its row made and written
(measured 19 us)."""
LARGEST_MESSAGE_SHARE = 64
"""One message may use at most 1/64 of --max-memory (its bytes decoded into Python objects)."""


@dataclass(frozen=True)
class Budget:
    """What one command may use: ``memory`` [bytes] and ``seconds`` [s] of wall time."""

    memory: float = DEFAULT_MEMORY
    seconds: float = DEFAULT_TIME

    @classmethod
    def of(cls, args) -> Budget:
        """The budget given on the command line (defaults for options the command lacks)."""
        if isinstance(args, Budget):
            return args
        return cls(getattr(args, "max_memory", None) or DEFAULT_MEMORY, getattr(args, "max_time", None) or DEFAULT_TIME)

    def messages(self, bytes_each: float) -> int:
        """How many items of ``bytes_each`` bytes fit the memory budget."""
        return max(1, int(self.memory // bytes_each))


# --- options ---------------------------------------------------------------------------------------------
def quantity(text: str, units: dict, what: str, spelling: str) -> float:
    """The value of ``text``, a number in the one grammar of numbers
    (:data:`omnikin.common.number_text.PLAIN_NUMBER`: no blanks, ``_``, other scripts' digits, ``inf``)
    followed at once by one of ``units`` (suffix -> scale), times the unit's scale; else an
    argparse usage error naming ``what`` (``"size"``) and how it is written (``spelling``)."""
    found = _UNIT.search(text) if isinstance(text, str) else None
    unit = found.group() if found else ""
    digits = text[: len(text) - len(unit)] if isinstance(text, str) else text
    if not isinstance(digits, str) or not PLAIN_NUMBER.fullmatch(digits):
        raise argparse.ArgumentTypeError(f"not a {what}: {shorten(text)} ({spelling})")
    if unit not in units:
        raise argparse.ArgumentTypeError(f"{shorten(text)}: unknown unit {shorten(unit)} of a {what} ({spelling})")
    value = float(digits) * units[unit]
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{shorten(text)} is too large for a {what} (not a finite number)")
    return value


def parse_size(text: str) -> int:
    """A memory size [bytes]: bytes, or a number with a unit of :data:`SIZE_SUFFIXES` (``512M``,
    ``1.5G``, ``2GiB``), at least one byte."""
    value = quantity(text, SIZE_SUFFIXES, "size", SIZE_HELP)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{shorten(text)}: a size must be at least one byte")
    return int(value)


def parse_duration(text: str) -> float:
    """A duration [s]: seconds, or a number with a unit of :data:`TIME_SUFFIXES` (``90``,
    ``10m``, ``2h``), positive."""
    value = quantity(text, TIME_SUFFIXES, "duration", TIME_HELP)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{shorten(text)}: a duration must be positive")
    return value


def add_budget_options(parser, *, time: bool = True) -> None:
    """Add ``--max-memory SIZE`` (and, with ``time``, ``--max-time DURATION``) to ``parser``."""
    parser.add_argument(
        "--max-memory",
        type=parse_size,
        default=DEFAULT_MEMORY,
        metavar="SIZE",
        help=f"refuse to start a job estimated to need more memory ({SIZE_HELP}; default "
        f"{format_bytes(DEFAULT_MEMORY)})",
    )
    if time:
        parser.add_argument(
            "--max-time",
            type=parse_duration,
            default=DEFAULT_TIME,
            metavar="DURATION",
            help=f"refuse to start a job estimated to take longer ({TIME_HELP}; "
            f"default {format_seconds(DEFAULT_TIME)})",
        )


# --- checks -----------------------------------------------------------------------------------------------
def require(
    args, what: str, *, memory: float | None = None, seconds: float | None = None, hint: str, size: str = ""
) -> None:
    """Refuse (:class:`ResourceLimitError`) a job estimated to need more than the budget of
    ``args`` (a parsed command line or a :class:`Budget`); else, if it will take long, say so on
    standard error.

    ``what``: the command (``"simulate"``); ``memory`` [bytes] and ``seconds`` [s]: the
    estimates; ``hint``: what to change (``"lower --rate or shorten --path"``); ``size``: the
    size in the job's own terms (``"2.2e+07 samples"``), for the message.
    """
    budget = Budget.of(args)
    require_within(
        what,
        memory=memory,
        seconds=seconds,
        max_memory=budget.memory,
        max_time=budget.seconds,
        names=OPTIONS,
        hint=hint,
        size=size,
    )
    if seconds is not None and seconds > NOTE_AFTER:
        of = f" for {size}" if size else ""
        print(f"omnikin: note: {what}: this will take about {format_seconds(seconds)}{of}", file=sys.stderr)


@contextlib.contextmanager
def explained(args):
    """Add the option that sets the limit to a :class:`ResourceLimitError` raised by a library
    call given a bound derived from the budget (a bag reader's ``max_messages``)."""
    try:
        yield
    except ResourceLimitError as exc:
        option = OPTIONS.time if exc.unit == "seconds" else OPTIONS.memory
        value = Budget.of(args).seconds if exc.unit == "seconds" else Budget.of(args).memory
        shown = format_seconds(value) if exc.unit == "seconds" else format_bytes(value)
        raise ResourceLimitError(
            f"{exc} (the limit follows from {option} {shown}; raise it to allow more)",
            needed=exc.needed,
            limit=exc.limit,
            unit=exc.unit,
        ) from None
