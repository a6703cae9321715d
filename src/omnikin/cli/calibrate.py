"""``omnikin calibrate``: a robot file calibrated from measured runs (:func:`omnikin.calibrate`),
or the runs to drive for it (``--plan``, :func:`omnikin.calibration_plan`)."""

from __future__ import annotations

import argparse

from ..api.calibration import calibrate, calibration_plan
from ..api.common import dumps
from ..errors import InputError
from ..evaluation.calibration import ERROR_UNITS, FIT_LIMIT
from ..motion.plans import UMBMARK_SIDE
from .common import add_output, add_output_options, command_inputs, console, declare_inputs, number


def add_parser(sub, robot_help: str) -> None:
    """Add ``calibrate`` to ``sub``."""
    sp = sub.add_parser(
        "calibrate",
        help="calibrate a robot file from measured runs",
        description="Least-squares calibration of the wheel radii, hub positions and drive "
        "directions from runs with measured end poses (docs/umbmark.md). --plan "
        "prints the runs to drive and a runs file to fill in.",
        epilog="examples:\n"
        "  omnikin calibrate tomasi-omni3 --plan > runs.csv     the runs to drive, to fill in\n"
        "  omnikin calibrate tomasi-omni3 runs.csv -o calibrated.yaml\n"
        "  omnikin calibrate tomasi-omni3 examples/calibration_runs.csv --json\n"
        "RUNS columns: path, x_abs, y_abs [m], optional theta_abs_deg [deg] (or theta_abs "
        "[rad]).\n'omnikin umbmark' writes one: umbmark-report/calibration_runs.csv.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("runs", metavar="RUNS", nargs="?", help="CSV of runs: path, x_abs, y_abs[, theta_abs_deg]")
    add_output(
        sp,
        "-o",
        "--output",
        metavar="FILE",
        help="write the calibrated robot file (YAML, or JSON for .json); with --plan, the runs file to fill in",
    )
    add_output_options(sp)
    declare_inputs(sp, "runs", robots=("robot",))
    sp.add_argument(
        "--plan", action="store_true", help="print the recommended calibration runs as a runs file to fill in (no RUNS)"
    )
    sp.add_argument(
        "--side",
        type=number,
        default=UMBMARK_SIDE,
        metavar="M",
        help="with --plan: side of the squares and length of the lines [m] (default 4)",
    )
    sp.add_argument("--json", action="store_true", help="print the result as JSON")
    sp.set_defaults(func=run)


def run(args) -> int:
    """Print the calibration (or ``--json``) and write ``--output``; with ``--plan``, the runs file
    to fill in; status 0."""
    if args.plan:
        if args.runs is not None:
            raise InputError("calibrate --plan prints the runs to drive; it takes no RUNS file")
        return _print_plan(args)
    if args.runs is None:
        raise InputError("calibrate: give RUNS (a runs file with measured end poses), or --plan for the runs to drive")
    from ..io.output import is_stdout

    inputs = command_inputs(args)
    to_stdout = bool(args.output) and is_stdout(args.output)
    cal = calibrate(args.robot, args.runs)
    if args.output:
        cal.write_robot(args.output, force=args.force, inputs=inputs)
    if args.json:
        print(
            dumps(
                {
                    **cal.as_dict(),
                    "units": {
                        "errors": ERROR_UNITS,
                        "residual_rms": "measurement sigmas",
                        "parameters": "each entry's 'unit'",
                    },
                    "output": args.output,
                }
            ),
            end="",
        )
        return 0
    from rich.table import Table

    con = console(120)
    t = Table(title=f"calibration of {cal.nominal.name} from {len(cal.runs)} runs", title_justify="left")
    for col in ("parameter", "estimate", "sigma", "unit"):
        t.add_column(col, justify="left" if col in ("parameter", "unit") else "right")
    for p in cal.parameters():
        t.add_row(p["name"], f"{p['value']:.6g}", f"{p['sigma']:.3g}", p["unit"])
    con.print(t)
    con.print(f"residual RMS {cal.residual_before:.3g} -> {cal.residual_after:.3g} measurement sigmas")
    if not cal.fits:
        con.print(
            f"warning: the calibrated model does not fit the runs (residual RMS {cal.residual_after:.3g} "
            f"measurement sigmas, above {FIT_LIMIT:g}): check the robot file and the runs; do not use the "
            "calibrated robot"
        )
    for combo in cal.identifiability.blind:
        con.print("not observable by these runs: " + " + ".join(f"{c['weight']:+.2f} {c['parameter']}" for c in combo))
    if args.output and not to_stdout:
        con.print(f"calibrated robot written to {args.output}")
    return 0


def _print_plan(args) -> int:
    from ..evaluation.calibration import RECOMMENDED_REPEATS
    from ..io.output import check_output, is_stdout, write_text
    from ..io.runs import calibration_template

    paths = calibration_plan(args.robot, args.side)
    note = (
        f"calibration runs for {args.robot}: drive each path {RECOMMENDED_REPEATS} times, commanded by the "
        "robot's own (nominal) model,\n"
        "starting at rest at the origin (x forward, y left). Measure the end pose: x_abs, y_abs [m] to about "
        "1 mm,\n"
        "theta_abs_deg [deg] to about 0.2 deg (delete that column if you do not measure the heading).\n"
        "Fill in every field. Paths: square cw|ccw rotate|translate SIDE,\n"
        "line LENGTH HEADING_DEG, spin ANGLE_DEG (positive counter-clockwise), arc RADIUS ANGLE_DEG.\n"
        f"then: omnikin calibrate {args.robot} THIS_FILE -o calibrated.yaml"
    )
    text = calibration_template(paths, RECOMMENDED_REPEATS, note)
    if args.output:
        check_output(args.output, inputs=command_inputs(args), force=args.force)
        write_text(args.output, text)
        if not args.json and not is_stdout(args.output):
            console(120, stderr=True).print(f"runs file to fill in written to {args.output}")
    if args.json:
        print(
            dumps(
                {
                    "robot": args.robot,
                    "paths": paths,
                    "repeats": RECOMMENDED_REPEATS,
                    "columns": ["path", "x_abs", "y_abs", "theta_abs_deg"],
                    "output": args.output,
                }
            ),
            end="",
        )
    elif not args.output:
        print(text, end="")
    return 0
