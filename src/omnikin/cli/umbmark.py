"""``omnikin umbmark``, ``omnikin umbmark analyze`` and ``omnikin calibrate``.

The main job (``omnikin umbmark`` with no robot): the seed robot ``tomasi-omni3`` built
with a seeded ``typical`` as-built error profile runs UMBmark, is calibrated by least
squares from simulated calibration runs, and runs UMBmark again; a report folder gets
the figures, ``report.md`` and ``result.json``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from ..evaluation.calibration import borenstein_calibrate, calibrate, recommended_runs
from ..evaluation.umbmark import analyze, differential_pair, run_umbmark
from ..errors import InputError
from ..simulation.error_models import NOISE, PROFILES, noise as noise_profile
from ..plans import CalibrationRun, umbmark_square
from ..simulation.simulate import simulate
from .common import console, load_robot, robot_as_built

MAIN_ROBOT = "tomasi-omni3"
CALIBRATION_REPEATS = 5

UMBMARK_EPILOG = f"""examples:
  omnikin umbmark                          the main job: {MAIN_ROBOT} as built, UMBmark, calibration,
                                           UMBmark again, report in ./umbmark-report
  omnikin umbmark diff-drive --calibrate   any robot (preset or file); Borenstein's correction too
  omnikin umbmark mecanum4 --mode translate --trials 1000 --json
  omnikin umbmark my.yaml --true-robot as_built.yaml --noise none
  omnikin umbmark analyze measured.csv --robot diff-drive     for a real robot's runs

