"""``omnikin umbmark`` (:func:`omnikin.run_umbmark`) and its command ``omnikin umbmark analyze``
(:func:`omnikin.analyze_umbmark`).

Thin over the Python API (:mod:`omnikin.api`): the options' defaults are read from the
API's signatures, so the command line and ``omnikin.run_umbmark`` cannot disagree.
``omnikin umbmark`` runs the same study for every robot (``tomasi-omni3`` when none is
named): UMBmark of the robot as built, calibration, UMBmark again, the noise floor; the
report folder goes through :mod:`omnikin.io.output` (checked before anything runs, replaced
as a whole, never a foreign folder).
"""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

from ..api.common import dumps
from ..api.report import floor_limit, physics_floor_text
from ..api.umbmark import (
    DEFAULT_ROBOT,
    UMBmarkReport,
    analyze_umbmark,
    run_umbmark,
)
from ..common.number_text import mm_text, reduction_bounded, reduction_text
from ..motion.timing import RATE_RANGE
from ..physics.engines import ENGINE_NAMES
from ..simulation.error_models import NOISE, PROFILES
from ..viz import FIGURE_FORMATS, MAX_DPI, MIN_DPI, dpi_problem
from .budget import add_budget_options, require
from .common import (
    add_output,
    add_step_option,
    as_built_group,
    command_inputs,
    console,
    declare_inputs,
    engine_of,
    number,
    physics_hint,
    whole,
)
from .parser import CommandParser

DEFAULT_OUT = "umbmark-report"
"""The report folder of ``omnikin umbmark`` without ``-o``."""


