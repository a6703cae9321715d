"""Path files: waypoints ``x, y[, theta]`` [m, m, rad] in the world frame, as CSV or YAML, read
into a :class:`omnikin.control.path.Path`; and :func:`load_path`, which takes either a file or
the text form of a built-in path (:func:`omnikin.control.path.parse_path`).

* **CSV** (``.csv``): a header ``x,y`` or ``x,y,theta`` (any order), then one waypoint per
  line; the table rules of :mod:`omnikin.io.csvfile` (``#`` comments, no empty field, every
  problem named by line and column).
* **YAML** (``.yaml``, ``.yml``)::

      closed: false          # optional
      waypoints:
        - [0.0, 0.0]         # x, y
        - [1.0, 0.0, 1.57]   # x, y, theta
        - {x: 1.0, y: 1.0, theta: 3.14}

  every waypoint with a heading or none of them; read with the strict loader of
  :mod:`omnikin.io.robot_file` (no aliases, no duplicate keys, 256 KiB at most).

A CSV path whose last waypoint repeats the first (``x, y``, and ``theta`` up to whole turns) is
closed: the robot ends where it started. Two consecutive waypoints at the same place are
refused, naming both. With ``theta`` the heading is given per point; without it the ``heading``
mode applies (:data:`omnikin.control.path.HEADINGS`, default ``tangent``). The corners are
stopped at (``blend`` 0), cut by arcs of radius ``blend`` [m], or the whole path is a smooth
curve through the waypoints (``smooth``: :func:`omnikin.control.path.spline`).

At most :data:`MAX_WAYPOINTS` waypoints are read: a file with more is refused when the reader
gets there, so a huge file costs bounded time and memory.
"""

from __future__ import annotations

import math
import os
from pathlib import Path as FilePath

import numpy as np

from ..common.messages import shorten
from ..control.path import Path, parse_path, polyline, spline
from ..errors import InputError, PathFileError
from .csvfile import column_problems, iter_rows, number
from .robot_file import parse_yaml
from .textfile import read_text

MAX_WAYPOINTS = 100_000
"""Most waypoints a path file may hold."""

PATH_FILE_SUFFIXES = (".csv", ".yaml", ".yml")
"""Endings that make a path argument a file (any existing file is read too)."""


def is_path_file(spec) -> bool:
    """Whether the path argument ``spec`` names a file: a :class:`os.PathLike`, a name with a
    path file's ending (:data:`PATH_FILE_SUFFIXES`) or one that exists and does not begin with a
    built-in path's name (``circle 1`` is the built-in circle even beside a file of that name, as
    a preset name always means the preset); anything else is the text form of a built-in path."""
    from ..control.path import PATH_SPECS

    if isinstance(spec, os.PathLike):
        return True
    if not isinstance(spec, str):
        return False
    if spec.lower().endswith(PATH_FILE_SUFFIXES):
        return True
    words = spec.split()
    return not (words and words[0] in PATH_SPECS) and os.path.isfile(spec)


def load_path(spec, *, heading=None, blend: float | None = None, smooth: bool = False) -> Path:
    """The path ``spec`` names: a path file (:func:`read_path_file`) or a built-in path's text
    form (``"figure8 1"``, :func:`omnikin.control.path.parse_path`; ``blend`` and ``smooth``
    are for files: a built-in square takes its blend as its second number)."""
    if is_path_file(spec):
        return read_path_file(spec, heading=heading, blend=0.0 if blend is None else blend, smooth=smooth)
    if blend is not None or smooth:
        option = "smooth" if smooth else "blend"
        raise InputError(f"{option} is for path files; a built-in path takes its shape from its numbers ({spec!r})")
    return parse_path(spec, heading=heading)


def read_waypoints(path) -> tuple[np.ndarray, np.ndarray | None, bool]:
    """The waypoints of the path file ``path`` as they are written: positions ``(n, 2)`` [m],
    headings ``(n,)`` [rad] or None, and whether the path is closed (module docstring; the
    same checks as :func:`read_path_file`)."""
    source = str(path)
    suffix = FilePath(source).suffix.lower()
    if suffix == ".csv":
        return _read_csv(source)
    if suffix in (".yaml", ".yml"):
        return _read_yaml(source)
    raise PathFileError(f"{source}: not a path file (a .csv or .yaml of waypoints x, y[, theta])")


def read_path_file(path, *, heading=None, blend: float = 0.0, smooth: bool = False) -> Path:
    """The path through the waypoints of the file ``path`` (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.csv``, ``.yaml`` or ``.yml`` file.
    heading : str or float, optional
        For waypoints without ``theta``: :data:`omnikin.control.path.HEADINGS` or a fixed angle
        [rad]; default ``tangent``. Refused with waypoints that give ``theta``.
    blend : float, default 0
        Radius [m] of the arcs that cut the corners (0: stop at each corner).
    smooth : bool, default False
        A smooth curve through the waypoints instead of straight segments.

    Returns
    -------
    Path
        Named after the file.

    Raises
    ------
    PathFileError
        The file cannot be read, breaks the format, or its waypoints make no path (one line that
        names the file and where).
    """
    source = str(path)
    where = source
    xy, theta, closed = read_waypoints(source)
    if smooth and blend:
        raise PathFileError(f"{source}: a smooth path has no corners to blend; give smooth or blend")
    name = FilePath(source).name
    if theta is not None and heading is not None:
        raise PathFileError(f"{where}: the waypoints give theta; a heading mode ({heading!r}) cannot be too")
    mode = "tangent" if heading is None else heading
    try:
        if smooth:
            return spline(xy, heading=mode, closed=closed, name=name, theta=theta)
        return polyline(xy, blend=blend, heading=mode, closed=closed, name=name, theta=theta)
    except PathFileError:
        raise
    except InputError as exc:
        raise PathFileError(f"{source}: {exc}") from None


