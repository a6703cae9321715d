"""The UMBmark report's ``run_poses.csv``: the poses of every run over time.

Written by ``omnikin umbmark`` (:func:`run_poses_text`) and read by ``omnikin view --replay``
(:func:`read_run_poses`). A CSV file (the rules of :mod:`omnikin.io.csvfile`: ``#`` lines are
comments, no empty field) with the header::

    phase,direction,run,t,x,y,theta,odom_x,odom_y,odom_theta

one row per kept sample (:mod:`omnikin.evaluation.run_poses`): ``phase`` ``before`` or
``after`` (calibration), ``direction`` ``cw`` or ``ccw``, ``run`` 1, 2, ... (the rows of the
measurement file of that phase, in order), ``t`` [s] since the run's start, the true pose
``x``, ``y`` [m], ``theta`` [rad] and the odometry pose ``odom_x``, ``odom_y`` [m],
``odom_theta`` [rad], in the start frame (first leg along +x). The rows of one run are
together, their times strictly increasing; the last row of a run is its end pose. The first
line, ``# omnikin-run-poses/1: N rows, ...``, counts the data rows: a file cut short is refused.

Reading refuses, in one line naming the file and the line: a missing, unknown or duplicate
column, an unknown phase or direction, a run number that is not a whole number >= 1, a
number that is not finite, a time that does not increase, a run whose rows are split by
another run's, a run of one sample, fewer or more rows than the first line announces; and a
file of more than :data:`MAX_READ_ROWS` rows or :data:`MAX_READ_BYTES` bytes
(:class:`~omnikin.errors.ResourceLimitError`, before it is read when its size is known).
"""

from __future__ import annotations

import csv
import io
import os
import re
from array import array

import numpy as np

from ..common.messages import shorten
from ..errors import ResourceLimitError, RunPosesFileError
from ..evaluation.run_poses import DIRECTIONS, MAX_RATE, MAX_ROWS, PHASES, RunPoses
from .csvfile import column_problems, iter_rows, number
from .textfile import read_lines

COLUMNS = ("phase", "direction", "run", "t", "x", "y", "theta", "odom_x", "odom_y", "odom_theta")
FORMAT = "omnikin-run-poses/1"
"""Name and version of the file's format (its first comment line)."""
MAX_READ_ROWS = 8 * 2 * 2 * MAX_ROWS
"""Most data rows read: eight times what ``omnikin umbmark`` writes at most."""
MAX_READ_BYTES = 128 * 1024**2
"""Largest file read [bytes]: 128 MiB, rows of about 160 bytes."""


ANNOUNCED = re.compile(rf"# {re.escape(FORMAT)}: (\d{{1,12}}) rows\b")
"""The format line: the first line of a file omnikin wrote, with its count of data rows."""


def run_poses_text(runs, comment: str | None = None) -> str:
    """The file of the module docstring for :class:`~omnikin.evaluation.run_poses.RunPoses`
    ``runs``: times to 1 us, lengths to 1 um, angles to 1e-7 rad; ``comment`` (how the runs
    were made) becomes ``#`` lines after the format's own."""
    runs = list(runs)
    rows = sum(len(r.t) for r in runs)
    head = [
        f"{FORMAT}: {rows} rows, the poses of the runs of the first UMBmark procedure over time",
        "columns: phase (before/after calibration), direction (cw/ccw), run (1, 2, ...: the rows of "
        "measurements_PHASE.csv in order),",
        "t [s] since the run's start, true pose x, y [m], theta [rad], odometry pose odom_x, odom_y [m], "
        "odom_theta [rad], start frame (first leg along +x)",
        f"kept at most {MAX_RATE:g} Hz (every k-th sample of the simulation) and at most {MAX_ROWS} rows per "
        "phase and direction; the last row of a run is its end pose",
    ]
    if comment:
        head += comment.splitlines()
    buffer = io.StringIO()
    buffer.write("".join(f"# {line}".rstrip() + "\n" for line in head))
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    for r in runs:
        for k in range(len(r.t)):
            x, y, th = r.truth[k]
            ox, oy, oth = r.odometry[k]
            writer.writerow(
                (
                    r.phase,
                    r.direction,
                    r.run,
                    f"{r.t[k]:.6f}",
                    f"{x:.6f}",
                    f"{y:.6f}",
                    f"{th:.7f}",
                    f"{ox:.6f}",
                    f"{oy:.6f}",
                    f"{oth:.7f}",
                )
            )
    return buffer.getvalue()


def _check_size(path) -> None:
    try:
        size = os.stat(path).st_size if os.path.isfile(path) else 0
    except (OSError, ValueError):
        return  # the reader names what is wrong with the path
    if size > MAX_READ_BYTES:
        raise ResourceLimitError(
            f"{path}: {size} bytes, more than the {MAX_READ_BYTES} bytes of run poses read "
            f"(omnikin umbmark writes at most {2 * 2 * MAX_ROWS} rows)",
            needed=size,
            limit=MAX_READ_BYTES,
            unit="bytes",
        )


class _Run:
    def __init__(self, key: tuple[str, str, int], line: int):
        self.key = key
        self.line = line
        self.columns = [array("d") for _ in range(7)]


