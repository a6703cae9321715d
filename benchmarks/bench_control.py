"""Trajectories and tracking, each against a reference measured in the same run.

1. Time-optimal planning: omnikin's timing of a 1000-point path against toppra's (the
   independent reference solver, the same problem on the same grid): target within 2x its time,
   with the same duration. The path is a figure-eight of tomasi-omni3 with its heading along the
   tangent, 1000 samples; both get the same wheel rows (omnikin computes them; toppra is timed on
   the solve alone, so the ratio is conservative for omnikin, whose time includes the rows).
2. One MPC step of tomasi-omni3 (horizon 20, the figure-eight at the wheels' limits, 50 Hz):
   target p95 below 20 % of the 20 ms period on one core; the reference formulation (the same
   programme with the errors as variables, built from scratch and solved by Clarabel each tick,
   ``tests/support/mpc_reference.py``) timed at the same states.
3. The feedback controller's step against the runtime's control cycle (the command offered and
   the runtime stepped, ``bench_runtime.py``'s cycle): target within 3x.

Steps 2 and 3 are timed one call at a time along a whole tracked run (the percentiles of those
calls); the machine's load shows in them, so run it on an idle machine."""

from __future__ import annotations

import time

import numpy as np

from _common import best_time, save
from bench_runtime import cycle_seconds
from omnikin import load_robot
from omnikin.control import PoseFeedback, WheelLimits, plan_trajectory, time_optimal
from omnikin.control.mpc import PoseMPC
from omnikin.control.path import figure8, from_samples
from omnikin.control.time_optimal import path_rates
from omnikin.evaluation.tracking import track
from support.mpc_reference import reference_correction
from support.toppra_reference import duration, toppra_sdot

LIMITS = WheelLimits(speed=12.0, accel=40.0)


def thousand_point_figure8():
    dense = figure8(1.0, heading="tangent")
    pick = np.linspace(0, len(dense.s) - 1, 1000).round().astype(int)
    return from_samples(dense.pose[pick, :2], dense.pose[pick, 2], name="figure8 1 (1000 points)")


RATE = 50.0


def controller_steps() -> dict:
    """Per-call wall times [ms] of the MPC, its reference formulation and the feedback controller
    along the tracked figure-eight, and the runtime's control cycle [ms]."""
    robot = load_robot("tomasi-omni3")
    trajectory = plan_trajectory(robot, figure8(1.0), LIMITS)
    mpc = PoseMPC(robot, trajectory, rate=RATE)
    run = track(robot, trajectory, mpc, rate=RATE)
    reference = []
    last = np.zeros(3)
    for k in range(0, len(run.t), 5):  # the reference at every fifth state of the run
        start = time.perf_counter()
        reference_correction(mpc, float(run.t[k]), run.odometry[k], last)
        reference.append(time.perf_counter() - start)
        last = run.command[k]
    feedback = PoseFeedback(robot, trajectory, rate=RATE)
    fed = track(robot, trajectory, feedback, rate=RATE)
    return {
        "mpc_ms": run.solve_time * 1e3,
        "reference_ms": np.array(reference) * 1e3,
        "feedback_ms": fed.solve_time * 1e3,
        "cycle_ms": cycle_seconds("tomasi-omni3") * 1e3,
    }


def main() -> dict:
    robot = load_robot("tomasi-omni3")
    path = thousand_point_figure8()
    rates = path_rates(robot, path)
    ours = time_optimal(robot, path, LIMITS)
    sd = toppra_sdot(path.s, rates.w, rates.dw, LIMITS.speed, LIMITS.accel)
    t_ours = best_time(lambda: time_optimal(robot, path, LIMITS), repeat=7)
    t_ref = best_time(lambda: toppra_sdot(path.s, rates.w, rates.dw, LIMITS.speed, LIMITS.accel), repeat=7)
    out = {
        "samples": len(path.s),
        "duration_s": ours.duration,
        "toppra_duration_s": duration(path.s, sd),
        "omnikin_ms": t_ours * 1e3,
        "toppra_ms": t_ref * 1e3,
        "ratio": t_ours / t_ref,
    }
    print(
        f"time-optimal timing of a {out['samples']}-point figure-eight (tomasi-omni3, 12 rad/s, 40 rad/s^2):\n"
        f"  omnikin {out['omnikin_ms']:.1f} ms, toppra {out['toppra_ms']:.1f} ms (reference, same run): "
        f"{out['ratio']:.2f}x (target <= 2x)\n"
        f"  duration {out['duration_s']:.4f} s, toppra {out['toppra_duration_s']:.4f} s"
    )
    steps = controller_steps()
    period_ms = 1e3 / RATE
    p95 = {key: float(np.percentile(steps[key], 95)) for key in ("mpc_ms", "reference_ms", "feedback_ms")}
    out["mpc"] = {
        "p50_ms": float(np.percentile(steps["mpc_ms"], 50)),
        "p95_ms": p95["mpc_ms"],
        "max_ms": float(np.max(steps["mpc_ms"])),
        "share_of_period_p95": p95["mpc_ms"] / period_ms,
        "reference_p95_ms": p95["reference_ms"],
        "ratio_to_reference_p95": p95["mpc_ms"] / p95["reference_ms"],
    }
    out["feedback"] = {
        "p50_ms": float(np.percentile(steps["feedback_ms"], 50)),
        "p95_ms": p95["feedback_ms"],
        "cycle_ms": steps["cycle_ms"],
        "ratio_to_cycle_p50": float(np.percentile(steps["feedback_ms"], 50)) / steps["cycle_ms"],
    }
    print(
        f"MPC step (tomasi-omni3, horizon 20, figure-eight at the limits, {RATE:g} Hz): p50 "
        f"{out['mpc']['p50_ms']:.2f} ms, p95 {p95['mpc_ms']:.2f} ms = {100 * out['mpc']['share_of_period_p95']:.1f} % "
        f"of the period (target < 20 %); reference formulation (Clarabel) p95 {p95['reference_ms']:.2f} ms: "
        f"{out['mpc']['ratio_to_reference_p95']:.2f}x\n"
        f"feedback step p50 {out['feedback']['p50_ms'] * 1e3:.0f} us, the runtime's control cycle "
        f"{steps['cycle_ms'] * 1e3:.0f} us: {out['feedback']['ratio_to_cycle_p50']:.2f}x (target <= 3x)"
    )
    return out


if __name__ == "__main__":
    save("control", main())
