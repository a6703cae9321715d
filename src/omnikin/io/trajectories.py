"""Trajectory files in and out: TUM, KITTI and CSV, for 2D poses ``(x, y, theta)``.

* ``tum`` (Sturm et al. 2012): one pose per line, ``t x y z qx qy qz qw`` separated by spaces;
  written with ``z = qx = qy = 0``, ``qz = sin(theta/2)``, ``qw = cos(theta/2)``. Read: the
  heading is the yaw of the quaternion, ``atan2(2 (qw qz + qx qy), qw^2 + qx^2 - qy^2 - qz^2)``
  (any scale), ``z`` is ignored.
* ``kitti`` (Geiger et al. 2012): one pose per line, the 3x4 matrix ``[R | t]`` row-major,
  12 numbers; the 2D pose is embedded as ``R = Rz(theta)``, ``t = (x, y, 0)``. KITTI files carry
  no timestamps: read, pose k gets ``t = k`` (so two KITTI files associate by index).
* ``csv``: header ``t,x,y,theta`` [s, m, m, rad], as ``omnikin odometry`` writes.

Integer timestamps (``int64`` nanoseconds, as in ROS bags) are written exactly as
``seconds.nanoseconds``. Reading follows :mod:`omnikin.io.csvfile`: blank lines and lines
starting with ``#`` are skipped, an empty field is an error (never dropped), every problem names
the file and the line; TUM and KITTI fields are separated by blanks (or single commas).
"""

from __future__ import annotations

import math

import numpy as np

from ..common.messages import shorten
from ..errors import TrajectoryFileError
from ..kinematics.se2 import wrap_angle
from .csvfile import iter_fields, number, read_rows
from .output import STDOUT, check_output, write_text

FORMATS = ("tum", "kitti", "csv")


def format_times(t) -> list[str]:
    """Timestamps as text: ``int`` nanoseconds exactly (``sec.nnnnnnnnn``), floats with 9 decimals."""
    arr = np.asarray(t)
    if np.issubdtype(arr.dtype, np.integer):
        out = []
        for ns in arr.tolist():
            sign = "-" if ns < 0 else ""
            sec, nsec = divmod(abs(int(ns)), 1_000_000_000)
            out.append(f"{sign}{sec}.{nsec:09d}")
        return out
    return [f"{v:.9f}" for v in arr.astype(float).tolist()]


def trajectory_lines(t, poses, fmt: str) -> list[str]:
    """The lines of a trajectory file (without newlines), header included for ``csv``."""
    if fmt not in FORMATS:
        raise TrajectoryFileError(f"unknown trajectory format {fmt!r}; one of {list(FORMATS)}")
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise TrajectoryFileError(f"poses must have shape (N, 3), got {p.shape}")
    times = format_times(t)
    if len(times) != len(p):
        raise TrajectoryFileError(f"{len(times)} timestamps for {len(p)} poses")
    c, s = np.cos(p[:, 2]) + 0.0, np.sin(p[:, 2]) + 0.0  # + 0.0 turns -0.0 into 0.0: no "-0" in the files
    p = p + 0.0
    if fmt in ("csv", "tum"):  # fixed decimals: what rounds to zero is written as 0
        p = np.column_stack([np.round(p[:, :2], 9), np.round(p[:, 2], 12)]) + 0.0
    if fmt == "csv":
        return ["t,x,y,theta"] + [
            f"{tk},{x:.9f},{y:.9f},{th:.12f}" for tk, (x, y, th) in zip(times, p.tolist(), strict=True)
        ]
    if fmt == "tum":
        qz, qw = np.round(np.sin(0.5 * p[:, 2]), 12) + 0.0, np.round(np.cos(0.5 * p[:, 2]), 12) + 0.0
        return [
            f"{tk} {x:.9f} {y:.9f} 0 0 0 {z:.12f} {w:.12f}"
            for tk, (x, y, _), z, w in zip(times, p.tolist(), qz.tolist(), qw.tolist(), strict=True)
        ]
    return [
        f"{ck:.12g} {-sk + 0.0:.12g} 0 {x:.12g} {sk:.12g} {ck:.12g} 0 {y:.12g} 0 0 1 0"
        for (x, y, _), ck, sk in zip(p.tolist(), c.tolist(), s.tolist(), strict=True)
    ]


