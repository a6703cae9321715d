"""``omnikin``: command-line entry point.

Every sub-command takes ROBOT = a preset name (``omnikin presets``) or a robot file.
Errors end with one line ``omnikin: error: ...`` on stderr, never a traceback: exit status 2
for bad input or usage, 1 when something fails while running (an output cannot be written, a
hardware link fails, an unexpected error), 141 when a reader closes the pipe. Stopping is not
an error: a command that serves until the user stops it (:data:`SERVERS`: view, sim, ros) ends
on Ctrl-C, SIGTERM or SIGHUP with ``omnikin view: stopped (SIGTERM)`` and status 0; any other
command stopped before it finished says ``omnikin: interrupted`` (130, Ctrl-C) or ``omnikin:
terminated (SIGTERM)`` (143; 129 on SIGHUP), so that a script knows the work is not done.
Ctrl-C and a termination signal end a command the same way: every temporary file and staging
folder is removed, a previous output stays as it was.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import io
import math
import os
import signal
import sys
import threading
import warnings
from collections.abc import Iterator

import numpy as np

from .._version import __version__
from ..common.messages import one_line, shorten
from ..errors import CliError, InfeasibleTwistError, InputError, OmnikinError, OutputError, Terminated, UsageError
from ..presets import PRESET_NAMES
from .common import (
    STOPPED,
    add_method_option,
    add_output,
    add_output_options,
    add_wheel_bound_options,
    command_inputs,
    console,
    declare_inputs,
    forget_handled_interrupt,
    load_robot,
    number,
    print_json,
    running,
    stop_name,
    whole,
)
from .parser import CommandParser

EPILOG = """examples:
  omnikin presets                          list the robots shipped with omnikin
  omnikin show tomasi-omni3                geometry, IK/FK matrices, mobility analysis
  omnikin show my_robot.yaml --plot layout.png
  omnikin ik tomasi-omni3 0.2 0 0.5        wheel speeds [rad/s] for vx vy omega
  omnikin ik ackermann 1 0 0.3 --json      steering angles too
  omnikin fk tomasi-omni3 10 -5 -5         body twist from wheel speeds
  omnikin odometry tomasi-omni3 log.csv -o traj.tum --format tum
  omnikin umbmark                          the main job: UMBmark, calibration, report
  omnikin umbmark analyze measured.csv --robot diff-drive
  omnikin calibrate tomasi-omni3 runs.csv -o calibrated.yaml
  omnikin simulate tomasi-omni3 --bag sim.bag      simulated run recorded to a ROS 2 bag
  omnikin bag odometry tomasi-omni3 run.bag -o odom.bag
  omnikin bag export sim.bag --topic /ground_truth --format tum -o truth.tum
  omnikin metrics truth.tum odom.tum --align       ATE and RPE (evo's definitions)
  omnikin ros tomasi-omni3                         the ROS 2 base driver (extra ros)
  omnikin sweep examples/tolerance.yaml -o study/  tolerance study on Dask (extra sweep)

units: SI and radians; degrees only where an option or column ends in -deg/_deg.
frames: body x forward, y left, angles counter-clockwise (REP-103).
negative numbers are values: omnikin ik tomasi-omni3 -2.5e-3 0 -1e-1 (-1E3, -.5 too).
options may come before, between or after the positional arguments.

output files: no command writes over one of its inputs, --force or not. An existing file is
  replaced only with --force; an existing folder only if omnikin wrote it (a report folder is
  replaced by the next run, a bag only with --force); omnikin never deletes anything else.
  Files are written whole or not at all (a temporary file beside them, renamed when complete).
  '-' is standard output, which then carries the data only: messages and tables go to stderr.
  The outputs of a command are checked together before it starts: no two on one path, none
  inside another, none the current folder, at most one on standard output (--json counts).
limits: commands whose size you choose (umbmark --trials/--runs, simulate --rate/--path, bags,
  trajectory files) are sized first and refused beyond --max-memory (default 2G) or --max-time
  (default 1h).
errors: one line 'omnikin: error: ...' on stderr; exit status 2 for bad input or usage, 1 when
  something fails while running (writing an output, a hardware link).
stopping: view, sim and ros serve until stopped: Ctrl-C or SIGTERM ends them normally (status 0,
  'omnikin view: stopped (Ctrl-C)'). Any other command stopped before it finished says
  'omnikin: interrupted' (status 130, Ctrl-C) or 'omnikin: terminated (SIGTERM)' (143: timeout,
  kill) and leaves no partial output (omnikin sweep keeps the tasks it finished, to resume from)."""

MESSAGE_LIMIT = 800
"""Longest error or warning line printed [characters]."""

WRITE_ERRORS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EFBIG,
    errno.EIO,
    errno.EROFS,
    errno.EACCES,
    errno.EPERM,
    errno.EBADF,
    errno.EPIPE,
}
"""Operating-system errors that mean an output could not be written."""


def _fmt(x: float) -> str:
    return f"{x:.6g}" if np.isfinite(x) else str(x)


def _clean(matrix, scale: float | None = None) -> np.ndarray:
    """A matrix or vector for display (text output only; ``--json`` keeps the numbers): entries
    below 1e-12 of ``scale`` (default: its largest entry) set to 0 (rounding noise such as
    cos(pi/2) = 6e-17)."""
    m = np.array(matrix, dtype=float)
    largest = np.max(np.abs(m), initial=0.0) if scale is None else abs(scale)
    m[np.abs(m) < 1e-12 * max(largest, 1e-300)] = 0.0
    return m


def _matrix_table(matrix, row_names, col_names):
    from rich.table import Table

    table = Table()
    table.add_column("")
    for c in col_names:
        table.add_column(c, justify="right")
    for name, row in zip(row_names, np.atleast_2d(_clean(matrix)), strict=True):
        table.add_row(name, *[_fmt(v) for v in row])
    return table


# --- presets ----------------------------------------------------------------------------
def cmd_presets(args) -> int:
    from rich.table import Table

    table = Table(title="omnikin presets (omnikin show NAME)", title_justify="left")
    for col in ("name", "wheels", "Campion type", "holonomic", "reference"):
        table.add_column(col)
    out = []
    from ..io.robot_file import load_preset

    for name in PRESET_NAMES:
        r = load_preset(name)  # the shipped files, whatever the current folder holds
        m = r.mobility
        ref = r.references[0] if r.references else ""
        out.append(
            {
                "name": name,
                "wheels": len(r.wheels),
                "campion_type": list(m.campion_type),
                "holonomic": m.holonomic,
                "reference": ref,
            }
        )
        table.add_row(
            name,
            str(len(r.wheels)),
            str(m.campion_type),
            "yes" if m.holonomic else "no",
            ref[:70] + ("..." if len(ref) > 70 else ""),
        )
    if args.json:
        print_json(out)
    else:
        console().print(table)
    return 0


# --- show --------------------------------------------------------------------------------
def show_data(robot) -> dict:
    """The ``show --json`` document: the robot's fields as its robot file holds them, written by
    the one serialiser (:func:`~omnikin.io.robot_file.robot_to_dict`, without the schema
    version; physical fields only those given), each wheel's polar placement (``distance`` [m],
    ``angle_deg``) and roller angle (``roller_deg``, 0 for wheels without rollers at an angle),
    then the kinematic matrices and the mobility analysis."""
    from ..io.robot_file import robot_to_dict

    m = robot.mobility
    data = robot_to_dict(robot)
    del data["omnikin"]
    for d, w in zip(data["wheels"], robot.wheels, strict=True):
        d["distance"] = math.hypot(w.x, w.y)
        d["angle_deg"] = math.degrees(math.atan2(w.y, w.x))
        d.setdefault("roller_deg", math.degrees(w.roller))
    fk = robot.fk_matrix()
    return {
        **data,
        "wheel_names": robot.rolling_names,
        "steer_names": robot.steer_names,
        "ik_matrix": robot.ik_matrix.tolist(),
        "fk_matrix": fk[:, : len(robot.rolling_names)].tolist(),
        "fk_rank": robot.fk_rank(),
        "rank": m.rank,
        "mobility": m.degree_of_mobility,
        "steerability": m.degree_of_steerability,
        "campion_type": list(m.campion_type),
        "campion_name": m.campion_name,
        "holonomic": m.holonomic,
        "condition_number": m.condition_number,
        "characteristic_length": m.characteristic_length,
        "isotropic": m.isotropic,
    }


def cmd_show(args) -> int:
    plot_format = _plot_format(args) if args.plot is not None else None
    robot = load_robot(args.robot)
    data = show_data(robot)
    # --- conditioning warning (robot-file validation): one line on stderr, a field in --json ---
    warning = robot.mobility.conditioning_warning
    data["condition_warning"] = warning
    if warning:
        print(f"omnikin: warning: {robot.name}: {warning}", file=sys.stderr)
    # --- end conditioning warning ---
    text = _json_checked(data)
    if args.plot is not None and plot_format is not None:
        _save_plot(robot, args.plot, plot_format)
    if args.json:
        print(text)
        return 0
    from rich.table import Table

    con = console()
    con.print(f"{robot.name}: {robot.description}")
    for ref in robot.references:
        con.print(f"  ref: {ref}")
    con.print("wheels (body frame: x forward, y left)")
    geo = Table()
    for col in (
        "name",
        "type",
        "x [m]",
        "y [m]",
        "angle [deg]",
        "drive [deg]",
        "roller [deg]",
        "radius [m]",
        "steer",
        "encoder",
    ):
        geo.add_column(col, justify="right" if "[" in col else "left")
    for w in data["wheels"]:
        steer = (
            f"offset {w['steer']['offset']:g} m, {w['steer']['min_deg']:g}..{w['steer']['max_deg']:g} deg"
            if "steer" in w
            else ""
        )
        enc = (
            (
                f"{w['encoder']['ticks_per_rev']:g}/rev x{w['encoder']['gear_ratio']:g}"
                + (" inv" if w["encoder"]["invert"] else "")
            )
            if "encoder" in w
            else ""
        )
        geo.add_row(
            w["name"],
            w["type"],
            _fmt(w["x"]),
            _fmt(w["y"]),
            _fmt(w["angle_deg"]),
            _fmt(w["drive_deg"]),
            _fmt(w["roller_deg"]),
            _fmt(w["radius"]),
            steer,
            enc,
        )
    con.print(geo)
    twist = ["vx", "vy", "omega"]
    note = " at zero steering" if robot.steerable else ""
    con.print(f"inverse kinematics{note}: wheel speeds [rad/s] = J (vx, vy, omega)")
    con.print(_matrix_table(data["ik_matrix"], robot.rolling_names, twist))
    con.print(f"forward kinematics{note}: (vx, vy, omega) = F wheel speeds (least squares)")
    con.print(_matrix_table(data["fk_matrix"], twist, robot.rolling_names))
    if data["fk_rank"] < data["mobility"]:
        con.print(
            f"note: at zero steering the wheel speeds determine only {data['fk_rank']} of the "
            f"{data['mobility']} motion components; F is the minimum-norm solution there"
        )
    con.print("mobility analysis (Campion, Bastin, d'Andrea-Novel 1996)")
    ana = Table()
    ana.add_column("quantity")
    ana.add_column("value", justify="right")
    rank_label = "rank of J (generic steering)" if robot.steerable else "rank of J"
    for k, v in (
        (rank_label, data["rank"]),
        ("degree of mobility", data["mobility"]),
        ("degree of steerability", data["steerability"]),
        ("Campion type", f"{tuple(data['campion_type'])} {data['campion_name']}"),
        ("holonomic", "yes" if data["holonomic"] else "no"),
        ("condition number", _fmt(data["condition_number"])),
        ("characteristic length [m]", _fmt(data["characteristic_length"])),
        ("isotropic", "yes" if data["isotropic"] else "no"),
    ):
        ana.add_row(k, str(v))
    con.print(ana)
    if args.plot is not None:
        con.print(f"layout drawing written to {args.plot}")
    return 0


def _plot_format(args) -> str:
    """The drawing format of ``--plot FILE`` (from its extension), checked with the output
    before any work: never the robot file, an existing file only with ``--force``."""
    from ..viz import require_matplotlib

    require_matplotlib()
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    suffix = os.path.splitext(args.plot)[1].lower().lstrip(".")
    if suffix not in formats:
        raise CliError(
            f"--plot {shorten(args.plot)}: unknown drawing format {shorten(suffix) if suffix else '(no extension)'}; "
            f"one of {', '.join(sorted(formats))}"
        )
    return suffix


def _save_plot(robot, path, fmt: str) -> None:
    """Draw the layout to ``path`` atomically (a failure leaves no partial file)."""
    from ..io.output import atomic_write
    from ..viz.layout import layout_figure

    figure = layout_figure(robot)
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format=fmt)


def _json_checked(data) -> str:
    """The ``--json`` text of a result, made in text mode too: a non-finite number in a result
    is an error naming its field either way (never a silent ``inf`` in a table)."""
    from ..io.jsonfile import to_json

    return to_json(data)


# --- ik / fk -------------------------------------------------------------------------------
def cmd_ik(args) -> int:
    robot = load_robot(args.robot)
    twist = np.array([args.vx, args.vy, args.omega])
    hint = np.radians(args.steer_hint_deg) if args.steer_hint_deg is not None else None
    if hint is not None and not robot.steerable:
        raise CliError(f"robot {robot.name!r} has no steerable wheel: drop --steer-hint-deg")
    if hint is not None and len(hint) != len(robot.steerable):
        raise CliError(f"--steer-hint-deg needs {len(robot.steerable)} values for {robot.steer_names}")
    try:
        res = robot.ik(
            twist, heading=args.heading, steer_hint=hint, on_infeasible="return" if args.allow_infeasible else "raise"
        )
    except InfeasibleTwistError as exc:
        raise CliError(f"{exc.detail}; --allow-infeasible reports the violation instead") from None
    body = robot.body_twist(twist, args.heading) if args.heading is not None else twist
    data = {
        "robot": robot.name,
        "twist": body.tolist(),
        "wheel_names": robot.rolling_names,
        "wheel_speeds": res.wheel_speeds.tolist(),
    }
    if robot.steerable:
        data["steer_names"] = robot.steer_names
        data["steer_angles"] = res.steer_angles.tolist()
    if robot.swedish_names:
        data["roller_names"] = robot.swedish_names
        data["roller_speeds"] = robot.roller_speeds(body).tolist()
    if robot.fixed:
        data["violation"] = res.violation.tolist()
    if robot.steerable:
        data["steer_limited"] = res.steer_limited.tolist()
    data["feasible"] = bool(res.feasible)
    text = _json_checked(data)
    if args.json:
        print(text)
        return 0
    from rich.table import Table

    con = console()
    shown = _clean(body)
    con.print(
        f"{robot.name}: body twist vx={_fmt(shown[0])} m/s, vy={_fmt(shown[1])} m/s, omega={_fmt(shown[2])} rad/s"
    )
    table = Table(title_justify="left")
    for col in ("wheel", "speed [rad/s]", "steer [deg]", "roller [m/s]"):
        table.add_column(col, justify="right")
    steer = dict(zip(robot.steer_names, _clean(res.steer_angles), strict=True))
    roller = dict(zip(robot.swedish_names, _clean(data.get("roller_speeds", [])), strict=True))
    for name, speed in zip(robot.rolling_names, _clean(res.wheel_speeds), strict=True):
        table.add_row(
            name,
            _fmt(speed),
            _fmt(math.degrees(steer[name])) if name in steer else "",
            _fmt(roller[name]) if name in roller else "",
        )
    con.print(table)
    if not res.feasible:
        if robot.fixed and np.any(np.abs(res.violation) > 1e-9):
            slips = ", ".join(f"{w.name} {v:.6g}" for w, v in zip(robot.fixed, res.violation, strict=True))
            con.print(f"infeasible: fixed wheels would slide sideways [m/s]: {slips}")
        limited = [n for n, flag in zip(robot.steer_names, np.atleast_1d(res.steer_limited), strict=False) if flag]
        if limited:
            con.print(f"infeasible: no steering angle within limits (or no steady one) for {', '.join(limited)}")
    return 0


def cmd_fk(args) -> int:
    robot = load_robot(args.robot)
    n = len(robot.rolling_names)
    if len(args.speeds) != n:
        raise CliError(
            f"robot {robot.name!r} has {n} rolling wheels {robot.rolling_names}: "
            f"give {n} wheel speeds, got {len(args.speeds)}"
        )
    steer = None
    if robot.steerable:
        if args.steer_deg is None or len(args.steer_deg) != len(robot.steerable):
            raise CliError(
                f"robot {robot.name!r} has steerable wheels {robot.steer_names}: give their steering "
                f"angles with --steer-deg ({len(robot.steerable)} values)"
            )
        steer = np.radians(args.steer_deg)
    elif args.steer_deg is not None:
        raise CliError(f"robot {robot.name!r} has no steerable wheel: drop --steer-deg")
    res = robot.fk(np.array(args.speeds), steer)
    data = {
        "robot": robot.name,
        "wheel_names": robot.rolling_names,
        "twist": res.twist.tolist(),
        "residual": res.residual.tolist(),
        "residual_norm": float(res.residual_norm),
    }
    text = _json_checked(data)
    if args.json:
        print(text)
        return 0
    con = console()
    t = _clean(res.twist)
    con.print(f"{robot.name}: vx={_fmt(t[0])} m/s, vy={_fmt(t[1])} m/s, omega={_fmt(t[2])} rad/s")
    speeds = float(np.max(np.abs(args.speeds)))  # the residual's rounding noise is relative to the speeds
    residual, norm = _clean(res.residual, speeds), _clean([res.residual_norm], speeds)[0]
    con.print(f"residual [rad/s]: {[float(_fmt(v)) for v in residual]} (norm {_fmt(norm)})")
    return 0


# --- odometry -----------------------------------------------------------------------------------
def cmd_odometry(args) -> int:
    from ..errors import OdometryInputError
    from ..io.logs import read_tick_log
    from ..io.output import is_stdout
    from ..io.trajectories import write_trajectory
    from ..odometry.batch import batch_odometry

    to_stdout = is_stdout(args.output)
    robot = load_robot(args.robot)
    log = read_tick_log(args.log, robot)
    if log.duplicate_lines:
        lines = ", ".join(map(str, log.duplicate_lines[:10])) + (" ..." if len(log.duplicate_lines) > 10 else "")
        print(
            f"omnikin: warning: {args.log}: skipped {len(log.duplicate_lines)} row(s) repeating the previous "
            f"sample exactly (line {lines})",
            file=sys.stderr,
        )
    try:
        res = batch_odometry(
            robot,
            log.t,
            log.ticks,
            steer=log.steer,
            method=args.method,
            counter_bits=args.counter_bits,
            max_wheel_speed=args.max_wheel_speed,
            max_wheel_accel=args.max_wheel_accel,
        )
    except OdometryInputError as exc:
        if exc.sample is None:
            raise CliError(f"{args.log}: {exc}") from None
        raise CliError(f"{args.log}: line {log.lines[exc.sample]}: {exc.detail}") from None
    write_trajectory(args.output, log.t, res.poses, args.format, force=args.force, inputs=command_inputs(args))
    end = res.poses[-1]
    path = float(np.sum(np.hypot(*np.diff(res.poses[:, :2], axis=0).T)))
    summary = {
        "robot": robot.name,
        "samples": int(len(log.t)),
        "duration": float(log.t[-1] - log.t[0]),
        "method": args.method,
        "final_pose": end.tolist(),
        "path_length": path,
        "max_residual": float(np.max(np.abs(res.residual))) if res.residual.size else 0.0,
        "output": str(args.output),
        "format": args.format,
        "duplicate_lines": list(log.duplicate_lines),
    }
    if args.json:
        print_json(summary)
    else:
        console().print(
            f"{robot.name}: {summary['samples']} samples over {summary['duration']:.6g} s, {args.method} integration\n"
            f"final pose x={end[0]:.6g} m, y={end[1]:.6g} m, theta={end[2]:.6g} rad; path {path:.6g} m\n"
            f"written to {'standard output' if to_stdout else args.output} ({args.format})"
        )
    return 0


# --- parser --------------------------------------------------------------------------------------------
def build_parser() -> CommandParser:
    p = CommandParser(
        prog="omnikin",
        description="Kinematics and exact odometry for wheeled mobile robots of any wheel layout.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"omnikin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    robot_help = (
        f"preset name ({', '.join(PRESET_NAMES)}) or robot file path (YAML/JSON, schema 1); a preset "
        "name always means the preset: write ./NAME for a file of the current folder named like one"
    )

    sp = sub.add_parser(
        "presets",
        help="list the shipped robots",
        description="List the robots shipped with omnikin.",
        epilog="examples:\n  omnikin presets\n  omnikin presets --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("--json", action="store_true", help="machine-readable output")
    sp.set_defaults(func=cmd_presets)

    sp = sub.add_parser(
        "show",
        help="geometry, IK/FK matrices and mobility analysis of a robot",
        description="Show a robot: wheel table, inverse and forward kinematics matrices, "
        "rank, Campion type, holonomy and conditioning; optionally draw it.",
        epilog="example: omnikin show tomasi-omni3 --plot layout.png",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument(
        "--json", action="store_true", help="print JSON (keys ik_matrix, rank, mobility, steerability, ...)"
    )
    add_output(
        sp,
        "--plot",
        stdout=False,
        metavar="FILE.png",
        help="draw the layout with drive and roller directions (format from the extension: png, svg, pdf, ...)",
    )
    add_output_options(sp)
    declare_inputs(sp, robots=("robot",))
    sp.set_defaults(func=cmd_show)

    sp = sub.add_parser(
        "ik",
        help="inverse kinematics: twist -> wheel speeds (and steering)",
        description="Wheel speeds [rad/s, robot-file order] for a body twist VX VY [m/s] OMEGA "
        "[rad/s]; with --heading the velocity is given in the world frame.",
        epilog="examples:\n  omnikin ik tomasi-omni3 0.2 0 0.5\n"
        "  omnikin ik diff-drive 0.5 0.1 0 --allow-infeasible --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("vx", type=number, metavar="VX", help="velocity along body x [m/s] (world x with --heading)")
    sp.add_argument("vy", type=number, metavar="VY", help="velocity along body y [m/s] (world y with --heading)")
    sp.add_argument("omega", type=number, metavar="OMEGA", help="turn rate [rad/s], counter-clockwise positive")
    sp.add_argument("--heading", type=number, metavar="RAD", help="robot heading [rad]: VX VY are world-frame rates")
    sp.add_argument(
        "--steer-hint-deg",
        type=number,
        nargs="+",
        metavar="DEG",
        help="current steering angles [deg]: the nearest valid alignment is chosen",
    )
    sp.add_argument(
        "--allow-infeasible",
        action="store_true",
        help="report the side-slip violation of fixed wheels instead of refusing the twist",
    )
    sp.add_argument("--json", action="store_true", help="print JSON (keys wheel_speeds, steer_angles [rad], ...)")
    sp.set_defaults(func=cmd_ik)

    sp = sub.add_parser(
        "fk",
        help="forward kinematics: wheel speeds -> twist and residual",
        description="Body twist from wheel speeds [rad/s] of all rolling wheels in robot-file "
        "order, by least squares; the residual measures slip or model error.",
        epilog="example: omnikin fk omni4 10 -5 -10 5 --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("speeds", type=number, nargs="+", metavar="W", help="wheel speeds [rad/s]")
    sp.add_argument(
        "--steer-deg",
        type=number,
        nargs="+",
        metavar="DEG",
        help="steering angles [deg] of the steerable wheels (required for them)",
    )
    sp.add_argument("--json", action="store_true", help="print JSON (keys twist, residual)")
    sp.set_defaults(func=cmd_fk)

    sp = sub.add_parser(
        "odometry",
        help="integrate an encoder tick log into a trajectory",
        description="Read a CSV tick log (header: t, then one column per encoded wheel named by "
        "the wheel, plus <wheel>_steer_deg for steerable wheels), integrate it exactly "
        "on SE(2) and write the trajectory.",
        epilog="examples:\n  omnikin odometry tomasi-omni3 log.csv -o traj.tum --format tum\n"
        "  evo_traj tum traj.tum --plot\n"
        "  omnikin odometry my_robot.yaml log.csv -o - --counter-bits 16 | head\n\n"
        "tick readings: integers (ASCII digits, optional leading '-'), exact up to 64 bits.\n"
        "A jump no wheel could make in one sample, or a change of speed no wheel could make\n"
        "between two samples, is an error: if the counters wrap, give their width\n"
        "(--counter-bits or encoder.counter_bits in the robot file). docs/conventions.md\n"
        "says which wrapped counters are caught at which sample rates.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("log", metavar="LOG.csv", help="tick log")
    add_output(
        sp,
        "-o",
        "--output",
        required=True,
        metavar="OUT",
        help="trajectory file to write ('-': standard output, messages then go to standard error)",
    )
    add_output_options(sp)
    declare_inputs(sp, "log", robots=("robot",))
    sp.add_argument(
        "--format",
        choices=("csv", "tum", "kitti"),
        default="csv",
        help="csv: t,x,y,theta; tum: t x y z qx qy qz qw; kitti: 3x4 matrices (default csv)",
    )
    add_method_option(sp)
    sp.add_argument(
        "--counter-bits",
        type=whole,
        metavar="N",
        help="encoder counters wrap at 2**N (e.g. 16, 32); default: each wheel's encoder.counter_bits "
        "in the robot file (a different value there is an error), else no wrap-around",
    )
    add_wheel_bound_options(sp)
    sp.add_argument("--json", action="store_true", help="print a JSON summary")
    sp.set_defaults(func=cmd_odometry)
    from . import bag, export, ros, umbmark

    umbmark.add_parsers(sub, robot_help)
    _add_umbmark_analyze(sub.choices["umbmark"])
    bag.add_parsers(sub, robot_help)
    ros.add_parsers(sub, robot_help)
    from . import sim, sweep, view

    sim.add_parsers(sub, robot_help)
    view.add_parsers(sub, robot_help)
    sweep.add_parsers(sub, robot_help)
    export.add_parsers(sub, robot_help)
    return p


def _add_umbmark_analyze(umbmark_parser: CommandParser) -> None:
    """``omnikin umbmark analyze``: the options and behaviour of :func:`omnikin.cli.umbmark.analyze_parser`,
    as a command of ``umbmark`` beside its optional ROBOT (:meth:`CommandParser.add_command`)."""
    from .umbmark import analyze_parser

    spec = analyze_parser()
    analyze = CommandParser(
        prog="omnikin umbmark analyze",
        parents=[spec],
        add_help=False,
        description=spec.description,
        epilog=spec.epilog,
        formatter_class=spec.formatter_class,
    )
    umbmark_parser.add_command("analyze", analyze)


# --- running a command ----------------------------------------------------------------------------------
def main(argv=None) -> int:
    """Run ``omnikin`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Every failure ends here as one line on stderr (:func:`_fail`), whatever raised it: usage
    and input errors (2), failures while running (1; writing an output: the one place an
    :class:`OutputError` becomes a status), a closed pipe (141, quiet),
    floating-point trouble in omnikin's own computations (2: an input out of range; NumPy's
    warnings are errors inside a command), anything unexpected (1, ``internal error``; set
    ``OMNIKIN_TRACEBACK=1`` to see where). Other libraries' warnings print as one line.
    Standard output and error may be closed or in an encoding without every character
    (:func:`_standard_streams`). Ctrl-C, SIGTERM and SIGHUP (:class:`Terminated`) are not
    failures: a server (:data:`SERVERS`) ends with status 0 (:func:`_stopped`), any other
    command with 130 or 128 + the signal (:func:`_ended`).
    """
    argv = [str(a) for a in (sys.argv[1:] if argv is None else argv)]
    STOPPED.clear()
    with _standard_streams(), _termination_unwinds() as fired:
        status = _main(argv, fired)
    forget_handled_interrupt()  # a Ctrl-C handled above must not still end the process by SIGINT
    return status


def _main(argv: list[str], fired: list[int]) -> int:
    # the command's name: parsed, or before that the first argument naming a server (a server
    # stopped while omnikin still starts is stopped all the same)
    command: list[str] = [argv[0]] if argv and argv[0] in SERVERS else []
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            warnings.filterwarnings("error", category=RuntimeWarning, module=r"omnikin(\.|$)")
            try:
                status = _run(argv, command)
            except Exception:
                if fired:  # a library turned the termination into an error of its own (matplotlib's
                    raise Terminated(fired[0]) from None  # C code: 'initialization failed'): it is one
                raise
            if STOPPED and command and command[0] in SERVERS:  # stopped inside until_stopped()
                _stopped(command[0], STOPPED[0])
            sys.stdout.flush()  # a full disk or a closed pipe shows here, not at exit
            return status
    except (KeyboardInterrupt, Terminated) as exc:
        if command and command[0] in SERVERS:  # the user stops a server: its normal end
            return _stopped(command[0], stop_name(exc))
        if isinstance(exc, Terminated):
            return _ended(f"terminated ({stop_name(exc)})", 128 + exc.signum)
        return _ended(f"interrupted; {exc}" if str(exc) else "interrupted", 130)
    except UsageError as exc:
        return _fail(f"{exc.command + ': ' if exc.command else ''}{exc} (see {exc.help_hint})", 2)
    except OutputError as exc:  # the one place for write failures: the message names the path
        return _fail(exc, 1)
    except InfeasibleTwistError as exc:  # without the library's way out (a Python argument)
        return _fail(exc.detail, 2)
    except InputError as exc:
        return _fail(exc, 2)
    except OmnikinError as exc:  # LinkError: failures while running
        return _fail(exc, 1)
    except ImportError as exc:  # an optional extra is missing (the message names it)
        return _fail(exc, 2)
    except BrokenPipeError:  # the reader of standard output went away: stop quietly
        _quiet_stdout()
        return 141
    except (RuntimeWarning, FloatingPointError) as exc:
        return _fail(f"numerical failure ({exc}): an input is probably beyond the range omnikin computes with", 2)
    except MemoryError:
        return _fail("out of memory; lower the sizes of the job (see --max-memory of the command)", 1)
    except OSError as exc:  # not raised by omnikin's readers and writers: standard output
        _quiet_stdout()
        where = f"{exc.filename}" if exc.filename else "standard output"
        return _fail(
            f"{where}: cannot write: {exc.strerror or exc}"
            if exc.errno in WRITE_ERRORS
            else f"{where}: {exc.strerror or exc}",
            1,
        )
    except Exception as exc:  # noqa: BLE001 (the promise: no traceback reaches a user)
        if os.environ.get("OMNIKIN_TRACEBACK"):
            import traceback

            traceback.print_exc()
        return _fail(
            f"internal error: {type(exc).__name__}: {exc} (a bug in omnikin: please report it with the "
            f"command line; OMNIKIN_TRACEBACK=1 shows where)",
            1,
        )


def _run(argv: list[str], command: list[str]) -> int:
    """Parse and run; the command's name is appended to ``command`` once known."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help and --version print, then argparse exits
        return exc.code if isinstance(exc.code, int) else 0
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    command[:] = [args.command]
    with running(args):  # every output of the command checked together before any work
        return args.func(args)


def _fail(message, status: int) -> int:
    """Print ``omnikin: error: MESSAGE`` as one bounded line on stderr; return ``status``."""
    return _say(f"omnikin: error: {one_line(message, MESSAGE_LIMIT)}", status)


def _ended(message, status: int) -> int:
    """A command the user interrupted or terminated before it finished: ``omnikin: MESSAGE`` (not
    an error: the user asked for it; the status, 130 or 128 + the signal, tells a script that
    the work is not done); return ``status``."""
    return _say(f"omnikin: {one_line(message, MESSAGE_LIMIT)}", status)


def _stopped(command: str, how: str) -> int:
    """A server the user stopped (:data:`SERVERS`): ``omnikin COMMAND: stopped (HOW)``, status 0."""
    return _say(f"omnikin {command}: stopped ({how})", 0)


def _say(line: str, status: int) -> int:
    try:
        print(line, file=sys.stderr)
        sys.stderr.flush()
    except (OSError, ValueError):  # stderr itself is gone: nothing more to say
        pass
    return status


SERVERS = frozenset({"view", "sim", "ros"})
"""Commands that run until the user stops them (a page, a window, a ROS node): Ctrl-C, SIGTERM
or SIGHUP is their normal end, status 0 (:func:`_stopped`)."""


TERMINATION_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
"""Signals that end a command like Ctrl-C does (:class:`Terminated`): ``timeout``, ``kill``,
systemd, a closed terminal."""


@contextlib.contextmanager
def _termination_unwinds() -> Iterator[list[int]]:
    """Turn the first termination signal into :class:`Terminated` while a command runs; later
    ones are ignored, to the end of the process (the cleanup the first one started must finish,
    and the process is ending). Without a signal the previous handlers come back after. A
    signal the caller ignores (``nohup``) stays ignored. Only in the main thread. Yields the
    list of signals received, so that an error a library raised in place of the termination
    (it arrived inside its C code) is still reported as the termination."""
    fired: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield fired
        return

    def unwind(signum, frame):
        if not fired:
            fired.append(signum)
            raise Terminated(signum)

    previous = {}
    for sig in TERMINATION_SIGNALS:
        handler = signal.getsignal(sig)
        if handler is not signal.SIG_IGN:
            previous[sig] = signal.signal(sig, unwind)
    try:
        yield fired
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, signal.SIG_IGN if fired else signal.SIG_DFL if handler is None else handler)


class _ClosedStream(io.TextIOBase):
    """Stands for standard output when the process has none (started with ``>&-``): writing to it
    is an ``OSError`` (EBADF), which :func:`main` reports as one line with status 1."""

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "it is closed")

    def isatty(self) -> bool:
        return False


@contextlib.contextmanager
def _standard_streams() -> Iterator[None]:
    """Standard output and error, usable whatever the process was given: a missing one (closed
    by the caller) is replaced (standard output by :class:`_ClosedStream`, standard error by
    the null device: nothing more can be said), and characters the stream's encoding lacks
    (``PYTHONIOENCODING=ascii``, a C locale) are written as backslash escapes instead of
    failing. Data written to ``-`` is UTF-8 whatever the encoding
    (:func:`omnikin.io.output.write_text`). Restored after the command."""
    saved = sys.stdout, sys.stderr
    errors = {}
    devnull = None
    if sys.stdout is None:
        sys.stdout = _ClosedStream()
    if sys.stderr is None:
        devnull = sys.stderr = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (closed below)
    for stream in (sys.stdout, sys.stderr):
        if isinstance(stream, io.TextIOWrapper) and stream.errors != "backslashreplace":
            errors[stream] = stream.errors
            with contextlib.suppress(OSError, ValueError):
                stream.reconfigure(errors="backslashreplace")
    try:
        yield
    finally:
        for stream, old in errors.items():
            with contextlib.suppress(OSError, ValueError):
                stream.reconfigure(errors=old)
        if devnull is not None:
            devnull.close()
        sys.stdout, sys.stderr = saved


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings of other libraries as one line (``warnings.showwarning`` during a command)."""
    try:
        print(f"omnikin: warning: {one_line(message, MESSAGE_LIMIT)}", file=sys.stderr)
    except (OSError, ValueError):
        pass


def _quiet_stdout() -> None:
    """After standard output failed (closed pipe, full disk), point it at /dev/null so that the
    interpreter's final flush does not print a second error."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (a test's capture)
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
    except OSError:
        pass


if __name__ == "__main__":
    sys.exit(main())
