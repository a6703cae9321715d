"""``omnikin fk``: forward kinematics, wheel speeds to the body twist and its residual
(:meth:`omnikin.Robot.fk`)."""

from __future__ import annotations

import argparse

import numpy as np

from ..errors import CliError
from .common import cell, console, denoised, json_checked, load_robot, number


def add_parser(sub, robot_help: str) -> None:
    """Add ``fk`` to ``sub``."""
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
    sp.set_defaults(func=run)


def run(args) -> int:
    """Print the body twist of the wheel speeds and its residual (or ``--json``); status 0."""
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
    text = json_checked(data)
    if args.json:
        print(text)
        return 0
    con = console()
    t = denoised(res.twist)
    con.print(f"{robot.name}: vx={cell(t[0])} m/s, vy={cell(t[1])} m/s, omega={cell(t[2])} rad/s")
    speeds = float(np.max(np.abs(args.speeds)))  # the residual's rounding noise is relative to the speeds
    residual, norm = denoised(res.residual, speeds), denoised([res.residual_norm], speeds)[0]
    con.print(f"residual [rad/s]: {[float(cell(v)) for v in residual]} (norm {cell(norm)})")
    return 0