def _announced_rows(path) -> int | None:
    """The row count of the format line (the file's first line), None without one."""
    for _, text in read_lines(path, RunPosesFileError, what="a CSV file"):
        found = ANNOUNCED.match(text)
        return int(found.group(1)) if found else None
    return None


def _ends_with_newline(path) -> bool:
    with open(path, "rb") as f:
        f.seek(0, os.SEEK_END)
        if f.tell() == 0:
            return False
        f.seek(-1, os.SEEK_END)
        return f.read(1) == b"\n"


def read_run_poses(path, *, max_rows: int = MAX_READ_ROWS) -> list[RunPoses]:
    """The runs of a run-poses file (module docstring), in file order; theta and odom_theta
    as written (not wrapped).

    Parameters
    ----------
    path : str or os.PathLike
        The run-poses file (``run_poses.csv`` of an UMBmark report).
    max_rows : int
        Most data rows read (default :data:`MAX_READ_ROWS`).

    Returns
    -------
    list of RunPoses
        One :class:`~omnikin.evaluation.run_poses.RunPoses` per run: its phase, direction and
        number, times ``(n,)`` [s] from its start, the true and the odometry poses ``(n, 3)``
        ``(x [m], y [m], theta [rad])`` in the start frame (first leg along +x).

    Raises
    ------
    RunPosesFileError
        In one line naming the file and the line: a bad column, phase, direction, run number,
        number or time order, a run split or of one sample, a file cut short.
    ResourceLimitError
        More than ``max_rows`` rows or :data:`MAX_READ_BYTES` bytes.
    """
    source = str(path)
    _check_size(path)
    announced = _announced_rows(path) if os.path.isfile(path) else None
    rows = iter_rows(path, RunPosesFileError)
    first = next(rows, None)
    if first is None:
        raise RunPosesFileError(f"{source}: empty file (expected the header {','.join(COLUMNS)})")
    header_line, header = first
    problems = column_problems(header, COLUMNS)
    if problems:
        raise RunPosesFileError(f"{source}: line {header_line}: " + "; ".join(problems) + f"; expected {list(COLUMNS)}")
    where = [header.index(c) for c in COLUMNS]
    runs: list[_Run] = []
    seen: dict[tuple[str, str, int], int] = {}
    count = 0
    for line, fields in rows:
        count += 1
        if count > max_rows:
            raise ResourceLimitError(
                f"{source}: more than {max_rows} rows of run poses (omnikin umbmark writes at most {2 * 2 * MAX_ROWS})",
                needed=count,
                limit=max_rows,
                unit="rows",
            )
        if len(fields) != len(header):
            raise RunPosesFileError(f"{source}: line {line}: {len(fields)} fields, the header has {len(header)}")
        phase, direction, run_text = (fields[k] for k in where[:3])
        if phase not in PHASES:
            raise RunPosesFileError(
                f"{source}: line {line}, column 'phase': expected {' or '.join(PHASES)}, got {shorten(phase)}"
            )
        if direction not in DIRECTIONS:
            raise RunPosesFileError(
                f"{source}: line {line}, column 'direction': expected cw or ccw, got {shorten(direction)}"
            )
        if not run_text.isdigit() or not run_text.isascii() or len(run_text) > 9 or int(run_text) < 1:
            raise RunPosesFileError(
                f"{source}: line {line}, column 'run': expected a whole number >= 1, got {shorten(run_text)}"
            )
        key = (phase, direction, int(run_text))
        values = [
            number(fields[k], source, line, c, RunPosesFileError) for k, c in zip(where[3:], COLUMNS[3:], strict=True)
        ]
        if not runs or runs[-1].key != key:
            if key in seen:
                raise RunPosesFileError(
                    f"{source}: line {line}: {phase} {direction} run {key[2]} again after other runs "
                    f"(its rows began on line {seen[key]}); the rows of a run must be together"
                )
            seen[key] = line
            runs.append(_Run(key, line))
        current = runs[-1]
        times = current.columns[0]
        if times and not values[0] > times[-1]:
            raise RunPosesFileError(
                f"{source}: line {line}, column 't': {values[0]:g} s does not follow {times[-1]:g} s; the times "
                "of a run must increase"
            )
        for column, value in zip(current.columns, values, strict=True):
            column.append(value)
    if not runs:
        raise RunPosesFileError(f"{source}: no data rows after the header")
    if announced is not None and not _ends_with_newline(path):
        raise RunPosesFileError(f"{source}: the last line has no line end: the file is cut short (truncated)")
    if announced is not None and announced != count:
        raise RunPosesFileError(
            f"{source}: {count} data rows, line 1 announces {announced}: the file is truncated or was edited"
        )
    out = []
    for r in runs:
        data = [np.frombuffer(c, dtype=float) for c in r.columns]
        if len(data[0]) < 2:
            raise RunPosesFileError(
                f"{source}: line {r.line}: {r.key[0]} {r.key[1]} run {r.key[2]} has one sample; a run needs two"
            )
        truth = np.column_stack(data[1:4])
        odometry = np.column_stack(data[4:7])
        out.append(RunPoses(r.key[0], r.key[1], r.key[2], data[0].copy(), truth, odometry))
    return out
