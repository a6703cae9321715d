"""``omnikin ik``: inverse kinematics, a body twist to wheel speeds and steering angles
(:meth:`omnikin.Robot.ik`)."""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..errors import CliError, InfeasibleTwistError
from .common import cell, console, denoised, json_checked, load_robot, number


def add_parser(sub, robot_help: str) -> None:
    """Add ``ik`` to ``sub``."""
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
    sp.set_defaults(func=run)


def run(args) -> int:
    """Print the wheel speeds and steering angles of the twist (or ``--json``); status 0."""
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
    text = json_checked(data)
    if args.json:
        print(text)
        return 0
    from rich.table import Table

    con = console()
    shown = denoised(body)
    con.print(
        f"{robot.name}: body twist vx={cell(shown[0])} m/s, vy={cell(shown[1])} m/s, omega={cell(shown[2])} rad/s"
    )
    table = Table(title_justify="left")
    for col in ("wheel", "speed [rad/s]", "steer [deg]", "roller [m/s]"):
        table.add_column(col, justify="right")
    steer = dict(zip(robot.steer_names, denoised(res.steer_angles), strict=True))
    roller = dict(zip(robot.swedish_names, denoised(data.get("roller_speeds", [])), strict=True))
    for name, speed in zip(robot.rolling_names, denoised(res.wheel_speeds), strict=True):
        table.add_row(
            name,
            cell(speed),
            cell(math.degrees(steer[name])) if name in steer else "",
            cell(roller[name]) if name in roller else "",
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