errors: --errors draws per-wheel systematic errors ({', '.join(sorted(PROFILES))}); --noise adds
run-to-run slip, floor and measurement errors ({', '.join(sorted(NOISE))}). The robot executes
each square by its own (nominal) model, so its odometry says it came home; the return error is
true end pose minus odometry end pose (Borenstein and Feng; seed paper eq. 1-6)."""


def add_parsers(sub, robot_help: str) -> None:
    sp = sub.add_parser("umbmark", help="UMBmark, calibration and report (the main job)",
                        description="Simulate the UMBmark odometry benchmark on a robot as built, optionally "
                                    "calibrate it and run UMBmark again; write a report folder. "
                                    "'omnikin umbmark analyze FILE' analyses a real robot's measurements.",
                        epilog=UMBMARK_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sp.add_argument("robot", nargs="?", metavar="ROBOT", help=f"{robot_help} (default {MAIN_ROBOT}, main job)")
    sp.add_argument("--true-robot", metavar="FILE", help="the robot as built (replaces --errors)")
    sp.add_argument("--errors", default="typical", metavar="PROFILE",
                    help=f"systematic error profile: {', '.join(sorted(PROFILES))} (default typical)")
    sp.add_argument("--mode", choices=("rotate", "translate"), default="rotate",
                    help="square driven by turning in place at corners (rotate, default) or by translating "
                         "with the heading held (translate, holonomic robots)")
    sp.add_argument("--runs", type=int, default=5, metavar="N", help="runs per direction (default 5)")
    sp.add_argument("--side", type=float, default=4.0, metavar="M", help="side of the square [m] (default 4)")
    sp.add_argument("--noise", default="typical", metavar="PROFILE",
                    help=f"random errors: {', '.join(sorted(NOISE))} (default typical)")
    sp.add_argument("--rate", type=float, default=100.0, metavar="HZ", help="encoder sample rate (default 100)")
    sp.add_argument("--seed", type=int, default=1, metavar="N", help="random seed (default 1)")
    sp.add_argument("--trials", type=int, default=1, metavar="N",
                    help="repeat the whole procedure N times (Monte Carlo; default 1)")
    sp.add_argument("--calibrate", action="store_true",
                    help="calibrate and run UMBmark again (always on for the main job)")
    sp.add_argument("--out", default="umbmark-report", metavar="DIR", help="report folder (default ./umbmark-report)")
    sp.add_argument("--json", action="store_true", help="print the result as JSON instead of tables")
    sp.set_defaults(func=cmd_umbmark)

    sp = sub.add_parser("calibrate", help="calibrate a robot file from measured runs",
                        description="Least-squares calibration of the wheel radii, hub positions and drive "
                                    "directions from runs with measured end poses (see docs/umbmark.md for the "
                                    "RUNS file: columns path, x_abs, y_abs[, theta_abs_deg]).",
                        epilog="examples:\n  omnikin calibrate tomasi-omni3 runs.csv -o calibrated.yaml\n"
                               "  (omnikin umbmark writes an example runs file: umbmark-report/calibration_runs.csv)",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    sp.add_argument("robot", metavar="ROBOT", help=robot_help)
    sp.add_argument("runs", metavar="RUNS", help="CSV of runs: path, x_abs, y_abs[, theta_abs_deg]")
    sp.add_argument("-o", "--output", metavar="FILE", help="write the calibrated robot file (YAML or JSON)")
    sp.add_argument("--json", action="store_true", help="print the result as JSON")
    sp.set_defaults(func=cmd_calibrate)


def analyze_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="omnikin umbmark analyze",
        description="UMBmark of a real robot from measured end poses (seed paper eq. 1-6) and, for a "
                    "differential drive, Borenstein's correction.",
        epilog="MEASUREMENTS.csv columns: direction (cw/ccw), x_abs, y_abs, x_calc, y_calc [m], optional "
               "theta_abs, theta_calc [rad] or theta_abs_deg, theta_calc_deg [deg].\n"
               "example:\n  omnikin umbmark analyze runs.csv --robot diff-drive --side 4",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("measurements", metavar="MEASUREMENTS.csv")
    p.add_argument("--robot", metavar="ROBOT", help="the robot (a differential drive gets Borenstein's correction)")
    p.add_argument("--side", type=float, default=4.0, metavar="L", help="side of the square [m] (default 4)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=cmd_umbmark_analyze)
    return p


# --- helpers -----------------------------------------------------------------------------------------
def _mm(x: float) -> str:
    return f"{x * 1000:.2f}" if math.isfinite(x) else "-"


def _umbmark_table(results: dict):
    from rich.table import Table

    t = Table()
    for col in ("", "r_cg cw [mm]", "r_cg ccw [mm]", "E_max,syst [mm]"):
        t.add_column(col, justify="right" if col else "left")
    for label, res in results.items():
        t.add_row(label, _mm(res.cw.r_cg), _mm(res.ccw.r_cg), _mm(res.e_max_syst))
    return t


class _Steps:
    """A rich progress bar over named steps (silent for --json)."""

    def __init__(self, total: int, quiet: bool):
        self.quiet = quiet
        self.progress = None
        if not quiet:
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

            self.progress = Progress(TextColumn("{task.description:<38}"), BarColumn(), TextColumn("{task.completed}/"
                                     "{task.total}"), TimeElapsedColumn(), console=console(120, stderr=True),
                                     transient=True)
            self.task = self.progress.add_task("starting", total=total)

    def __enter__(self):
        if self.progress:
            self.progress.__enter__()
        return self

    def __exit__(self, *exc):
        if self.progress:
            self.progress.__exit__(*exc)

    def step(self, description: str):
        if self.progress:
            self.progress.update(self.task, description=description)

    def done(self):
        if self.progress:
            self.progress.advance(self.task)


# --- umbmark -----------------------------------------------------------------------------------------
def cmd_umbmark(args) -> int:

    main_job = args.robot is None
    robot = load_robot(args.robot or MAIN_ROBOT)
    do_calibrate = args.calibrate or main_job
    if args.runs < 1:
        raise InputError(f"--runs must be at least 1, got {args.runs}")
    if args.trials < 1:
        raise InputError(f"--trials must be at least 1, got {args.trials}")
    if not (math.isfinite(args.side) and args.side > 0):
        raise InputError(f"--side must be a positive length [m], got {args.side}")
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise InputError(f"--rate must be a positive number of samples per second, got {args.rate}")
    if args.seed < 0:
        raise InputError(f"--seed must be a whole number >= 0, got {args.seed}")
    if args.mode == "translate" and not robot.mobility.holonomic:
        raise InputError(f"robot {robot.name!r} is not holonomic (Campion type {robot.mobility.campion_type}): "
                           f"it cannot drive the 'translate' square; use --mode rotate")
    noise = noise_profile(args.noise)
    seeds = np.random.SeedSequence(args.seed).spawn(4)
    true, errors = robot_as_built(robot, args.true_robot, args.errors, seeds[0])
    rng = np.random.default_rng(seeds[1])
    opts = dict(side=args.side, mode=args.mode, runs=args.runs, noise=noise, rate=args.rate)
    steps = 3 + (5 if do_calibrate else 0)
    out = Path(args.out)
    with _Steps(steps, args.json) as bar:
        bar.step("UMBmark before calibration")
        before = run_umbmark(true, robot, trials=args.trials, rng=rng, **opts)
        bar.done()
        bar.step("trajectories for the figures")
        traj = {"before": _trajectories(true, robot, args, noise, seeds[2])}
        bar.done()
        cal = bor = None
        after = None
        if do_calibrate:
            bar.step("calibration runs")
            cal_runs, cal_rows = _calibration_runs(true, robot, noise, rng, args)
            bar.done()
            bar.step("least-squares calibration")
            cal = calibrate(robot, cal_runs)
            bar.done()
            if differential_pair(robot) is not None and args.mode == "rotate":
                bar.step("Borenstein's correction (comparison)")
                bor = _borenstein(true, robot, before[0], rng, opts)
            bar.done()
            bar.step("UMBmark after calibration")
            after = run_umbmark(true, cal.robot, trials=args.trials, rng=rng, **opts)
            bar.done()
            traj["after"] = _trajectories(true, cal.robot, args, noise, seeds[2])
            bar.done()
        bar.step("report")
        result = _result(args, robot, true, errors, before, after, cal, bor, main_job)
        result["systematic"] = _systematic(true, robot, cal, args)
        _write_report(out, args, robot, true, result, before, after, traj, cal, cal_rows if do_calibrate else None)
        bar.done()
    if args.json:
        print(json.dumps(result["umbmark"], indent=2))
        return 0
    _print_summary(args, robot, result, before, after, cal, bor, out)
    return 0


def _systematic(true, robot, cal, args) -> dict:
    """E_max,syst without random errors: the systematic part alone (one run per direction suffices)."""
    quiet = noise_profile("none")
    opts = dict(side=args.side, mode=args.mode, runs=1, noise=quiet, rate=args.rate)
    out = {"before": run_umbmark(true, robot, **opts)[0].e_max_syst}
    if cal is not None:
        out["after"] = run_umbmark(true, cal.robot, **opts)[0].e_max_syst
        out["improvement"] = out["before"] / out["after"] if out["after"] > 0 else math.inf
    return out


def _trajectories(true, command, args, noise, seed) -> dict:
    rng = np.random.default_rng(seed)
    return {d: simulate(umbmark_square(d, args.side, args.mode), true, command, rate=args.rate, noise=noise,
                        trials=1, rng=rng) for d in ("cw", "ccw")}


def _calibration_runs(true, robot, noise, rng, args):
    runs, rows = [], []
    for label, plan in recommended_runs(robot, args.side):
        sim = simulate(plan, true, robot, rate=args.rate, noise=noise, trials=CALIBRATION_REPEATS, rng=rng,
                       keep_truth=False)
        text = _path_text(label, args.side)
        for m in sim.measured:
            runs.append(CalibrationRun(plan, tuple(m), label, (max(noise.measurement, 1e-4),
                                                                max(noise.measurement_theta, math.radians(0.05)))))
            rows.append((text, m))
    return runs, rows


def _path_text(label: str, side: float) -> str:
    """The runs-file spelling of a recommended run's label (see omnikin.io.runs)."""
    words = label.split()
    if words[0] == "square":
        return f"square {words[1]} {words[2]} {side:g}"
    if words[0] == "line":
        return f"line {words[1]} {0 if words[-1] == 'x' else 90}"
    return f"spin {words[1]}"


