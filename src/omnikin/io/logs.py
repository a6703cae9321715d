"""Encoder tick logs in and out (CSV).

Tick log (CSV, comma separated, one header line): column ``t`` [s] first, then one
tick column per encoded wheel, named by the wheel (any order), and for every
steerable wheel a column ``<wheel>_steer_deg`` with its steering angle [deg].
Blank lines and lines starting with ``#`` are skipped.

Times [s] and steering angles [deg] are plain ASCII decimal numbers
(:func:`omnikin.io.csvfile.number`: ``0_1``, digits of other scripts, ``inf`` and ``nan``
are refused); the odometry refuses a steering angle outside its wheel's limits at its sample
(:func:`omnikin.odometry.batch.steer_bounds`).

Tick readings are exact integers: plain ASCII decimal digits with an optional leading
``-`` (``0x10``, ``1e3``, ``5.0``, ``1_0``, digits of other scripts and inner spaces are
refused, with file, line and column), read without passing through a float, and kept in an
array that holds them exactly (int64, or uint64 for a 64-bit unsigned counter beyond 2**63).
A reading must fit a 64-bit counter, signed or unsigned: ``-2**63 .. 2**64 - 1``.

Trajectory files (CSV, TUM, KITTI) are :mod:`omnikin.io.trajectories`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..common.messages import shorten
from ..errors import InputError, OdometryInputError
from ..kinematics.robot import Robot
from ..odometry.batch import encoded_wheels
from ..odometry.counters import INT64_MIN, UINT64_END, counter_readings
from .csvfile import column_problems, number, read_rows
from .output import write_text
from .trajectories import format_times

TICK = re.compile(r"-?[0-9]+")
"""A tick reading: ASCII digits only (Python's int() would also take '1_0', '+5', ' 5' and
other scripts' digits)."""
TICK_DIGITS = 20
"""Digits of the largest 64-bit reading, 2**64 - 1: longer text is refused before int()."""


@dataclass(frozen=True)
class TickLog:
    """A parsed tick log: ``t`` (N,), ``ticks`` (N, n_enc), ``steer`` (N, n_steer) [rad] or None.

    ``ticks`` is int64 (uint64 when a reading exceeds 2**63 - 1 and none is negative; an
    object array of Python ints when a log mixes both). Rows that repeat the previous row
    exactly (a logger writing a sample twice) are dropped and their line numbers kept in
    ``duplicate_lines``; a repeated time with other readings stays in and is refused by the
    odometry.
    """

    t: np.ndarray
    ticks: np.ndarray
    steer: np.ndarray | None
    wheel_names: list[str]
    duplicate_lines: tuple[int, ...] = ()
    """Lines skipped because they repeat the previous sample exactly (time and readings)."""
    lines: tuple[int, ...] = ()
    """File line of each kept sample."""


def tick_reading(text: str, source: str, line: int, column: str) -> int:
    """One tick reading as an exact int, or :class:`OdometryInputError` naming file, line and column."""
    where = f"{source}: line {line}, column {column!r}"
    if not TICK.fullmatch(text):
        raise OdometryInputError(
            f"{where}: not a tick reading: {shorten(text)} (expected an integer: ASCII digits "
            f"with an optional leading '-')"
        )
    if len(text.lstrip("-")) > TICK_DIGITS or not INT64_MIN <= int(text) < UINT64_END:
        raise OdometryInputError(
            f"{where}: tick reading {shorten(text)} outside the range of a 64-bit counter "
            f"({INT64_MIN} .. {UINT64_END - 1})"
        )
    return int(text)


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
        raise OdometryInputError(
            f"{source}: line {header_line}: the first column must be 't', got "
            f"{shorten(header[:1])}; expected columns {expected}"
        )
    problems = column_problems(header, expected)
    if problems:
        raise OdometryInputError(
            f"{source}: line {header_line}: " + "; ".join(problems) + f"; robot {robot.name!r} expects {expected}"
        )
    if len(rows) < 3:
        raise OdometryInputError(f"{source}: needs at least two samples, got {len(rows) - 1}")
    position = {name: k for k, name in enumerate(header)}  # a dict: linear in the number of columns
    t_col, tick_cols = position["t"], [position[name] for name in wheels]
    steer_idx = [position[name] for name in steer_cols]
    samples: list[tuple] = []
    kept_lines: list[int] = []
    duplicates: list[int] = []
    for line, row in rows[1:]:
        if len(row) != len(header):
            raise OdometryInputError(f"{source}: line {line}: {len(row)} fields, header has {len(header)}")
        sample = (
            number(row[t_col], source, line, "t", OdometryInputError),
            tuple(tick_reading(row[j], source, line, name) for j, name in zip(tick_cols, wheels, strict=True)),
            tuple(
                number(row[j], source, line, name, OdometryInputError)
                for j, name in zip(steer_idx, steer_cols, strict=True)
            ),
        )
        if samples and sample == samples[-1]:
            duplicates.append(line)
            continue
        samples.append(sample)
        kept_lines.append(line)
    if len(samples) < 2:
        raise OdometryInputError(f"{source}: needs at least two distinct samples, got {len(samples)}")
    ticks = counter_readings([s[1] for s in samples], wheels)
    steer = np.radians(np.array([s[2] for s in samples], dtype=float)) if steer_cols else None
    return TickLog(
        np.array([s[0] for s in samples], dtype=float), ticks, steer, wheels, tuple(duplicates), tuple(kept_lines)
    )


def tick_log_lines(t, ticks, wheel_names, steer=None, steer_names=(), comment: str | None = None) -> list[str]:
    """The lines of a tick log (without newlines): optional ``# comment`` lines, the header, the rows.

    ``t`` (N,) [s] (float, or int64 nanoseconds written exactly; increasing as written);
    ``ticks`` (N, n) whole numbers (written exactly; floats must be whole); ``steer``
    (N, n_steer) [rad], written in degrees, for the wheels ``steer_names``.
    """
    names = [str(n) for n in wheel_names]
    tk = np.asarray(ticks)
    if tk.ndim != 2 or tk.shape[1] != len(names):
        raise InputError(f"ticks: expected shape (N, {len(names)}) for wheels {names}, got {tk.shape}")
    if tk.dtype.kind == "f":
        if not np.all(np.isfinite(tk)) or np.any(tk != np.round(tk)) or np.any(np.abs(tk) > 2.0**53):
            raise InputError(
                "ticks: a tick log holds whole-number counter readings; got fractions or values "
                "beyond 2**53 (quantise the ticks first)"
            )
        tk = tk.astype(np.int64)
    elif tk.dtype.kind not in "iuO":
        raise InputError(f"ticks: expected integer readings, got dtype {tk.dtype}")
    times = format_times(t)
    if len(times) != len(tk):
        raise InputError(f"{len(times)} timestamps for {len(tk)} rows of ticks")
    _require_increasing(times)
    steer_names = [str(n) for n in steer_names]
    columns = ["t"] + names + [f"{n}_steer_deg" for n in steer_names]
    deg = None
    if steer is not None or steer_names:
        deg = np.degrees(np.asarray(steer, dtype=float))
        if deg.shape != (len(tk), len(steer_names)):
            raise InputError(
                f"steer: expected shape ({len(tk)}, {len(steer_names)}) for {steer_names}, got {deg.shape}"
            )
    out = [f"# {line}" for line in (comment.splitlines() if comment else [])]
    out.append(",".join(columns))
    rows = tk.tolist()
    for k, (tk_text, row) in enumerate(zip(times, rows, strict=True)):
        cells = [tk_text] + [str(int(v)) for v in row]
        if deg is not None:
            cells += [repr(float(v) + 0.0) for v in deg[k]]
        out.append(",".join(cells))
    return out


def _require_increasing(times: list[str]) -> None:
    """Refuse times that, as written and read back (floats, as :func:`read_tick_log` reads
    them), do not increase: the odometry would refuse the log (a time too large for its
    sample rate rounds several samples to one stamp)."""
    back = np.array(times, dtype=float)
    stuck = np.flatnonzero(~(np.diff(back) > 0))
    if stuck.size:
        k = int(stuck[0]) + 1
        raise InputError(
            f"t: sample {k} at {shorten(times[k])} s does not come after sample {k - 1} at "
            f"{shorten(times[k - 1])} s as written: a tick log's times must increase"
        )


def write_tick_log(path, t, ticks, wheel_names, steer=None, *, steer_names=(), comment: str | None = None) -> None:
    """Write a tick log (module docstring; see :func:`tick_log_lines`) atomically, or to
    standard output for ``-``. Check the path first with
    :func:`omnikin.io.output.check_output`."""
    text = "\n".join(tick_log_lines(t, ticks, wheel_names, steer, steer_names, comment)) + "\n"
    write_text(path, text)  # a write failure: OutputError naming the path
