"""Cost of one control cycle of the base runtime (what ``omnikin ros`` does per period).

One cycle = one offered velocity command (validation, saturation check) and one
``BaseRuntime.step`` (read the simulated wheels, odometry with covariance, command filter,
inverse kinematics, write the wheels). The simulated back-end's own work is included, as in
``omnikin ros`` with the default back-end. The figure that matters is the share of the
control period used at 100 Hz (10 ms): the rest is left to rclpy and the messages. The
streaming odometry update alone is measured in the same run for scale.
"""

from __future__ import annotations

import numpy as np

from _common import best_time, save
from omnikin import Odometry, load_robot
from omnikin.runtime.base import BaseRuntime
from omnikin.simulation.backend import SimBackend

ROBOTS = ("tomasi-omni3", "omni4", "mecanum4", "diff-drive", "xr4000", "villasenor-omni3")
CYCLES = 1000
PERIOD = 0.01


def cycle_seconds(name: str) -> float:
    robot = load_robot(name)
    twist = (0.1, 0.0, 0.2) if robot.fixed else (0.1, 0.05, 0.2)
    runtime = BaseRuntime(robot, SimBackend(robot))
    clock = [0.0]

    def run():
        t = clock[0]
        for _ in range(CYCLES):
            t += PERIOD
            runtime.command(twist, t)
            runtime.step(t)
        clock[0] = t

    run()  # warm-up: caches, first measurement
    return best_time(run, repeat=5) / CYCLES


def odometry_update_seconds() -> float:
    robot = load_robot("tomasi-omni3")
    odo = Odometry(robot)
    angles = np.cumsum(np.full((CYCLES, 3), 0.01), axis=0).tolist()

    def run():
        odo.reset()
        for k, a in enumerate(angles):
            odo.update_angles(k * PERIOD, a)

    return best_time(run, repeat=5) / CYCLES


def main() -> dict:
    ref = odometry_update_seconds()
    out = {"odometry_update_us": ref * 1e6, "robots": {}}
    print(f"streaming odometry update alone (tomasi-omni3): {ref * 1e6:.1f} us")
    for name in ROBOTS:
        s = cycle_seconds(name)
        out["robots"][name] = {"cycle_us": s * 1e6, "share_of_100hz_period": s / PERIOD, "vs_odometry": s / ref}
        print(
            f"{name:18s} control cycle {s * 1e6:7.0f} us = {100 * s / PERIOD:4.1f} % of a 100 Hz period "
            f"({s / ref:.0f}x the odometry update)"
        )
    return out


if __name__ == "__main__":
    save("runtime", main())