def _borenstein(true, robot, first, rng, opts) -> dict:
    """Borenstein's iterated correction, for comparison with least squares."""
    out, model, res = [], robot, first
    for _ in range(3):
        model = borenstein_calibrate(model, res)
        res = run_umbmark(true, model, rng=rng, **opts)[0]
        out.append(res.e_max_syst)
    return {"e_max_syst_per_iteration": out, "robot": model}


def _stats(results) -> dict:
    v = np.array([r.e_max_syst for r in results])
    return {"procedures": len(v), "e_max_syst_mean": float(v.mean()), "e_max_syst_median": float(np.median(v)),
            "e_max_syst_p95": float(np.percentile(v, 95)), "e_max_syst_max": float(v.max())}


def _result(args, robot, true, errors, before, after, cal, bor, main_job) -> dict:
    from ..io.robot_file import robot_to_dict

    umb = before[0].as_dict()
    settings = {"robot": robot.name, "true_robot": args.true_robot, "errors": None if args.true_robot else args.errors,
                "noise": args.noise, "mode": args.mode, "runs": args.runs, "side": args.side, "rate": args.rate,
                "seed": args.seed, "trials": args.trials}
    result = {"settings": settings, "before": before[0].as_dict(), "robot": robot_to_dict(robot),
              "true_robot": robot_to_dict(true)}
    if errors is not None:
        result["injected_errors"] = errors.as_dict()
    if args.trials > 1:
        result["monte_carlo"] = {"before": _stats(before)}
    if cal is not None:
        result["after"] = after[0].as_dict()
        result["calibrated_robot"] = robot_to_dict(cal.robot)
        improvement = before[0].e_max_syst / after[0].e_max_syst if after[0].e_max_syst > 0 else math.inf
        calibration = {**cal.as_dict(), "after": after[0].as_dict(), "improvement": improvement,
                       "calibrated_robot": result["calibrated_robot"]}
        if bor is not None:
            calibration["borenstein_iterations"] = bor["e_max_syst_per_iteration"]
        result["calibration"] = calibration
        if args.trials > 1:
            result["monte_carlo"]["after"] = _stats(after)
        umb["calibration"] = calibration
    result["umbmark"] = umb
    return result