def _repeats(xy: np.ndarray, where, source: str) -> None:
    """Refuse two consecutive waypoints at the same place, naming them by ``where(k)``."""
    same = np.flatnonzero(np.all(np.abs(np.diff(xy, axis=0)) <= 1e-9, axis=1))
    if same.size:
        k = int(same[0])
        raise PathFileError(
            f"{source}: {where(k)} and {where(k + 1)} are at the same place (a path goes somewhere between waypoints)"
        )


def _closing(xy: np.ndarray, theta: np.ndarray | None) -> bool:
    """Whether the last waypoint repeats the first (position; heading up to whole turns)."""
    if len(xy) < 3 or not np.all(np.abs(xy[-1] - xy[0]) <= 1e-9):
        return False
    if theta is None:
        return True
    turns = (theta[-1] - theta[0]) / (2 * math.pi)
    return abs(turns - round(turns)) <= 1e-9


def _read_csv(source: str) -> tuple[np.ndarray, np.ndarray | None, bool]:
    where = source
    rows = iter_rows(source, PathFileError)
    try:
        _, header = next(rows)
    except StopIteration:
        raise PathFileError(f"{source}: empty (expected a header x,y or x,y,theta)") from None
    problems = column_problems(header, ("x", "y"), ("theta",))
    if problems:
        raise PathFileError(f"{source}: {'; '.join(problems)} (expected a header x,y or x,y,theta)")
    columns = [header.index(c) for c in ("x", "y", "theta") if c in header]
    values: list[list[float]] = []
    lines: list[int] = []
    for line, fields in rows:
        if len(fields) != len(header):
            raise PathFileError(f"{where}: line {line}: {len(fields)} fields, the header has {len(header)}")
        if len(values) == MAX_WAYPOINTS:
            raise PathFileError(f"{source}: line {line}: more than {MAX_WAYPOINTS} waypoints")
        values.append([number(fields[c], source, line, header[c], PathFileError) for c in columns])
        lines.append(line)
    if len(values) < 2:
        raise PathFileError(f"{source}: {len(values)} waypoint(s); a path needs two or more")
    table = np.array(values)
    xy, theta = table[:, :2], (table[:, 2] if table.shape[1] == 3 else None)
    _repeats(xy, lambda k: f"line {lines[k]}", source)
    closed = _closing(xy, theta)
    if closed:
        xy, theta = xy[:-1], (None if theta is None else theta[:-1])
    return xy, theta, closed


def _read_yaml(source: str) -> tuple[np.ndarray, np.ndarray | None, bool]:
    data = parse_yaml(read_text(source, PathFileError, what="a path file"), source, PathFileError)
    where = source
    if not isinstance(data, dict):
        raise PathFileError(f"{where}: expected a mapping with 'waypoints' (and optionally 'closed')")
    unknown = sorted(str(k) for k in data if k not in ("waypoints", "closed"))
    if unknown:
        raise PathFileError(f"{where}: unknown key(s) {', '.join(shorten(k, 40) for k in unknown[:8])}")
    closed = data.get("closed", False)
    if not isinstance(closed, bool):
        raise PathFileError(f"{where}: closed must be true or false, got {shorten(closed)}")
    points = data.get("waypoints")
    if not isinstance(points, list):
        raise PathFileError(f"{where}: 'waypoints' must be a list of [x, y] or [x, y, theta]")
    if len(points) > MAX_WAYPOINTS:
        raise PathFileError(f"{where}: {len(points)} waypoints is too many (at most {MAX_WAYPOINTS})")
    rows = [_waypoint(p, k, where) for k, p in enumerate(points)]
    widths = {len(r) for r in rows}
    if len(widths) > 1:
        k = next(k for k, r in enumerate(rows) if len(r) != len(rows[0]))
        has = "has" if len(rows[k]) == 3 else "lacks"
        raise PathFileError(f"{where}: waypoint {k} {has} a theta; all waypoints or none must have one")
    if len(rows) < 2:
        raise PathFileError(f"{where}: {len(rows)} waypoint(s); a path needs two or more")
    table = np.array(rows)
    xy, theta = table[:, :2], (table[:, 2] if table.shape[1] == 3 else None)
    _repeats(xy, lambda k: f"waypoint {k}", source)
    return xy, theta, closed


def _waypoint(point, k: int, where: str) -> list[float]:
    if isinstance(point, dict):
        unknown = sorted(str(key) for key in point if key not in ("x", "y", "theta"))
        if unknown or "x" not in point or "y" not in point:
            raise PathFileError(f"{where}: waypoint {k}: expected keys x, y and optionally theta, got {shorten(point)}")
        fields = [point["x"], point["y"]] + ([point["theta"]] if "theta" in point else [])
        names = ["x", "y", "theta"]
    elif isinstance(point, list) and len(point) in (2, 3):
        fields, names = point, ["x", "y", "theta"]
    else:
        raise PathFileError(f"{where}: waypoint {k}: expected [x, y], [x, y, theta] or a mapping, got {shorten(point)}")
    out = []
    for value, name in zip(fields, names, strict=False):
        number = None
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            try:
                number = float(value)
            except OverflowError:  # an integer beyond any float
                number = None
        if number is None or not math.isfinite(number):
            raise PathFileError(f"{where}: waypoint {k}: {name} must be a finite number, got {shorten(value)}")
        out.append(number)
    return out
