"""The incremental encoder a wheel carries: ticks per revolution, gear ratio, direction and the
width of its counter (``docs/conventions.md``, robot file ``encoder:``).

``angle = 2 pi ticks / (ticks_per_rev gear_ratio)`` [rad], negated when ``invert``; what a
counter of ``counter_bits`` bits reads and how its increments wrap is
:mod:`omnikin.odometry.counters`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.arrays import range_problem, whole_problem
from ..common.messages import shorten
from ..errors import InputError

TICKS_PER_REV_RANGE = (1.0, 2.0**32)
"""Encoder ticks per revolution of the encoder shaft: from a single index pulse to a 32-bit
absolute encoder."""
COUNTER_BITS_RANGE = (2, 64)
"""Width of an encoder's hardware counter [bits]: from a 2-bit quadrature state to a 64-bit count."""
GEAR_RATIO_RANGE = (1e-3, 1e4)
"""Encoder revolutions per wheel revolution: multi-stage gearboxes stay below 1e4."""


def _require(problem: str | None, what: str) -> None:
    if problem is not None:
        raise InputError(f"{what} {problem}")


@dataclass(frozen=True)
class Encoder:
    """Incremental encoder on a wheel: ``angle = 2 pi ticks / (ticks_per_rev gear_ratio)``.

    Parameters
    ----------
    ticks_per_rev : float
        Ticks per encoder revolution, 1 .. 2**32 (the robot file's ``encoder.ticks_per_rev``).
    gear_ratio : float, default 1.0
        Encoder turns per wheel turn, 0.001 .. 10000.
    invert : bool, default False
        True when the counts run against the wheel's positive spin (then :attr:`rad_per_tick`
        is negative).
    counter_bits : int or None, default None
        Width of the hardware counter whose readings are logged (2 .. 64): its readings wrap
        modulo ``2**counter_bits`` (:mod:`omnikin.odometry.counters`). None: they never wrap.

    Raises
    ------
    InputError
        A value outside its range (docs/conventions.md, "Ranges"), not a number, or ``invert``
        not a bool; the message names the field.
    """

    ticks_per_rev: float
    gear_ratio: float = 1.0
    invert: bool = False
    counter_bits: int | None = None

    def __post_init__(self):
        if self.counter_bits is not None:
            _require(whole_problem(self.counter_bits, *COUNTER_BITS_RANGE), "encoder: counter_bits")
        _require(range_problem(self.ticks_per_rev, *TICKS_PER_REV_RANGE), "encoder: ticks_per_rev")
        _require(range_problem(self.gear_ratio, *GEAR_RATIO_RANGE), "encoder: gear_ratio")
        if not isinstance(self.invert, (bool, np.bool_)):
            raise InputError(f"encoder: invert must be True or False, got {shorten(self.invert)}")

    @property
    def rad_per_tick(self) -> float:
        """Wheel angle per tick [rad], negative when ``invert``."""
        sign = -1.0 if self.invert else 1.0
        return sign * 2.0 * np.pi / (self.ticks_per_rev * self.gear_ratio)
