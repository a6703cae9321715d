"""Batch odometry: target >= 10 million samples/s on one core, and never slower than the
straightforward vectorised NumPy reference, warm (best of several calls in one process) or cold
(the first call in a fresh process, which pays the page faults of every fresh large array).

References measured in the same run:
* ``straightforward numpy``: diff, ``@`` with the FK matrix, the SE(2) exponential of every
  increment with np.sin/np.cos and a np.where small-angle branch, then headings by cumsum and
  rotation of every local step into the world, cumsum of positions;
* ``plain loop``: a pure-Python float loop (on a shorter log).
"""

from __future__ import annotations

import math
import statistics
import subprocess
import sys
import time

import numpy as np

from _common import best_time, save, tomasi_log
from omnikin import batch_odometry


def straightforward_numpy(fk, scale, t, ticks):
    d = np.diff(ticks, axis=-2) * scale
    inc = d @ fk.T
    a, b, phi = inc[..., 0], inc[..., 1], inc[..., 2]
    small = np.abs(phi) < 1e-9
    safe = np.where(small, 1.0, phi)
    s1 = np.where(small, 1.0, np.sin(phi) / safe)
    c1 = np.where(small, 0.0, (1 - np.cos(phi)) / safe)
    dx, dy = s1 * a - c1 * b, c1 * a + s1 * b
    th = np.concatenate([np.zeros(phi.shape[:-1] + (1,)), np.cumsum(phi, axis=-1)], axis=-1)
    c, s = np.cos(th[..., :-1]), np.sin(th[..., :-1])
    x = np.concatenate([np.zeros(phi.shape[:-1] + (1,)), np.cumsum(c * dx - s * dy, axis=-1)], axis=-1)
    y = np.concatenate([np.zeros(phi.shape[:-1] + (1,)), np.cumsum(s * dx + c * dy, axis=-1)], axis=-1)
    return np.stack([x, y, np.arctan2(np.sin(th), np.cos(th))], axis=-1)


def plain_loop(fk, scale, t, ticks):
    x = y = th = 0.0
    prev = ticks[0]
    for row in ticks[1:]:
        d = [(row[j] - prev[j]) * scale[j] for j in range(3)]
        a, b, phi = (sum(fk[i][j] * d[j] for j in range(3)) for i in range(3))
        k = math.sin(phi / 2) / (phi / 2) if phi else 1.0
        h = th + phi / 2
        x += k * (math.cos(h) * a - math.sin(h) * b)
        y += k * (math.sin(h) * a + math.cos(h) * b)
        th += phi
        prev = row
    return x, y, th


def cold_call(which: str, n: int) -> float:
    """Seconds of the first call of ``which`` in this (fresh) process, inputs made beforehand."""
    robot, t, ticks = tomasi_log(n)
    fk = robot.fk_matrix()
    scale = np.array([w.encoder.rad_per_tick for w in robot.wheels])
    batch_odometry(robot, t[:10], ticks[:10])  # imports, not the measurement
    straightforward_numpy(fk, scale, t[:10], ticks[:10])
    fn = {
        "omnikin": lambda: batch_odometry(robot, t, ticks),
        "straightforward numpy": lambda: straightforward_numpy(fk, scale, t, ticks),
    }[which]
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def cold(n: int, runs: int) -> dict:
    """Median and best of ``runs`` fresh processes per implementation, alternating."""
    times = {"omnikin": [], "straightforward numpy": []}
    for _ in range(runs):
        for which in times:
            out = subprocess.run(
                [sys.executable, __file__, "--cold", which, str(n)], capture_output=True, text=True, check=True
            )
            times[which].append(float(out.stdout))
    return {k: {"median_s": statistics.median(v), "best_s": min(v)} for k, v in times.items()}


def main(n: int = 2_000_000, trials: int = 20, cold_runs: int = 5) -> dict:
    robot, t, ticks = tomasi_log(n)
    fk = robot.fk_matrix()
    scale = np.array([w.encoder.rad_per_tick for w in robot.wheels])
    ours = batch_odometry(robot, t, ticks).poses
    ref = straightforward_numpy(fk, scale, t, ticks)
    err = float(np.max(np.abs(ours[:, :2] - ref[:, :2])))
    rates = {
        "omnikin": n / best_time(lambda: batch_odometry(robot, t, ticks), repeat=5),
        "straightforward numpy": n / best_time(lambda: straightforward_numpy(fk, scale, t, ticks), repeat=5),
    }
    m = n // trials
    stacked = np.stack([ticks[:m]] * trials)
    rates[f"omnikin, {trials} trials x {m}"] = (
        trials * m / best_time(lambda: batch_odometry(robot, t[:m], stacked), repeat=5)
    )
    short = [list(map(int, row)) for row in ticks[:100_000]]
    rates["plain loop"] = len(short) / best_time(lambda: plain_loop(fk.tolist(), scale.tolist(), t, short), repeat=2)
    base = rates["straightforward numpy"]
    print(f"batch odometry, tomasi-omni3, {n} samples of int64 ticks (warm: best of 5 in one process)")
    for name, r in rates.items():
        print(f"  {name:32s} {r / 1e6:8.2f} M samples/s   {r / base:5.2f}x straightforward numpy")
    print(f"  max |position difference| omnikin vs reference: {err:.2e} m")
    first = cold(n, cold_runs)
    ratio = first["straightforward numpy"]["median_s"] / first["omnikin"]["median_s"]
    print(f"cold: first call in a fresh process, median (best) of {cold_runs} processes each")
    for name, c in first.items():
        print(f"  {name:32s} {n / c['median_s'] / 1e6:8.2f} ({n / c['best_s'] / 1e6:.2f}) M samples/s")
    print(f"  omnikin cold is {ratio:.2f}x the reference's speed")
    print(
        f"  target >= 10 M samples/s: {'met' if rates['omnikin'] >= 10e6 else 'NOT met'}; never slower than "
        f"the reference: warm {'met' if rates['omnikin'] >= base else 'NOT met'}, "
        f"cold {'met' if ratio >= 1.0 else 'NOT met'}"
    )
    return {
        "samples_per_s": rates,
        "target": 10e6,
        "max_position_difference_m": err,
        "cold": first,
        "cold_speed_ratio": ratio,
    }


if __name__ == "__main__":
    if sys.argv[1:2] == ["--cold"]:
        print(cold_call(sys.argv[2], int(sys.argv[3])))
    else:
        save("batch", main())
