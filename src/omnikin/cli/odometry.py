"""``omnikin odometry``: an encoder tick log integrated into a trajectory
(:func:`omnikin.odometry.batch.batch_odometry`), written as CSV, TUM or KITTI."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ..errors import CliError
from .common import (
    add_method_option,
    add_output,
    add_output_options,
    add_wheel_bound_options,
    command_inputs,
    console,
    declare_inputs,
    load_robot,
    print_json,
    whole,
)


def add_parser(sub, robot_help: str) -> None:
    """Add ``odometry`` to ``sub``."""
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
    sp.set_defaults(func=run)


def run(args) -> int:
    """Integrate the tick log, write the trajectory, print a summary; status 0."""
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
