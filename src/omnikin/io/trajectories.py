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
``seconds.nanoseconds``. Blank lines and lines starting with ``#`` are skipped when reading;
every problem names the file and the line.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import numpy as np

from ..geometry import wrap_angle
from ..errors import InputError
from .csvfile import number

FORMATS = ("tum", "kitti", "csv")


class TrajectoryFileError(InputError):
    """A trajectory file that cannot be read or written; the message names the file (and line)."""


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
    c, s = np.cos(p[:, 2]) + 0.0, np.sin(p[:, 2]) + 0.0     # + 0.0 turns -0.0 into 0.0: no "-0" in the files
    p = p + 0.0
    if fmt in ("csv", "tum"):                      # fixed decimals: what rounds to zero is written as 0
        p = np.column_stack([np.round(p[:, :2], 9), np.round(p[:, 2], 12)]) + 0.0
    if fmt == "csv":
        return ["t,x,y,theta"] + [f"{tk},{x:.9f},{y:.9f},{th:.12f}" for tk, (x, y, th) in zip(times, p.tolist())]
    if fmt == "tum":
        qz, qw = np.round(np.sin(0.5 * p[:, 2]), 12) + 0.0, np.round(np.cos(0.5 * p[:, 2]), 12) + 0.0
        return [f"{tk} {x:.9f} {y:.9f} 0 0 0 {z:.12f} {w:.12f}"
                for tk, (x, y, _), z, w in zip(times, p.tolist(), qz.tolist(), qw.tolist())]
    return [f"{ck:.12g} {-sk + 0.0:.12g} 0 {x:.12g} {sk:.12g} {ck:.12g} 0 {y:.12g} 0 0 1 0"
            for (x, y, _), ck, sk in zip(p.tolist(), c.tolist(), s.tolist())]


def write_trajectory(path, t, poses, fmt: str) -> None:
    """Write a trajectory file; ``path`` ``None`` or ``'-'`` writes to standard output."""
    text = "\n".join(trajectory_lines(t, poses, fmt)) + "\n"
    if path is None or str(path) == "-":
        sys.stdout.write(text)
        return
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise TrajectoryFileError(f"{path}: cannot write: {exc.strerror or exc}") from None


_SPLIT = re.compile(r"[\s,]+")


def _numbers(source, line_no, fields, count, fmt) -> list[float]:
    if len(fields) != count:
        raise TrajectoryFileError(f"{source}: line {line_no}: {len(fields)} fields, a {fmt} line has {count}")
    return [number(f, source, line_no, k + 1, TrajectoryFileError) for k, f in enumerate(fields)]


def detect_format(path) -> str:
    """``csv`` (header starting ``t,``), ``tum`` (8 fields) or ``kitti`` (12 fields) from the first data line."""
    lines = _lines(path)
    if not lines:
        raise TrajectoryFileError(f"{path}: empty trajectory file")
    line_no, text = lines[0]
    if text.replace(" ", "").lower().startswith("t,"):
        return "csv"
    n = len([f for f in _SPLIT.split(text.strip()) if f])
    if n == 8:
        return "tum"
    if n == 12:
        return "kitti"
    raise TrajectoryFileError(f"{path}: line {line_no}: {n} fields; expected a TUM line (t x y z qx qy qz qw, 8 "
                              f"fields), a KITTI line (12 fields) or a CSV header t,x,y,theta")


def _lines(path) -> list[tuple[int, str]]:
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise TrajectoryFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise TrajectoryFileError(f"{path}: is a directory, not a trajectory file") from None
    except UnicodeDecodeError as exc:
        raise TrajectoryFileError(f"{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason})") from None
    except OSError as exc:
        raise TrajectoryFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    return [(k + 1, line) for k, line in enumerate(text.splitlines())
            if line.strip() and not line.lstrip().startswith("#")]


def read_trajectory(path, fmt: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(t (N,), poses (N, 3))`` of a TUM, KITTI or CSV file (``fmt`` None: detected)."""
    source = str(path)
    fmt = fmt or detect_format(path)
    if fmt not in FORMATS:
        raise TrajectoryFileError(f"unknown trajectory format {fmt!r}; one of {list(FORMATS)}")
    lines = _lines(path)
    if fmt == "csv":
        if not lines:
            raise TrajectoryFileError(f"{source}: empty trajectory file")
        header = [h.strip() for h in lines[0][1].split(",")]
        if header != ["t", "x", "y", "theta"]:
            raise TrajectoryFileError(f"{source}: line {lines[0][0]}: expected the header t,x,y,theta, got "
                                      f"{lines[0][1].strip()!r}")
        lines = lines[1:]
    if not lines:
        raise TrajectoryFileError(f"{source}: no poses")
    t = np.empty(len(lines))
    poses = np.empty((len(lines), 3))
    for k, (line_no, text) in enumerate(lines):
        fields = [f for f in (text.split(",") if fmt == "csv" else _SPLIT.split(text.strip())) if f.strip()]
        if fmt == "csv":
            t[k], *poses[k] = _numbers(source, line_no, [f.strip() for f in fields], 4, "csv")
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
