"""``omnikin show``: a robot's wheel table, kinematic matrices and mobility analysis, and its
layout drawn (``--plot``, :func:`omnikin.plot_layout`)."""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

from ..common.messages import shorten
from ..errors import CliError
from .common import (
    add_output,
    add_output_options,
    cell,
    console,
    declare_inputs,
    denoised,
    json_checked,
    load_robot,
)


def add_parser(sub, robot_help: str) -> None:
    """Add ``show`` to ``sub``."""
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
    sp.set_defaults(func=run)


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


def run(args) -> int:
    """Print the robot (or ``--json``) and draw ``--plot``; status 0."""
    plot_format = _plot_format(args) if args.plot is not None else None
    robot = load_robot(args.robot)
    data = show_data(robot)
    # --- conditioning warning (robot-file validation): one line on stderr, a field in --json ---
    warning = robot.mobility.conditioning_warning
    data["condition_warning"] = warning
    if warning:
        print(f"omnikin: warning: {robot.name}: {warning}", file=sys.stderr)
    # --- end conditioning warning ---
    text = json_checked(data)
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
            cell(w["x"]),
            cell(w["y"]),
            cell(w["angle_deg"]),
            cell(w["drive_deg"]),
            cell(w["roller_deg"]),
            cell(w["radius"]),
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
        ("condition number", cell(data["condition_number"])),
        ("characteristic length [m]", cell(data["characteristic_length"])),
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
    """Draw the layout (:func:`omnikin.plot_layout`) to ``path`` atomically (a failure leaves no
    partial file)."""
    from ..api import plot_layout
    from ..io.output import atomic_write

    figure = plot_layout(robot)
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format=fmt)


def _matrix_table(matrix, row_names, col_names):
    from rich.table import Table

    table = Table()
    table.add_column("")
    for c in col_names:
        table.add_column(c, justify="right")
    for name, row in zip(row_names, np.atleast_2d(denoised(matrix)), strict=True):
        table.add_row(name, *[cell(v) for v in row])
    return table