def _defaults(function) -> dict:
    """Keyword defaults of ``function`` (the API entry point a command calls)."""
    return {
        name: p.default
        for name, p in inspect.signature(function).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


UMBMARK = _defaults(run_umbmark)
WRITE = _defaults(UMBmarkReport.write)
ANALYZE = _defaults(analyze_umbmark)

UMBMARK_EPILOG = f"""examples:
  omnikin umbmark                          {DEFAULT_ROBOT} as built: UMBmark, calibration, UMBmark again,
                                           report in ./{DEFAULT_OUT}
  omnikin umbmark diff-drive -o dd-report  any robot (preset or file); Borenstein's correction too
  omnikin umbmark mecanum4 --mode translate --trials 200 --json
  omnikin umbmark my.yaml --true-robot as_built.yaml --noise none --figures pdf
  omnikin umbmark --engine physics --side 1 --rate 50   every run in MuJoCo (extra physics), and the
                                           floor: the nominal robot's UMBmark in physics
  omnikin umbmark analyze measured.csv --robot diff-drive     for a real robot's runs

Every robot goes through the same steps; the calibration drives the runs of
'omnikin calibrate ROBOT --plan' (--no-calibrate skips it). --errors draws per-wheel systematic
errors ({", ".join(sorted(PROFILES))}); --noise adds run-to-run slip, floor and measurement errors
({", ".join(sorted(NOISE))}). The return error is the true end pose minus the odometry end pose
(Borenstein and Feng, "Measurement and correction of systematic odometry errors in mobile robots").
The report gives confidence intervals of E_max,syst and of the reduction factor (Hotelling's T^2,
3 runs per direction at least) and the noise floor: E_max,syst of the same robot perfectly
calibrated, under the same random errors."""


def add_parser(sub, robot_help: str) -> None:
    """Add ``umbmark`` to ``sub``, with ``analyze`` as its command (:func:`analyze_parser`)."""
    d = UMBMARK
    sp = sub.add_parser(
        "umbmark",
        help="UMBmark, calibration and report",
        description="Simulate the UMBmark odometry benchmark on a robot as built, calibrate it and "
        "run UMBmark again; write a report folder. 'omnikin umbmark analyze FILE' "
        "analyses a real robot's measurements.",
        epilog=UMBMARK_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument(
        "robot", nargs="?", default=d["robot"], metavar="ROBOT", help=f"{robot_help} (default {d['robot']})"
    )
    as_built = as_built_group(sp)
    as_built.add_argument(
        "--true-robot", metavar="FILE", default=d["true_robot"], help="the robot as built (replaces --errors)"
    )
    as_built.add_argument(
        "--errors",
        default=d["errors"],
        metavar="PROFILE",
        help=f"systematic error profile: {', '.join(sorted(PROFILES))} (default {d['errors']})",
    )
    sp.add_argument(
        "--mode",
        choices=("rotate", "translate"),
        default=d["mode"],
        help="square driven by turning in place at corners (rotate) or by translating with the "
        f"heading held (translate: robots that can move sideways); default {d['mode']}",
    )
    sp.add_argument(
        "--runs", type=whole, default=d["runs"], metavar="N", help=f"runs per direction (default {d['runs']})"
    )
    sp.add_argument(
        "--side", type=number, default=d["side"], metavar="M", help=f"side of the square [m] (default {d['side']:g})"
    )
    sp.add_argument(
        "--noise",
        default=d["noise"],
        metavar="PROFILE",
        help=f"random errors: {', '.join(sorted(NOISE))} (default typical; kinematic engine only)",
    )
    sp.add_argument(
        "--engine",
        choices=ENGINE_NAMES,
        default=d["engine"],
        help="kinematic: wheel motion with the --errors and --noise models; physics: every run in MuJoCo "
        "(rollers, motors; extra physics) on the robot as built, each run at roller phases drawn from --seed, "
        "and the floor: UMBmark of the nominal robot, what roller contact alone gives, with its spread "
        f"(default {d['engine']})",
    )
    add_step_option(sp, "time step of the physics engine (--engine physics)")
    sp.add_argument(
        "--rate",
        type=number,
        default=d["rate"],
        metavar="HZ",
        help=f"encoder sample rate [Hz], {RATE_RANGE[0]:g} to {RATE_RANGE[1]:g} (default {d['rate']:g})",
    )
    sp.add_argument(
        "--seed",
        type=whole,
        default=d["seed"],
        metavar="N",
        help=f"random seed (default {d['seed']}); the same seed builds the same robot, calibration and "
        "first procedures whatever --trials (in physics: the same roller phases of every run)",
    )
    sp.add_argument(
        "--trials",
        type=whole,
        default=d["trials"],
        metavar="N",
        help="repeat each UMBmark procedure N times with fresh random errors (Monte Carlo; the robot "
        f"as built and its calibration stay the same; default {d['trials']})",
    )
    sp.add_argument(
        "--calibrate",
        action=argparse.BooleanOptionalAction,
        default=d["calibrate"],
        help="calibrate and run UMBmark again (default on; --no-calibrate: UMBmark only)",
    )
    add_output(
        sp,
        "-o",
        "--out",
        folder="report",
        default=DEFAULT_OUT,
        metavar="DIR",
        help=f"report folder (default ./{DEFAULT_OUT}); a folder omnikin wrote is replaced as a whole, "
        "any other non-empty folder is refused",
    )
    sp.add_argument(
        "--figures",
        choices=FIGURE_FORMATS,
        default=WRITE["figure_format"],
        help=f"figure format: png, or svg/pdf (vector) for papers (default {WRITE['figure_format']})",
    )
    sp.add_argument(
        "--dpi",
        type=dpi,
        default=WRITE["dpi"],
        metavar="N",
        help=f"resolution of PNG figures [dots per inch], {MIN_DPI} (screens) to {MAX_DPI} (print; "
        f"default {WRITE['dpi']:g})",
    )
    sp.add_argument("--json", action="store_true", help="print result.json instead of tables")
    add_budget_options(sp)
    declare_inputs(sp, robots=("robot", "true_robot"))
    sp.set_defaults(func=run)
    _add_analyze(sp)


def add_analyze_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of ``omnikin umbmark analyze`` (for a parser or a sub-command parser)."""
    p.add_argument("measurements", metavar="MEASUREMENTS.csv")
    p.add_argument(
        "--robot",
        metavar="ROBOT",
        default=ANALYZE["robot"],
        help="the robot (a differential drive gets Borenstein's correction)",
    )
    p.add_argument(
        "--side",
        type=number,
        default=ANALYZE["side"],
        metavar="L",
        help=f"side of the square [m] (default {ANALYZE['side']:g})",
    )
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run_analyze)
    return p


ANALYZE_DESCRIPTION = (
    "UMBmark of a real robot from measured end poses (Borenstein and Feng) and, for a "
    "differential drive, Borenstein's correction."
)
ANALYZE_EPILOG = (
    "MEASUREMENTS.csv columns: direction (cw/ccw), x_abs, y_abs, x_calc, y_calc [m], optional "
    "theta_abs, theta_calc [rad] or theta_abs_deg, theta_calc_deg [deg].\n"
    "example:\n  omnikin umbmark analyze examples/umbmark_measurements.csv --robot tomasi-omni3"
)


def analyze_parser() -> argparse.ArgumentParser:
    """The parser of ``omnikin umbmark analyze``."""
    p = argparse.ArgumentParser(
        prog="omnikin umbmark analyze",
        description=ANALYZE_DESCRIPTION,
        epilog=ANALYZE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    return add_analyze_arguments(p)


def _add_analyze(umbmark_parser: CommandParser) -> None:
    """``omnikin umbmark analyze``: the options and behaviour of :func:`analyze_parser`, as a
    command of ``umbmark`` beside its optional ROBOT (:meth:`CommandParser.add_command`)."""
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


# --- helpers -----------------------------------------------------------------------------------------
def dpi(text: str) -> float:
    """An argparse ``type``: the resolution of ``--dpi`` [dots per inch], a plain number
    (:func:`~omnikin.cli.common.number`) in the range of :func:`omnikin.viz.dpi_problem`, so that
    a resolution no figure can be drawn at is a usage error before the study runs."""
    value = number(text)
    problem = dpi_problem(value)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return value


def _factor(x) -> str:
    return "unbounded" if x is None else f"{x:.3g}"


class _Status:
    """The current step on standard error (nothing for --json or when not a terminal)."""

    def __init__(self, quiet: bool):
        self.status = None
        if not quiet:
            con = console(120, stderr=True)
            if con.is_terminal:
                self.status = con.status("starting")

    def __enter__(self):
        if self.status:
            self.status.__enter__()
        return self

    def __exit__(self, *exc):
        if self.status:
            self.status.__exit__(*exc)

    def step(self, name: str) -> None:
        if self.status:
            self.status.update(name)


# --- umbmark -----------------------------------------------------------------------------------------
def run(args) -> int:
    """Run the study (:func:`omnikin.run_umbmark`), write the report folder, print a summary (or
    ``result.json``); status 0."""
    inputs = command_inputs(args)
    engine = engine_of(args)

    def within_budget(cost) -> None:  # every setting checked by now: refuse, or say it will take long
        require(
            args,
            "umbmark",
            memory=cost.bytes,
            seconds=cost.seconds,
            size=f"{cost.samples:.3g} robot-samples",
            hint=physics_hint(
                engine.options["step"],
                *[f"lower {option}" for option in ("--trials", "--runs") if getattr(args, option[2:]) > 1],
                "shorten --side",
            )
            if engine.measured_cost
            else "lower --trials, --runs or --rate",
        )

    with _Status(args.json) as status:
        report = run_umbmark(
            args.robot,
            true_robot=args.true_robot,
            errors=args.errors,
            mode=args.mode,
            runs=args.runs,
            side=args.side,
            noise=args.noise,
            rate=args.rate,
            seed=args.seed,
            trials=args.trials,
            calibrate=args.calibrate,
            engine=engine,
            max_memory=args.max_memory,
            max_time=args.max_time,
            progress=status.step,
            on_cost=within_budget,
        )
        status.step("report")
        doc = report.write(args.out, figure_format=args.figures, dpi=args.dpi, inputs=inputs)
    for problem in doc.get("physics_problems", []):  # runs that did not drive as commanded: one line each
        print(f"omnikin: warning: {problem}", file=sys.stderr)
    if args.json:
        print(dumps(doc), end="")
        return 0
    _print_summary(report, doc, args.out)
    return 0


def _umbmark_table(report: UMBmarkReport, doc: dict):
    from rich.table import Table

    level = f"{doc['settings']['confidence_level'] * 100:g} %"
    t = Table()
    floor = "noise floor" if report.engine.has_noise_model else "floor"
    for col in ("", "r_cg cw [mm]", "r_cg ccw [mm]", "E_max,syst [mm]", f"{level} interval [mm]", floor):
        t.add_column(col, justify="right" if col else "left")
    for key, label in (("before", "before"), ("after", "after calibration")):
        if key in doc:
            d = doc[key]
            iv = d["e_max_syst_interval"]
            t.add_row(
                label,
                mm_text(d["cw"]["r_cg"]),
                mm_text(d["ccw"]["r_cg"]),
                mm_text(d["e_max_syst"]),
                f"{mm_text(iv[0])} to {mm_text(iv[1])}" if iv else "n/a",
                "at floor" if d["at_noise_floor"] else "",
            )
    return t


def _print_summary(report: UMBmarkReport, doc: dict, out) -> None:
    s = doc["settings"]
    con = console(120)
    con.print(
        f"UMBmark: {report.robot.name} as built, {s['runs']} runs per direction, {s['side']:g} m square, "
        f"{s['mode']} mode, {doc['engine']} engine"
    )
    con.print(_umbmark_table(report, doc))
    floor = doc["noise_floor"]
    if not report.engine.has_noise_model:  # the floor is the nominal robot's
        level = f"{s['confidence_level'] * 100:g} %"
        con.print(f"floor (nominal robot in physics, roller contact alone): {physics_floor_text(floor, level)}")
    else:
        con.print(
            f"noise floor (perfectly calibrated robot, same random errors): median "
            f"{mm_text(floor['e_max_syst_median'])} mm, 95th percentile {mm_text(floor['e_max_syst_p95'])} mm"
        )
    bor = report.before[0].borenstein
    if bor is not None:
        con.print(f"Borenstein (before): {bor.describe()}")
    if "after" in doc:
        ri = doc["reduction_factor_interval"]
        sysm = doc["systematic"]
        con.print(
            "calibration: E_max,syst reduced "
            + reduction_text(doc["before"]["e_max_syst"], doc["after"]["e_max_syst"], floor_limit(doc))
            + "-fold"
            + (
                f" (95 % interval {_factor(ri[0])} to {_factor(ri[1])})"
                if ri and not reduction_bounded(doc["after"]["e_max_syst"], floor_limit(doc))
                else ""
            )
            + f"; systematic part alone (no random errors) {mm_text(sysm['e_max_syst_before'])} mm -> "
            f"{mm_text(sysm['e_max_syst_after'])} mm"
        )
        cal = doc["calibration"]
        if not cal["fits"]:
            con.print(
                f"warning: the calibration does not fit its runs (residual RMS {cal['residual_rms_after']:.3g} "
                "measurement sigmas); do not use the calibrated robot"
            )
        if "borenstein_iterations" in doc:
            con.print(
                "Borenstein's correction for comparison [mm per iteration]: "
                + ", ".join(mm_text(v) for v in doc["borenstein_iterations"])
            )
        blind = cal["identifiability"]["blind"]
        if blind:
            con.print(
                f"note: {len(blind)} parameter combination(s) not observable by the calibration runs (see report.md)"
            )
    if "monte_carlo" in doc:
        for label, st in doc["monte_carlo"].items():
            con.print(
                f"Monte Carlo {label}: {st['procedures']} procedures, E_max,syst median "
                f"{mm_text(st['e_max_syst_median'])} mm, 95th percentile {mm_text(st['e_max_syst_p95'])} mm"
            )
    con.print(f"report: {Path(out) / 'report.md'}")


# --- analyze -------------------------------------------------------------------------------------------
def run_analyze(args) -> int:
    """``omnikin umbmark analyze``: print the analysis of the measurements (or ``--json``);
    status 0."""
    res = analyze_umbmark(args.measurements, robot=args.robot, side=args.side)
    if args.json:
        print(dumps(res.as_dict()), end="")
        return 0
    con = console(120)
    con.print(
        f"UMBmark of {args.measurements} ({len(res.cw.epsilon)} cw, {len(res.ccw.epsilon)} ccw runs, "
        f"{args.side:g} m square)"
    )
    from rich.table import Table

    t = Table()
    for col in ("", "r_cg cw [mm]", "r_cg ccw [mm]", "E_max,syst [mm]", "95 % interval [mm]"):
        t.add_column(col, justify="right" if col else "left")
    iv = res.e_max_interval()
    t.add_row(
        "measured",
        mm_text(res.cw.r_cg),
        mm_text(res.ccw.r_cg),
        mm_text(res.e_max_syst),
        f"{mm_text(iv[0])} to {mm_text(iv[1])}" if iv else "n/a (3 runs per direction needed)",
    )
    con.print(t)
    for d in (res.cw, res.ccw):
        con.print(f"centre of gravity {d.direction}: x = {mm_text(d.cg[0])} mm, y = {mm_text(d.cg[1])} mm")
    if res.borenstein is not None:
        con.print(f"Borenstein: {res.borenstein.describe()}")
    elif args.robot is not None:
        con.print(
            f"{args.robot} is not a differential drive: Borenstein's correction does not apply (use omnikin calibrate)"
        )
    return 0


# --- calibrate -----------------------------------------------------------------------------------------
