"""``omnikin metrics``: ATE and RPE of an estimated trajectory against a reference
(:mod:`omnikin.evaluation.metrics`: evo's definitions, in the plane)."""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..errors import InputError, OmnikinError
from .budget import add_budget_options, require
from .common import console, number, print_json, whole

METRICS_EPILOG = """examples:
  omnikin metrics truth.tum odom.tum
  omnikin metrics truth.tum odom.tum --align --delta 10 --json
  omnikin metrics truth.tum odom.csv --t-max-diff 0.02 --t-offset 0.005

files: TUM (t x y z qx qy qz qw), KITTI (12 numbers per line; pose k at t = k) or CSV
(header t,x,y,theta), detected from the first line. ATE: translation error after optional SE(2)
alignment (Umeyama without scale); RPE: over DELTA frames of the associated poses,
non-overlapping pairs unless --all-pairs. Same definitions as evo_ape / evo_rpe (--pose_relation
trans_part, --delta N --delta_unit f)."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``metrics`` to ``sub``."""
    sp = sub.add_parser(
        "metrics",
        help="ATE and RPE of an estimated trajectory against a reference",
        description="Absolute trajectory error (translation, optionally after SE(2) alignment) "
        "and relative pose error (translation and rotation over DELTA frames) of EST "
        "against REF, after associating their timestamps.",
        epilog=METRICS_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("ref", metavar="REF", help="reference trajectory (TUM, KITTI or CSV)")
    sp.add_argument("est", metavar="EST", help="estimated trajectory (TUM, KITTI or CSV)")
    sp.add_argument("--align", action="store_true", help="align EST to REF by SE(2) least squares before the ATE")
    sp.add_argument("--delta", type=whole, default=1, metavar="N", help="RPE pose distance in frames (default 1)")
    sp.add_argument("--all-pairs", action="store_true", help="RPE over all pairs (i, i+N), not only consecutive")
    sp.add_argument(
        "--t-max-diff",
        type=number,
        default=0.01,
        metavar="SEC",
        help="largest time difference of associated poses [s] (default 0.01)",
    )
    sp.add_argument(
        "--t-offset",
        type=number,
        default=0.0,
        metavar="SEC",
        help="time offset added to EST's timestamps [s] (default 0)",
    )
    sp.add_argument("--json", action="store_true", help="print JSON (rotation in rad and in deg)")
    add_budget_options(sp, time=False)
    sp.set_defaults(func=run)


def run(args) -> int:
    """Print the ATE and RPE (or ``--json``); status 0."""
    from ..evaluation.metrics import evaluate, statistics
    from ..io.trajectories import detect_format, read_trajectory

    if args.delta < 1:
        raise InputError(f"--delta must be a whole number of frames >= 1, got {args.delta}")
    if not (math.isfinite(args.t_max_diff) and args.t_max_diff >= 0):
        raise InputError(f"--t-max-diff must be a time >= 0 [s], got {args.t_max_diff}")
    if not math.isfinite(args.t_offset):
        raise InputError(f"--t-offset must be a finite time [s], got {args.t_offset}")
    paths = (args.ref, args.est)
    for path in paths:
        _size_trajectory_file(args, path)
    formats = [detect_format(p) for p in paths]
    if formats.count("kitti") == 1:
        kitti, timed = paths if formats[0] == "kitti" else paths[::-1]
        raise InputError(
            f"{kitti} is KITTI (no timestamps: pose k stands at t = k) but {timed} has timestamps "
            f"[s]: they cannot be associated; export both as TUM or CSV, or both as KITTI to "
            f"compare by index"
        )
    t_ref, ref = read_trajectory(args.ref, formats[0])
    t_est, est = read_trajectory(args.est, formats[1])
    try:
        ev = evaluate(
            t_ref,
            ref,
            t_est,
            est,
            align=args.align,
            delta=args.delta,
            all_pairs=args.all_pairs,
            max_diff=args.t_max_diff,
            offset=args.t_offset,
        )
    except OmnikinError as exc:
        raise InputError(f"{args.ref} vs {args.est}: {exc}") from None
    rot_deg = statistics(np.degrees(ev.rpe.rotation))
    doc = {
        "reference": args.ref,
        "estimate": args.est,
        "reference_poses": len(t_ref),
        "estimate_poses": len(t_est),
        **ev.as_dict(),
    }
    doc["rpe"]["rotation_deg"] = rot_deg.as_dict()
    if args.json:
        print_json(doc)
        return 0
    from rich.table import Table

    con = console(120)
    a = ev.ate
    con.print(
        f"{args.est} against {args.ref}: {a.errors.size} associated poses (of {len(t_est)} and {len(t_ref)}; "
        f"max time difference {args.t_max_diff:g} s" + (f", offset {args.t_offset:g} s" if args.t_offset else "") + ")"
    )
    if a.alignment is not None:
        al = a.alignment
        con.print(f"SE(2) alignment: x={al.x:.6g} m, y={al.y:.6g} m, theta={math.degrees(al.theta):.6g} deg")
    table = Table(title_justify="left")
    cols = ("rmse", "mean", "median", "std", "min", "max")
    table.add_column("")
    for c in cols:
        table.add_column(c, justify="right")
    pairs = "all pairs (i, i+N)" if args.all_pairs else "consecutive pairs"
    con.print(f"RPE over delta N = {args.delta} frames: {ev.rpe.translation.size} {pairs}")
    rows = (
        ("ATE translation [m]" + (" (aligned)" if args.align else ""), a.stats),
        ("RPE translation [m]", ev.rpe.translation_stats),
        ("RPE rotation [deg]", rot_deg),
    )
    for label, s in rows:
        table.add_row(label, *[f"{getattr(s, c):.6g}" for c in cols])
    con.print(table)
    return 0


TRAJECTORY_BYTES_PER_FILE_BYTE = 24
"""Memory to read a trajectory file, per byte of the file (its text, its lines as Python
strings, the parsed numbers): measured 4 for TUM lines, 9 for KITTI, 16 for 12-byte CSV lines."""


def _size_trajectory_file(args, path) -> None:
    """Refuse a trajectory file too large to read within ``--max-memory`` (from its size; a pipe
    has none and is read as it comes, a device is refused by the reader)."""
    import os
    import stat

    try:
        info = os.stat(path)
    except OSError:
        return  # the reader names a missing or unreadable file
    if not stat.S_ISREG(info.st_mode):
        return
    size = info.st_size
    require(
        args,
        "metrics",
        memory=size * TRAJECTORY_BYTES_PER_FILE_BYTE,
        size=f"{path} ({size} bytes)",
        hint="compare shorter trajectories",
    )
