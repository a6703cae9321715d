"""Streaming odometry update for the 3-wheel robot, measured side by side with references.

Targets (docs/performance.md): the fastest path (Python int readings in a list) within 1.2x
of ``reference step`` while keeping every check; every input type a user is likely to pass
within 1.3x of the fastest path.

References measured in the same run, interleaved with omnikin round by round:
* ``reference step``: plain Python written for speed: the FK coefficients (per tick) and
  wheel count unrolled, the exact SE(2) step, no checks at all;
* ``reference step, same checks``: the same, written by hand with the checks omnikin's fast
  path makes (Python ints only, time order, every wheel's jump limit and change-of-speed
  limit): what these checks cost in CPython at best, without a pure state;
* ``plain loop``: a straightforward pure-Python estimator (loops over wheels and matrix
  entries), what one writes without tuning;
* ``numpy per update``: the same with small NumPy arrays per sample.
"""

from __future__ import annotations

import math
import random
from math import cos, floor, pi, sin

import numpy as np

from _common import best_time, save, tomasi_log
from omnikin import Odometry


class ReferenceStep:
    """Reference: unrolled exact step for 3 wheels, Python ints in, no checks."""

    def __init__(self, fk_ticks):
        (self.f00, self.f01, self.f02), (self.f10, self.f11, self.f12), (self.f20, self.f21, self.f22) = fk_ticks
        self.reset()

    def reset(self):
        self.prev = None
        self.x = self.y = self.th = 0.0

    def update(self, t, ticks):
        t0, t1, t2 = ticks
        if self.prev is None:
            self.prev = (t0, t1, t2)
            return (self.x, self.y, self.th)
        p0, p1, p2 = self.prev
        d0, d1, d2 = t0 - p0, t1 - p1, t2 - p2
        a = self.f00 * d0 + self.f01 * d1 + self.f02 * d2
        b = self.f10 * d0 + self.f11 * d1 + self.f12 * d2
        phi = self.f20 * d0 + self.f21 * d1 + self.f22 * d2
        h = 0.5 * phi
        k = 1.0 - h * h / 6.0 if -0.1 < h < 0.1 else sin(h) / h
        h += self.th
        c, s = cos(h), sin(h)
        self.x += k * (c * a - s * b)
        self.y += k * (s * a + c * b)
        th = self.th + phi
        if th >= pi or th < -pi:
            th -= 2 * pi * floor((th + pi) / (2 * pi))
        self.th = th
        self.prev = (t0, t1, t2)
        return (self.x, self.y, th)


class ReferenceCheckedStep(ReferenceStep):
    """Reference: the unrolled exact step with omnikin's checks written by hand (Python ints,
    time strictly later and finite, |d| <= rate dt + slack, |d - d_prev| <= accel dt dt_prev +
    2 slack), raising on anything else: one call per sample, state on the instance."""

    def __init__(self, fk_ticks, rate: float, slack: float, accel: float):
        self.rate, self.slack, self.accel = rate, slack, accel
        super().__init__(fk_ticks)

    def reset(self):
        super().reset()
        self.t = self.dt = math.nan
        self.q = (0.0, 0.0, 0.0)

    def update(self, t, ticks):
        if type(t) is not float:
            raise TypeError("time")
        t0, t1, t2 = ticks
        if type(t0) is not int or type(t1) is not int or type(t2) is not int:
            raise TypeError("ticks")
        if self.prev is None:
            self.prev, self.t = (t0, t1, t2), t
            return (self.x, self.y, self.th)
        dt = t - self.t
        if not 0.0 < dt < math.inf:
            raise ValueError("time order")
        p0, p1, p2 = self.prev
        d0, d1, d2 = t0 - p0 + 0.0, t1 - p1 + 0.0, t2 - p2 + 0.0
        lim = self.rate * dt + self.slack
        if not (-lim <= d0 <= lim and -lim <= d1 <= lim and -lim <= d2 <= lim):
            raise ValueError("jump")
        if self.dt == self.dt:
            q0, q1, q2 = self.q
            ch = self.accel * dt * self.dt + 2.0 * self.slack
            if not (-ch <= d0 - q0 <= ch and -ch <= d1 - q1 <= ch and -ch <= d2 - q2 <= ch):
                raise ValueError("change of speed")
        a = self.f00 * d0 + self.f01 * d1 + self.f02 * d2
        b = self.f10 * d0 + self.f11 * d1 + self.f12 * d2
        phi = self.f20 * d0 + self.f21 * d1 + self.f22 * d2
        h = 0.5 * phi
        k = 1.0 - h * h / 6.0 if -0.1 < h < 0.1 else sin(h) / h
        h += self.th
        c, s = cos(h), sin(h)
        self.x += k * (c * a - s * b)
        self.y += k * (s * a + c * b)
        th = self.th + phi
        if th >= pi or th < -pi:
            th -= 2 * pi * floor((th + pi) / (2 * pi))
        self.th = th
        self.prev, self.t, self.dt, self.q = (t0, t1, t2), t, dt, (d0, d1, d2)
        return (self.x, self.y, th)


