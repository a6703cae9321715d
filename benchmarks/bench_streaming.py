"""Streaming odometry update for the 3-wheel robot: target <= 2 us per update.

References measured in the same run:
* ``plain loop``: a straightforward pure-Python estimator (loops over wheels and matrix
  entries, math.sin/cos, exact integration), what one writes without tuning;
* ``numpy per update``: the same with small NumPy arrays per sample.
"""

from __future__ import annotations

import math

import numpy as np
from _common import best_time, save, tomasi_log

from omnikin import Odometry


class PlainLoop:
    """Reference: straightforward pure-Python exact odometry."""

    def __init__(self, fk, scale):
        self.fk = [list(row) for row in fk]
        self.scale = list(scale)
        self.prev = None
        self.x = self.y = self.th = 0.0

    def update(self, t, ticks):
        if self.prev is None:
            self.prev = list(ticks)
            return
        d = [(ticks[j] - self.prev[j]) * self.scale[j] for j in range(len(ticks))]
        inc = [sum(self.fk[i][j] * d[j] for j in range(len(d))) for i in range(3)]
        a, b, phi = inc
        if abs(phi) > 1e-9:
            sx, cx = math.sin(phi) / phi, (1 - math.cos(phi)) / phi
        else:
            sx, cx = 1.0, 0.0
        dx, dy = sx * a - cx * b, cx * a + sx * b
        c, s = math.cos(self.th), math.sin(self.th)
        self.x += c * dx - s * dy
        self.y += s * dx + c * dy
        self.th = math.atan2(math.sin(self.th + phi), math.cos(self.th + phi))
        self.prev = list(ticks)


class NumpyPerUpdate:
    """Reference: the same with NumPy arrays per sample."""

    def __init__(self, fk, scale):
        self.fk = np.asarray(fk) * np.asarray(scale)
        self.prev = None
        self.pose = np.zeros(3)

    def update(self, t, ticks):
        ticks = np.asarray(ticks)
        if self.prev is None:
            self.prev = ticks
            return
        a, b, phi = self.fk @ (ticks - self.prev)
        k = np.sinc(phi / (2 * np.pi))
        h = self.pose[2] + phi / 2
        self.pose += np.array([k * (np.cos(h) * a - np.sin(h) * b), k * (np.sin(h) * a + np.cos(h) * b), phi])
        self.prev = ticks


def main(n: int = 20000) -> dict:
    robot, t, ticks = tomasi_log(n)
    ts = [float(v) for v in t]
    tl = [[int(v) for v in row] for row in ticks]
    fk = robot.fk_matrix()
    scale = [w.encoder.rad_per_tick for w in robot.wheels]

    def run(est):
        def go():
            if hasattr(est, "reset"):
                est.reset()
            else:
                est.prev = None
            upd = est.update
            for k in range(n):
                upd(ts[k], tl[k])
        return go

    results = {}
    for name, est in (("omnikin", Odometry(robot)), ("omnikin, 16-bit counters", Odometry(robot, counter_bits=16)),
                      ("plain loop", PlainLoop(fk, scale)), ("numpy per update", NumpyPerUpdate(fk, scale))):
        results[name] = best_time(run(est), repeat=5) / n * 1e6
    ref = results["plain loop"]
    print(f"streaming odometry update, tomasi-omni3, {n} samples (best of 5)")
    for name, us in results.items():
        print(f"  {name:26s} {us:7.3f} us/update   {ref / us:5.2f}x the plain loop")
    print(f"  target <= 2 us per update: {'met' if results['omnikin'] <= 2.0 else 'NOT met'}")
    return {"us_per_update": results, "target_us": 2.0}


if __name__ == "__main__":
    save("streaming", main())
