"""Measurement files of real runs: UMBmark measurements and calibration runs (CSV).

UMBmark measurements (``omnikin umbmark analyze``): one row per run with columns
``direction`` (``cw``/``ccw``), ``x_abs``, ``y_abs``, ``x_calc``, ``y_calc`` [m] and
optionally ``theta_abs``, ``theta_calc`` [rad] or ``theta_abs_deg``, ``theta_calc_deg``
[deg]: the measured end pose and the odometry's, in the start frame (first leg along +x).

Calibration runs (``omnikin calibrate``): one row per run with columns ``path``, ``x_abs``,
``y_abs`` [m] and optionally ``theta_abs`` [rad] or ``theta_abs_deg`` [deg]. ``path`` is
one of::

    square cw|ccw rotate|translate [SIDE]    (default side 4 m)
    line LENGTH [HEADING_DEG]                 straight, along body direction HEADING_DEG
    spin ANGLE_DEG                            turn in place (positive: counter-clockwise)
    arc RADIUS ANGLE_DEG                      forward on a circle

Blank lines and lines starting with ``#`` are skipped; every field needs a value (an
optional theta column, once present, must be filled on every row: an empty field is an
error, not "not measured"). Errors name the file, the line and the column.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from ..common.messages import shorten
from ..errors import InputError, OmnikinError, RunsFileError
from ..kinematics.se2 import wrap_angle
from ..motion.plans import CalibrationRun, Plan, parse_plan
from .csvfile import column_problems, number, read_rows


def _rows(path) -> tuple[list[str], list[tuple[int, dict]]]:
    source = str(path)
    raw = read_rows(path, RunsFileError)
    if not raw:
        raise RunsFileError(f"{source}: empty file")
    header = raw[0][1]
    rows = []
    for line_no, r in raw[1:]:
        if len(r) != len(header):
            raise RunsFileError(f"{source}: line {line_no}: {len(r)} fields, the header has {len(header)}")
        rows.append((line_no, dict(zip(header, r, strict=True))))
    if not rows:
        raise RunsFileError(f"{source}: no data rows after the header")
    return header, rows


def _check_columns(source, header, required, optional):
    problems = column_problems(header, required, optional)
    if problems:
        raise RunsFileError(
            f"{source}: " + "; ".join(problems) + f"; expected {list(required)} and optionally {list(optional)}"
        )


def _number(source, line_no, column, text) -> float:
    return number(text, source, line_no, column, RunsFileError)


def _theta(source, header, line_no, row, which) -> float:
    rad, deg = f"theta_{which}", f"theta_{which}_deg"
    if rad in header and deg in header:
        raise RunsFileError(f"{source}: give {rad} [rad] or {deg} [deg], not both")
    if rad in header:
        return _number(source, line_no, rad, row[rad])
    if deg in header:
        return math.radians(_number(source, line_no, deg, row[deg]))
    return math.nan


def path_plan(text: str) -> Plan:
    """The plan of one path of the grammar in the module docstring
    (:func:`omnikin.motion.plans.parse_plan`: plain numbers, as in every table). One run drives one
    path: ``;`` (which chains paths in ``omnikin simulate --path``) is refused here. Raises
    :class:`InputError`.
    """
    if ";" in text:
        raise InputError(
            f"path {shorten(text)}: one run is one path; ';' (chaining paths) is not allowed here, "
            "give each path its own run"
        )
    return parse_plan(text)


def read_umbmark_measurements(path):
    """Return errors per direction: ``{'cw': (n, 3), 'ccw': (n, 3)}`` (theta NaN if not measured)."""
    source = str(path)
    header, rows = _rows(path)
    _check_columns(
        source,
        header,
        ("direction", "x_abs", "y_abs", "x_calc", "y_calc"),
        ("theta_abs", "theta_calc", "theta_abs_deg", "theta_calc_deg"),
    )
    eps: dict[str, list[tuple[float, float, float]]] = {"cw": [], "ccw": []}
    for line_no, row in rows:
        d = row["direction"].lower()
        if d not in eps:
            raise RunsFileError(
                f"{source}: line {line_no}, column 'direction': expected cw or ccw, got {shorten(row['direction'])}"
            )
        x = _number(source, line_no, "x_abs", row["x_abs"]) - _number(source, line_no, "x_calc", row["x_calc"])
        y = _number(source, line_no, "y_abs", row["y_abs"]) - _number(source, line_no, "y_calc", row["y_calc"])
        th = _theta(source, header, line_no, row, "abs") - _theta(source, header, line_no, row, "calc")
        eps[d].append((x, y, wrap_angle(th) if math.isfinite(th) else math.nan))
    for d, runs in eps.items():
        if not runs:
            raise RunsFileError(f"{source}: no {d} runs; UMBmark needs runs in both directions (cw and ccw)")
    return {d: np.array(v) for d, v in eps.items()}


DEFAULT_SIGMA = CalibrationRun.sigma
"""Default measurement standard deviations of a calibration run: position [m], heading [rad]
(:class:`omnikin.motion.plans.CalibrationRun`'s)."""


def read_calibration_runs(path, sigma=DEFAULT_SIGMA) -> list[CalibrationRun]:
    """Calibration runs of a runs file (module docstring)."""
    source = str(path)
    header, rows = _rows(path)
    _check_columns(source, header, ("path", "x_abs", "y_abs"), ("theta_abs", "theta_abs_deg"))
    plans: dict[str, Plan] = {}
    out = []
    for line_no, row in rows:
        key = row["path"]  # parsed once per spelling (parse_plan splits at ASCII blanks only)
        if key not in plans:
            try:
                plans[key] = path_plan(key)
            except OmnikinError as exc:
                raise RunsFileError(f"{source}: line {line_no}, column 'path': {exc}") from None
        m = (
            _number(source, line_no, "x_abs", row["x_abs"]),
            _number(source, line_no, "y_abs", row["y_abs"]),
            _theta(source, header, line_no, row, "abs"),
        )
        out.append(CalibrationRun(plans[key], m, row["path"], sigma, source=f"{source}: line {line_no}"))
    return out


def _comment(text: str | None) -> str:
    """``text`` as ``#`` comment lines (read back as nothing)."""
    if not text:
        return ""
    return "".join(f"# {line}".rstrip() + "\n" for line in text.splitlines())


def _csv(rows) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def _with_heading(headings, what: str) -> bool:
    """Whether a file gets a heading column: every heading measured (yes) or none (no); a file
    holds no empty field, so a mix cannot be written."""
    measured = [math.isfinite(h) for h in headings]
    if any(measured) and not all(measured):
        raise InputError(
            f"{what}: the heading is measured in some runs and not in others; a runs file has a "
            "heading column for every run or none"
        )
    return all(measured) and bool(measured)


def calibration_runs_text(runs, comment: str | None = None) -> str:
    """A runs file (``omnikin calibrate``): one row per :class:`~omnikin.motion.plans.CalibrationRun`
    (its ``label`` is the path in the runs-file grammar), x and y in metres to 1 um, the
    heading in degrees to 1e-5 deg (no heading column when no heading was measured);
    ``comment`` becomes ``#`` lines at the top."""
    runs = list(runs)
    heading = _with_heading([r.measured[2] for r in runs], "calibration runs")
    rows = [["path", "x_abs", "y_abs"] + (["theta_abs_deg"] if heading else [])]
    for run in runs:
        x, y, th = run.measured
        rows.append([run.label, f"{x:.6f}", f"{y:.6f}"] + ([f"{math.degrees(th):.5f}"] if heading else []))
    return _comment(comment) + _csv(rows)


def calibration_template(paths, repeats: int, comment: str | None = None) -> str:
    """A runs file to fill in on a real robot: every path ``repeats`` times, measurements empty
    (every field must be filled before it is read; without heading measurements delete the
    ``theta_abs_deg`` column)."""
    rows = [["path", "x_abs", "y_abs", "theta_abs_deg"]]
    rows += [[path, "", "", ""] for path in paths for _ in range(repeats)]
    return _comment(comment) + _csv(rows)


def umbmark_measurements_text(result, comment: str | None = None) -> str:
    """A measurements file (``omnikin umbmark analyze``) of a
    :class:`~omnikin.evaluation.umbmark.UMBmarkResult`: odometry at the origin, so ``abs`` =
    ``epsilon`` [m, deg]; no heading columns when no heading was measured."""
    eps = [e for d in (result.cw, result.ccw) for e in d.epsilon]
    heading = _with_heading([e[2] for e in eps], "UMBmark measurements")
    rows = [
        ["direction", "x_abs", "y_abs", "x_calc", "y_calc"] + (["theta_abs_deg", "theta_calc_deg"] if heading else [])
    ]
    for d in (result.cw, result.ccw):
        for e in d.epsilon:
            rows.append(
                [d.direction, f"{e[0]:.6f}", f"{e[1]:.6f}", "0", "0"]
                + ([f"{math.degrees(e[2]):.5f}", "0"] if heading else [])
            )
    return _comment(comment) + _csv(rows)
