"""Physics simulation (extra ``physics``): model generation and speed against real time.

Per preset: the time to describe the robot and write its MJCF (pure Python), to compile it in
MuJoCo, and to settle it on the floor; then the ratio of simulated to wall time while it drives
a constant twist at the default 2 ms step (the servos, ramps and heading tracking of
``PhysicsSim.step`` included). Best of three, in one process, so on one core; run it under
``taskset -c 0`` to pin it.
"""

from __future__ import annotations

import time

from _common import best_time, save
from omnikin import load_robot
from omnikin.physics.description import describe
from omnikin.physics.engine import PhysicsSim
from omnikin.physics.mjcf import mjcf

ROBOTS = {
    "tomasi-omni3": (0.2, 0.1, 0.5),
    "omni4": (0.2, 0.1, 0.5),
    "mecanum4": (0.2, 0.1, 0.5),
    "diff-drive": (0.3, 0.0, 0.5),
    "ackermann": (0.5, 0.0, 0.4),
    "xr4000": (0.2, 0.1, 0.3),
}
SIM_SECONDS = 5.0


def real_time_factor(name: str, twist) -> float:
    robot = load_robot(name)
    best = 0.0
    for _ in range(3):
        sim = PhysicsSim(robot)
        ik = robot.ik(twist)
        sim.command(ik.wheel_speeds, ik.steer_angles if robot.steerable else None)
        t0 = time.perf_counter()
        sim.advance(SIM_SECONDS)
        best = max(best, SIM_SECONDS / (time.perf_counter() - t0))
    return best


def main() -> dict:
    import mujoco

    out = {"mujoco": mujoco.__version__, "step_s": 0.002, "robots": {}}
    print(f"physics (MuJoCo {mujoco.__version__}, 2 ms step, one process)")
    head = ("robot", "bodies", "mjcf [ms]", "compile [ms]", "settle [ms]", "x real time")
    print(f"  {head[0]:<14s} {head[1]:>6s} {head[2]:>10s} {head[3]:>12s} {head[4]:>12s} {head[5]:>12s}")
    for name, twist in ROBOTS.items():
        robot = load_robot(name)
        text = mjcf(describe(robot))
        write = best_time(lambda robot=robot: mjcf(describe(robot)), repeat=5)
        compile_ = best_time(lambda text=text: mujoco.MjModel.from_xml_string(text), repeat=5)
        whole = best_time(lambda robot=robot: PhysicsSim(robot), repeat=3)
        bodies = mujoco.MjModel.from_xml_string(text).nbody
        rtf = real_time_factor(name, twist)
        settle = whole - write - compile_
        out["robots"][name] = {
            "bodies": bodies,
            "mjcf_ms": write * 1e3,
            "compile_ms": compile_ * 1e3,
            "settle_ms": settle * 1e3,
            "real_time_factor": rtf,
        }
        print(f"  {name:<14s} {bodies:6d} {write * 1e3:10.2f} {compile_ * 1e3:12.2f} {settle * 1e3:12.1f} {rtf:12.1f}")
    return out


if __name__ == "__main__":
    save("physics", main())