def _write_report(out: Path, args, robot, true, result, before, after, traj, cal, cal_rows) -> None:
    from ..io.robot_file import save_robot
    from ..io.runs import write_calibration_runs, write_umbmark_measurements

    try:
        out.mkdir(parents=True, exist_ok=True)
        figures = _figures(out, args, robot, before, after, traj)
        save_robot(true, out / "true_robot.yaml")
        write_umbmark_measurements(out / "measurements_before.csv", before[0])
        if cal is not None:
            save_robot(cal.robot, out / "calibrated_robot.yaml")
            write_calibration_runs(out / "calibration_runs.csv", cal_rows)
        result["figures"] = figures
        doc = {k: v for k, v in result.items() if k != "umbmark"}
        (out / "result.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        (out / "report.md").write_text(_report_md(args, robot, result, before, after, cal, figures),
                                       encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{out}: cannot write the report: {exc}") from None


def _figures(out: Path, args, robot, before, after, traj) -> list:
    try:
        from ..viz import umbmark as fig
        from ..viz import require_matplotlib

        require_matplotlib()
    except ImportError:
        return []
    results = {"before": before[0]} if after is None else {"before": before[0], "after calibration": after[0]}
    title = f"UMBmark, {robot.name} as built, {args.mode} mode, {args.side:g} m square"
    made = []
    for name, f in (("return_errors.png", fig.return_errors_figure(results, title)),
                    ("euclidean_errors.png", fig.euclidean_errors_figure(results, title)),
                    ("trajectories.png", fig.trajectories_figure(traj, args.side, title))):
        f.savefig(out / name)
        made.append(name)
    if args.trials > 1:
        values = {"before": [r.e_max_syst for r in before]}
        if after is not None:
            values["after calibration"] = [r.e_max_syst for r in after]
        fig.monte_carlo_figure(values, f"E_max,syst over {args.trials} procedures").savefig(out / "monte_carlo.png")
        made.append("monte_carlo.png")
    return made


def _report_md(args, robot, result, before, after, cal, figures) -> str:
    b = before[0]
    lines = [f"# UMBmark report: {robot.name}", "",
             f"Robot as built: {'file ' + args.true_robot if args.true_robot else 'nominal model with the '}"
             f"{'' if args.true_robot else repr(args.errors) + ' systematic error profile (seed ' + str(args.seed) + ')'}; "
             f"noise profile {args.noise!r}; {args.runs} runs per direction on a {args.side:g} m square, "
             f"{args.mode} mode, encoders at {args.rate:g} Hz.", "",
             "The robot executes every square by its own model, so its odometry says it returned home; the "
             "return error is the true end pose minus the odometry end pose (Borenstein and Feng; seed paper "
             "eq. 1-6).", "",
             "| | r_cg cw [mm] | r_cg ccw [mm] | E_max,syst [mm] |", "|---|---:|---:|---:|",
             f"| before | {_mm(b.cw.r_cg)} | {_mm(b.ccw.r_cg)} | {_mm(b.e_max_syst)} |"]
    if after is not None:
        a = after[0]
        lines.append(f"| after calibration | {_mm(a.cw.r_cg)} | {_mm(a.ccw.r_cg)} | {_mm(a.e_max_syst)} |")
    sysm = result["systematic"]
    lines += ["", f"Without random errors (the systematic part alone): E_max,syst {_mm(sysm['before'])} mm before"
              + (f", {_mm(sysm['after'])} mm after calibration ({sysm['improvement']:.1f}-fold)." if "after" in sysm
                 else ".") + f" With random errors the centres of gravity of {args.runs} runs scatter by about the run-to-run "
              f"scatter over sqrt({args.runs}), which bounds what one procedure can show."]
    if after is not None:
        lines += ["", f"Calibration reduced E_max,syst {result['calibration']['improvement']:.1f}-fold "
                      f"(least squares over {len(cal.identifiability.parameters)} wheel parameters, "
                      f"{cal.details['runs']} calibration runs; residual RMS {cal.residual_before:.3g} -> "
                      f"{cal.residual_after:.3g} measurement sigmas)."]
        if cal.identifiability.blind:
            lines += ["", "The calibration runs cannot see these parameter combinations (left at zero):"]
            for combo in cal.identifiability.blind:
                lines.append("- " + " + ".join(f"{c['weight']:+.2f} {c['parameter']}" for c in combo))
        if "borenstein_iterations" in result["calibration"]:
            its = result["calibration"]["borenstein_iterations"]
            lines += ["", "Borenstein's E_d/E_b correction, for comparison, E_max,syst after each iteration [mm]: "
                      + ", ".join(_mm(v) for v in its)]
    if b.borenstein is not None:
        bd = b.borenstein
        lines += ["", "Borenstein's differential-drive figures (before): "
                  f"alpha = {bd.alpha:.5g} rad, beta = {bd.beta:.5g} rad, R = {bd.R:.4g} m, E_d = {bd.E_d:.6f}, "
                  f"E_b = {bd.E_b:.6f}, c_L = {bd.c_L:.6f}, c_R = {bd.c_R:.6f}, b_new = {bd.b_new:.6f} m."]
    if "monte_carlo" in result:
        lines += ["", "## Monte Carlo", "", "| | procedures | median [mm] | mean [mm] | 95th percentile [mm] |",
                  "|---|---:|---:|---:|---:|"]
        for label, s in result["monte_carlo"].items():
            lines.append(f"| {label} | {s['procedures']} | {_mm(s['e_max_syst_median'])} | "
                         f"{_mm(s['e_max_syst_mean'])} | {_mm(s['e_max_syst_p95'])} |")
    if "injected_errors" in result and cal is not None:
        lines += ["", "## Injected vs estimated errors", "",
                  "| wheel | radius injected [%] | radius estimated [%] |", "|---|---:|---:|"]
        for name, e in result["injected_errors"].items():
            est = cal.errors.wheels.get(name)
            if est is not None:
                lines.append(f"| {name} | {e['radius'] * 100:+.3f} | {est.radius * 100:+.3f} |")
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    lines += ["", "Files: `result.json` (everything above), `true_robot.yaml`, `measurements_before.csv` "
              "(the format of `omnikin umbmark analyze`)" +
              (", `calibrated_robot.yaml`, `calibration_runs.csv` (the format of `omnikin calibrate`)."
               if cal is not None else "."), ""]
    return "\n".join(lines)


def _print_summary(args, robot, result, before, after, cal, bor, out) -> None:
    con = console(120)
    results = {"before": before[0]} if after is None else {"before": before[0], "after calibration": after[0]}
    con.print(f"UMBmark: {robot.name} as built, {args.runs} runs per direction, {args.side:g} m square, "
              f"{args.mode} mode")
    con.print(_umbmark_table(results))
    b = before[0]
    if b.borenstein is not None:
        bd = b.borenstein
        con.print(f"Borenstein (before): alpha {bd.alpha:.4g} rad, beta {bd.beta:.4g} rad, E_d {bd.E_d:.5f}, "
                  f"E_b {bd.E_b:.5f}, c_L {bd.c_L:.5f}, c_R {bd.c_R:.5f}, b_new {bd.b_new:.5f} m")
    if cal is not None:
        sysm = result["systematic"]
        con.print(f"calibration: E_max,syst reduced {result['calibration']['improvement']:.1f}-fold "
                  f"({_mm(before[0].e_max_syst)} mm -> {_mm(after[0].e_max_syst)} mm); systematic part alone "
                  f"(no random errors) {sysm['improvement']:.1f}-fold ({_mm(sysm['before'])} mm -> "
                  f"{_mm(sysm['after'])} mm)")
        if bor is not None:
            con.print("Borenstein's correction for comparison [mm per iteration]: "
                      + ", ".join(_mm(v) for v in bor["e_max_syst_per_iteration"]))
        if cal.identifiability.blind:
            con.print(f"note: {len(cal.identifiability.blind)} parameter combination(s) not observable by the "
                      f"calibration runs (see report.md)")
    if "monte_carlo" in result:
        for label, s in result["monte_carlo"].items():
            con.print(f"Monte Carlo {label}: {s['procedures']} procedures, E_max,syst median "
                      f"{_mm(s['e_max_syst_median'])} mm, 95th percentile {_mm(s['e_max_syst_p95'])} mm")
    con.print(f"report: {out / 'report.md'}")


# --- analyze / calibrate ---------------------------------------------------------------------------------
def cmd_umbmark_analyze(args) -> int:
    from ..io.runs import read_umbmark_measurements

    robot = load_robot(args.robot) if args.robot else None
    eps = read_umbmark_measurements(args.measurements)
    res = analyze(eps["cw"], eps["ccw"], args.side, robot)
    if args.json:
        print(json.dumps(res.as_dict(), indent=2))
        return 0
    con = console(120)
    con.print(f"UMBmark of {args.measurements} ({len(res.cw.epsilon)} cw, {len(res.ccw.epsilon)} ccw runs, "
              f"{args.side:g} m square)")
    con.print(_umbmark_table({"measured": res}))
    for d in (res.cw, res.ccw):
        con.print(f"centre of gravity {d.direction}: x = {_mm(d.cg[0])} mm, y = {_mm(d.cg[1])} mm")
    if res.borenstein is not None:
        bd = res.borenstein
        con.print(f"Borenstein: alpha {bd.alpha:.5g} rad, beta {bd.beta:.5g} rad, R {bd.R:.5g} m, E_d {bd.E_d:.6f}, "
                  f"E_b {bd.E_b:.6f}, c_L {bd.c_L:.6f}, c_R {bd.c_R:.6f}, b_new {bd.b_new:.6f} m")
    elif robot is not None:
        con.print(f"{robot.name} is not a differential drive: Borenstein's correction does not apply "
                  f"(use omnikin calibrate)")
    return 0


def cmd_calibrate(args) -> int:
    from ..io.robot_file import save_robot
    from ..io.runs import read_calibration_runs

    robot = load_robot(args.robot)
    runs = read_calibration_runs(args.runs)
    cal = calibrate(robot, runs)
    if args.output:
        try:
            save_robot(cal.robot, args.output)
        except OSError as exc:
            raise InputError(f"{args.output}: cannot write: {exc.strerror}") from None
    if args.json:
        print(json.dumps({**cal.as_dict(), "output": args.output}, indent=2))
        return 0
    from rich.table import Table

    con = console(120)
    t = Table(title=f"calibration of {robot.name} from {len(runs)} runs", title_justify="left")
    for col in ("parameter", "estimate", "sigma"):
        t.add_column(col, justify="right" if col != "parameter" else "left")
    sig = cal.identifiability.sigma
    for name in cal.identifiability.parameters:
        wheel, par = name.rsplit(".", 1)
        e = cal.errors.wheels[wheel]
        value = {"radius": e.radius, "drive": e.drive}.get(par)
        if par in ("axle", "lever"):       # the displacement's component along the parameter's direction
            w = robot.wheel(wheel)
            a = w.drive + (w.roller if par == "lever" else 0.0)
            value = -math.sin(a) * e.dx + math.cos(a) * e.dy
        elif par in ("dx", "dy"):
            value = getattr(e, par)
        unit = {"radius": "", "drive": " rad"}.get(par, " m")
        t.add_row(name, f"{value:.6g}{unit}", f"{sig[name]:.3g}{unit}")
    con.print(t)
    con.print(f"residual RMS {cal.residual_before:.3g} -> {cal.residual_after:.3g} measurement sigmas")
    for combo in cal.identifiability.blind:
        con.print("not observable by these runs: " + " + ".join(f"{c['weight']:+.2f} {c['parameter']}" for c in combo))
    if args.output:
        con.print(f"calibrated robot written to {args.output}")
    return 0
