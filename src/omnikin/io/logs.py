"""Encoder logs in and trajectories out (CSV and TUM).

Tick log (CSV, comma separated, one header line): column ``t`` [s] first, then one
tick column per encoded wheel, named by the wheel (any order), and for every
steerable wheel a column ``<wheel>_steer_deg`` with its steering angle [deg].
Blank lines and lines starting with ``#`` are skipped.

Trajectory files (CSV, TUM, KITTI) are :mod:`omnikin.io.trajectories`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OdometryInputError
from ..model import Robot
from ..odometry import encoded_wheels
from .csvfile import column_problems, number, read_rows



@dataclass(frozen=True)
class TickLog:
    """A parsed tick log: ``t`` (N,), ``ticks`` (N, n_enc), ``steer`` (N, n_steer) [rad] or None.

    Rows that repeat the previous row exactly (a logger writing a sample twice) are
    dropped and their line numbers kept in ``duplicate_lines``; a repeated time with
    other readings stays in and is refused by the odometry.
    """

    t: np.ndarray
    ticks: np.ndarray
    steer: np.ndarray | None
    wheel_names: list[str]
    duplicate_lines: tuple[int, ...] = ()
    """Lines skipped because they repeat the previous sample exactly (time and readings)."""
    lines: tuple[int, ...] = ()
    """File line of each kept sample."""


def read_tick_log(path: str | Path, robot: Robot) -> TickLog:
    """Read and check a tick log for ``robot`` (see module docstring)."""
    source = str(path)
    wheels = [w.name for w in encoded_wheels(robot)]
    steer_cols = [f"{name}_steer_deg" for name in robot.steer_names]
    expected = ["t"] + wheels + steer_cols
    rows = read_rows(path, OdometryInputError)
    if not rows:
        raise OdometryInputError(f"{source}: empty log; expected a header {','.join(expected)}")
    header_line, header = rows[0]
    if not header or header[0] != "t":
        raise OdometryInputError(f"{source}: line {header_line}: the first column must be 't', got {header[:1]}; "
                                 f"expected columns {expected}")
    problems = column_problems(header, expected)
    if problems:
        raise OdometryInputError(f"{source}: line {header_line}: " + "; ".join(problems) +
                                 f"; robot {robot.name!r} expects {expected}")
    if len(rows) < 3:
        raise OdometryInputError(f"{source}: needs at least two samples, got {len(rows) - 1}")
    index = {name: header.index(name) for name in expected}
    data = np.empty((len(rows) - 1, len(expected)))
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            raise OdometryInputError(f"{source}: line {line}: {len(row)} fields, header has {len(header)}")
        for j, name in enumerate(expected):
            data[k, j] = number(row[index[name]], source, line, name, OdometryInputError)
    repeat = np.zeros(len(data), dtype=bool)
    repeat[1:] = np.all(data[1:] == data[:-1], axis=1)
    duplicates = tuple(rows[k + 1][0] for k in np.flatnonzero(repeat))
    kept_lines = tuple(rows[k + 1][0] for k in np.flatnonzero(~repeat))
    data = data[~repeat]
    if len(data) < 2:
        raise OdometryInputError(f"{source}: needs at least two distinct samples, got {len(data)}")
    ticks = data[:, 1:1 + len(wheels)]
    if np.all(ticks == np.round(ticks)) and np.all(np.abs(ticks) < 2 ** 62):
        ticks = ticks.astype(np.int64)
    steer = np.radians(data[:, 1 + len(wheels):]) if steer_cols else None
    return TickLog(data[:, 0].copy(), ticks, steer, wheels, duplicates, kept_lines)
