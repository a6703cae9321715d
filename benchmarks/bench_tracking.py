"""Tracking in physics, every preset: the figure-eight and a square with blended corners at 80 % of
the wheel limits (12 rad/s and 40 rad/s^2, and the motors' own), each preset with every
controller it takes; the truth's RMS and largest distance to the path, and the wall time of the
run against the simulated time (MuJoCo, 2 ms steps, 50 Hz control).

A preset that cannot drive a path (a car's turning radius) is listed with the reason; the car
drives the same shapes six times larger. The table is docs/control.md's, "Tracking in physics".
"""

from __future__ import annotations

import time

from _common import save
from omnikin import PRESET_NAMES, load_robot
from omnikin.api.tracking import track
from omnikin.errors import InputError

SCALE = 0.8
PATHS = ("figure8 1", "square 1 0.2")
LARGER = {"ackermann": ("figure8 6", "square 6 1.5")}


def controllers(robot) -> tuple[str, ...]:
    """The controllers a layout takes: feedback if it translates in every direction, the MPC if
    its wheels do not steer, pure pursuit if it drives along its heading."""
    out = []
    if not robot.fixed:
        out.append("feedback")
    if not robot.steerable:
        out.append("mpc")
    if robot.fixed:
        out.append("pursuit")
    return tuple(out)


def main() -> dict:
    rows = []
    for name in PRESET_NAMES:
        robot = load_robot(name)
        for spec in LARGER.get(name, ()) + PATHS:
            for controller in controllers(robot):
                start = time.perf_counter()
                try:
                    done = track(
                        robot,
                        spec,
                        controller=controller,
                        engine="physics",
                        max_wheel_speed=12.0 * SCALE,
                        max_wheel_accel=40.0 * SCALE,
                    )
                except InputError as exc:
                    rows.append({"robot": name, "path": spec, "controller": controller, "refused": str(exc)})
                    print(f"{name:20s} {spec:14s} {controller:9s} refused: {exc}")
                    continue
                wall = time.perf_counter() - start
                s = done.summary()
                row = {
                    "robot": name,
                    "path": spec,
                    "controller": controller,
                    "duration_s": s["duration_s"],
                    "rms_mm": s["rms_error_m"] * 1e3,
                    "max_mm": s["max_error_m"] * 1e3,
                    "saturated": s["saturated_samples"],
                    "samples": s["samples"],
                    "wall_s": wall,
                }
                rows.append(row)
                print(
                    f"{name:20s} {spec:14s} {controller:9s} {s['duration_s']:6.2f} s  RMS {row['rms_mm']:7.2f} mm  "
                    f"max {row['max_mm']:7.2f} mm  saturated {s['saturated_samples']:4d}/{s['samples']}  "
                    f"wall {wall:5.1f} s"
                )
    return {"rows": rows}


if __name__ == "__main__":
    save("tracking", main())
