"""Batch odometry: target >= 10 million samples/s on one core, and no slower than the
straightforward vectorised NumPy reference.

References measured in the same run:
* ``straightforward numpy``: diff, ``@`` with the FK matrix, the SE(2) exponential of every
  increment with np.sin/np.cos and a np.where small-angle branch, then headings by cumsum and
  rotation of every local step into the world, cumsum of positions;
* ``plain loop``: a pure-Python float loop (on a shorter log).
"""

from __future__ import annotations

import math

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


def main(n: int = 2_000_000, trials: int = 20) -> dict:
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
    rates[f"omnikin, {trials} trials x {m}"] = trials * m / best_time(
        lambda: batch_odometry(robot, t[:m], stacked), repeat=5)
    short = [list(map(int, row)) for row in ticks[:100_000]]
    rates["plain loop"] = len(short) / best_time(lambda: plain_loop(fk.tolist(), scale.tolist(), t, short), repeat=2)
    base = rates["straightforward numpy"]
    print(f"batch odometry, tomasi-omni3, {n} samples (best of 5)")
    for name, r in rates.items():
        print(f"  {name:32s} {r / 1e6:8.2f} M samples/s   {r / base:5.2f}x straightforward numpy")
    print(f"  max |position difference| omnikin vs reference: {err:.2e} m")
    print(f"  target >= 10 M samples/s: {'met' if rates['omnikin'] >= 10e6 else 'NOT met'}; "
          f"no slower than the reference: {'met' if rates['omnikin'] >= base else 'NOT met'}")
    return {"samples_per_s": rates, "target": 10e6, "max_position_difference_m": err}


if __name__ == "__main__":
    save("batch", main())