def write_trajectory(path, t, poses, fmt: str, *, force: bool = False, inputs=()) -> None:
    """Write a trajectory file; ``path`` ``None`` or ``'-'`` writes to standard output.

    The output policy of :mod:`omnikin.io.output`: an existing file is replaced only with
    ``force``, never one of ``inputs`` (the files the caller read), and the file is written
    atomically (a failure leaves the previous file; an :class:`omnikin.errors.OutputError`
    names the path).
    """
    path = STDOUT if path is None else path
    check_output(path, inputs=inputs, force=force)
    write_text(path, "\n".join(trajectory_lines(t, poses, fmt)) + "\n")


def _numbers(source, line_no, fields, count, fmt, names=None) -> list[float]:
    """The numbers of one line; ``names``: the columns (CSV), else fields are named by number."""
    if len(fields) != count:
        raise TrajectoryFileError(f"{source}: line {line_no}: {len(fields)} fields, a {fmt} line has {count}")
    columns = names or range(1, count + 1)
    return [number(f, source, line_no, c, TrajectoryFileError) for c, f in zip(columns, fields, strict=True)]


CSV_HEADER = ["t", "x", "y", "theta"]


def _first_row(path) -> tuple[int, list[str]]:
    for row in iter_fields(path, TrajectoryFileError):
        return row
    raise TrajectoryFileError(f"{path}: empty trajectory file")


def detect_format(path) -> str:
    """``csv`` (header starting ``t,``), ``tum`` (8 fields) or ``kitti`` (12 fields) from the first data line."""
    line_no, fields = _first_row(path)
    if fields[0].lower() == "t":
        return "csv"
    if len(fields) == 8:
        return "tum"
    if len(fields) == 12:
        return "kitti"
    raise TrajectoryFileError(
        f"{path}: line {line_no}: {len(fields)} fields; expected a TUM line (t x y z qx qy qz "
        f"qw, 8 fields), a KITTI line (12 fields) or a CSV header t,x,y,theta"
    )


def _rows(path, fmt: str) -> list[tuple[int, list[str]]]:
    """The data rows of a trajectory file (the CSV header checked and dropped); no empty field."""
    source = str(path)
    if fmt != "csv":
        return list(iter_fields(path, TrajectoryFileError))
    rows = read_rows(path, TrajectoryFileError)
    if not rows:
        raise TrajectoryFileError(f"{source}: empty trajectory file")
    (line_no, header), *data = rows
    if header != CSV_HEADER:
        raise TrajectoryFileError(
            f"{source}: line {line_no}: expected the header t,x,y,theta, got {shorten(','.join(header))}"
        )
    return data


def read_trajectory(path, fmt: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(t (N,), poses (N, 3))`` of a TUM, KITTI or CSV file (``fmt`` None: detected).

    Every field must hold a number: an empty field (``1,,2``) is an error naming its line and
    column, never skipped (:mod:`omnikin.io.csvfile`).
    """
    source = str(path)
    fmt = fmt or detect_format(path)
    if fmt not in FORMATS:
        raise TrajectoryFileError(f"unknown trajectory format {fmt!r}; one of {list(FORMATS)}")
    rows = _rows(path, fmt)
    if not rows:
        raise TrajectoryFileError(f"{source}: no poses")
    t = np.empty(len(rows))
    poses = np.empty((len(rows), 3))
    for k, (line_no, fields) in enumerate(rows):
        if fmt == "csv":
            t[k], *poses[k] = _numbers(source, line_no, fields, 4, "csv", CSV_HEADER)
        elif fmt == "tum":
            tk, x, y, _z, qx, qy, qz, qw = _numbers(source, line_no, fields, 8, "TUM")
            if qx == qy == qz == qw == 0.0:
                raise TrajectoryFileError(f"{source}: line {line_no}: zero quaternion")
            t[k] = tk
            poses[k] = (x, y, math.atan2(2.0 * (qw * qz + qx * qy), qw * qw + qx * qx - qy * qy - qz * qz))
        else:
            m = _numbers(source, line_no, fields, 12, "KITTI")
            t[k] = float(k)
            poses[k] = (m[3], m[7], math.atan2(m[4], m[0]))
    poses[:, 2] = wrap_angle(poses[:, 2])
    return t, poses
