"""The wheel back-end interface of the runtime.

A back-end takes wheel commands and gives wheel measurements:

* ``write(t, speeds, steer=None)``: speeds [rad/s] of the robot's rolling wheels (file
  order) and, with steerable wheels, their steering angles [rad];
* ``read(t) -> WheelState``: positions [rad] and speeds [rad/s] of the encoded wheels
  (file order), steering angles, and the time of the measurement;
* ``stats() -> dict``: link statistics for diagnostics; ``close()``.


Back-ends: :class:`omnikin.simulation.backend.SimBackend` (the robot as built, simulated),
:class:`omnikin.runtime.serial_backend.SerialBackend` (wheel controllers on serial links).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class WheelState:
    """One measurement: time [s], encoded wheels' positions [rad] and speeds [rad/s], steering [rad]."""

    t: float
    positions: np.ndarray
    velocities: np.ndarray
    steer: np.ndarray | None = None


class WheelBackend(Protocol):
    """What the runtime needs from wheels (module docstring)."""

    def write(self, t: float, speeds: np.ndarray, steer: np.ndarray | None = None) -> None: ...

    def read(self, t: float) -> WheelState: ...

    def stats(self) -> dict: ...

    def close(self) -> None: ...
