"""Time-optimal planning: omnikin's timing of a 1000-point path against toppra's (the
independent reference solver, the same problem on the same grid, measured in the same run):
target within 2x its time, with the same duration.

The path is a figure-eight of tomasi-omni3 with its heading along the tangent, 1000 samples;
both get the same wheel rows (omnikin computes them; toppra is timed on the solve alone, so the
ratio is conservative for omnikin, whose time includes computing the rows)."""

from __future__ import annotations

import numpy as np

from _common import best_time
from omnikin import load_robot
from omnikin.control import WheelLimits, time_optimal
from omnikin.control.path import figure8, from_samples
from omnikin.control.time_optimal import path_rates
from support.toppra_reference import duration, toppra_sdot

LIMITS = WheelLimits(speed=12.0, accel=40.0)


def thousand_point_figure8():
    dense = figure8(1.0, heading="tangent")
    pick = np.linspace(0, len(dense.s) - 1, 1000).round().astype(int)
    return from_samples(dense.pose[pick, :2], dense.pose[pick, 2], name="figure8 1 (1000 points)")


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
    return out


if __name__ == "__main__":
    main()