class PlainLoop:
    """Reference: straightforward pure-Python exact odometry."""

    def __init__(self, fk, scale):
        self.fk = [list(row) for row in fk]
        self.scale = list(scale)
        self.reset()

    def reset(self):
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
        self.reset()

    def reset(self):
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


def main(n: int = 2000, rounds: int = 40) -> dict:
    robot, t, ticks = tomasi_log(n)
    fk = robot.fk_matrix()
    scale = [w.encoder.rad_per_tick for w in robot.wheels]
    fk_ticks = [[float(v) * s for v, s in zip(row, scale, strict=True)] for row in fk]
    ts = [float(v) for v in t]
    ints = [[int(v) for v in row] for row in ticks]
    inputs = {  # name: (timestamps, readings, method of Odometry)
        "Python ints (list)": (ts, ints, "update"),
        "Python ints (tuple)": (ts, [tuple(r) for r in ints], "update"),
        "NumPy int64 row": (ts, list(ticks), "update"),
        "NumPy uint32 row": (ts, list((ticks + 1_000_000).astype(np.uint32)), "update"),
        "list of np.int64": (ts, [list(r) for r in ticks], "update"),
        "np.float64 time, int64 row": (list(t), list(ticks), "update"),
        "wheel angles (update_angles)": (
            ts,
            [[v * s for v, s in zip(r, scale, strict=True)] for r in ints],
            "update_angles",
        ),
        "wheel angles as NumPy rows": (ts, list(ticks * np.array(scale)), "update_angles"),
    }

    def run(est, times, rows, method="update"):
        def go():
            est.reset()
            upd = getattr(est, method)
            for k in range(n):
                upd(times[k], rows[k])

        return go

    rule = Odometry(robot).rules[0]  # the tick bounds of omnikin's default rules (every wheel alike)
    accel, slack = rule.change_bounds("ticks")  # A [ticks/s^2], slack [ticks]
    runs = {
        "reference step": run(ReferenceStep(fk_ticks), ts, ints),
        "reference step, same checks": run(ReferenceCheckedStep(fk_ticks, rule.rate, slack, accel / 2), ts, ints),
        "plain loop": run(PlainLoop(fk, scale), ts, ints),
        "numpy per update": run(NumpyPerUpdate(fk, scale), ts, ints),
    }
    for name, (times, rows, method) in inputs.items():
        runs[f"omnikin, {name}"] = run(Odometry(robot), times, rows, method)
    runs["omnikin, 16-bit counters, Python ints"] = run(
        Odometry(robot, counter_bits=16), ts, [[v % 65536 for v in r] for r in ints]
    )
    best = {name: math.inf for name in runs}
    order = list(runs)
    for r in range(rounds):  # short runs, interleaved in a changing order: load from other processes hits all alike
        random.Random(r).shuffle(order)
        for name in order:
            best[name] = min(best[name], best_time(runs[name], repeat=1) / n * 1e6)
    ref = best["reference step"]
    checked = best["reference step, same checks"]
    fastest = best["omnikin, Python ints (list)"]
    print(f"streaming odometry update, tomasi-omni3, {n} samples per run (best of {rounds} interleaved rounds)")
    for name, us in best.items():
        print(f"  {name:44s} {us:7.3f} us/update   {us / ref:5.2f}x reference step   {us / fastest:5.2f}x fastest")
    worst = max((us for name, us in best.items() if name.startswith("omnikin, ") and "16-bit" not in name))
    print(
        f"  target fastest <= 1.2x reference step: {fastest / ref:.2f}x {'met' if fastest <= 1.2 * ref else 'NOT met'}"
    )
    print(f"  fastest path / hand-written step with the same checks: {fastest / checked:.2f}x")
    print(
        f"  target every input type <= 1.3x fastest: worst {worst / fastest:.2f}x "
        f"{'met' if worst <= 1.3 * fastest else 'NOT met'}"
    )
    return {
        "us_per_update": best,
        "ratio_to_reference": {k: v / ref for k, v in best.items()},
        "ratio_to_fastest": {k: v / fastest for k, v in best.items()},
        "fastest_to_checked_reference": fastest / checked,
    }


if __name__ == "__main__":
    save("streaming", main())
