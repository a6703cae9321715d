"""Accuracy: exact vs Euler vs midpoint integration on a 1 m radius circle at 10 Hz and 100 Hz.

tomasi-omni3 drives the constant twist (0.5 m/s, 0, 0.5 rad/s) for one full turn; wheel
angles are the exact ones (no quantisation), so the only error is the integration's.
The end pose should be the start pose; the error reported is the largest position error
along the way against the closed-form circle, and the end position error.
"""

from __future__ import annotations

import math

import numpy as np

from _common import save
from omnikin import batch_odometry_from_angles, load_robot


def circle(t, v=0.5, w=0.5):
    th = w * t
    return np.column_stack([v / w * np.sin(th), v / w * (1 - np.cos(th))])


def main() -> dict:
    robot = load_robot("tomasi-omni3")
    twist = np.array([0.5, 0.0, 0.5])
    out = {}
    print("integration error on a 1 m radius circle, one full turn (no encoder quantisation)")
    print(f"  {'rate':>6s} {'method':>9s} {'max error [m]':>14s} {'end error [m]':>14s}")
    for rate in (10.0, 100.0):
        n = int(round(2 * math.pi / 0.5 * rate))
        t = np.arange(n + 1) / rate
        angles = np.outer(t, robot.ik_matrix @ twist)
        truth = circle(t)
        for method in ("exact", "midpoint", "euler"):
            poses = batch_odometry_from_angles(robot, t, angles, method=method).poses
            err = np.hypot(*(poses[:, :2] - truth).T)
            out[f"{rate:g} Hz {method}"] = {"max_error_m": float(err.max()), "end_error_m": float(err[-1])}
            print(f"  {rate:5g}Hz {method:>9s} {err.max():14.3e} {err[-1]:14.3e}")
    return out


if __name__ == "__main__":
    save("accuracy", main())
