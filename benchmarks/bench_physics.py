"""Physics simulation (extra ``physics``): model generation and speed against real time.

Per preset: the time to describe the robot and write its MJCF (pure Python), to compile it in
MuJoCo, and to settle it on the floor; then the ratio of simulated to wall time while it drives
a constant twist at the default 2 ms step (the servos, ramps and heading tracking of
``PhysicsSim.step`` included). Best of three, in one process, so on one core; run it under
``taskset -c 0`` to pin it.

Then the scaling of independent runs over processes: ``PARALLEL_RUNS`` independent drives of
tomasi-omni3 (each its own ``PhysicsSim``, settled and driven ``SIM_SECONDS``) spread over a pool
of 1, then of 2 worker processes (``multiprocessing``, started and warmed up before the clock
starts); throughput = simulated seconds of all runs per wall second, best of three with the two
pool sizes taking turns, and the ratio of the two throughputs in the same run (2.0 would be
perfect scaling on two free cores). Do not pin this part: it needs the cores it measures.

Last, the estimate against the run (:func:`omnikin.physics.cost.physics_run_cost`, which
``--max-time`` checks): for each of :data:`ESTIMATED` the estimate's computing time and the run's
(this process's CPU time), and their ratio, above 1 on the safe side (docs/physics.md, "Computing
time").
"""

from __future__ import annotations

import multiprocessing
import os
import time

from _common import best_time, save
from omnikin import load_robot
from omnikin.physics.description import describe
from omnikin.physics.mjcf import mjcf
from omnikin.physics.simulator import PhysicsSim

ROBOTS = {
    "tomasi-omni3": (0.2, 0.1, 0.5),
    "omni4": (0.2, 0.1, 0.5),
    "mecanum4": (0.2, 0.1, 0.5),
    "diff-drive": (0.3, 0.0, 0.5),
    "ackermann": (0.5, 0.0, 0.4),
    "xr4000": (0.2, 0.1, 0.3),
}
ESTIMATED = [
    # (robot, plan, rate [Hz], time step [s])
    ("tomasi-omni3", "line 6", 50.0, 0.002),
    ("tomasi-omni3", "line 1", 100.0, 0.0005),
    ("tomasi-omni3", "square cw rotate 1", 50.0, 0.002),
    ("mecanum4", "spin 360", 20.0, 0.002),
    ("diff-drive", "line 3", 200.0, 0.001),
    ("synchro", "square cw rotate 4", 50.0, 0.002),
]
SIM_SECONDS = 5.0
PARALLEL_ROBOT = "tomasi-omni3"
PARALLEL_RUNS = 16
REPEATS = 3


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


def independent_run(seconds: float) -> tuple[float, float]:
    """One drive of PARALLEL_ROBOT for ``seconds`` of simulated time, from a fresh ``PhysicsSim``:
    ``(simulated seconds, CPU seconds of the worker)``."""
    cpu = time.process_time()
    robot = load_robot(PARALLEL_ROBOT)
    sim = PhysicsSim(robot)
    sim.command(robot.ik(ROBOTS[PARALLEL_ROBOT]).wheel_speeds)
    sim.advance(seconds)
    return sim.time, time.process_time() - cpu


def parallel_throughput(processes: int, runs: int) -> tuple[float, float]:
    """``runs`` independent runs over ``processes`` workers: simulated seconds per wall second,
    and per CPU second of the workers (equal for 1 and 2 processes when the runs do not slow
    each other down; then the wall ratio says how many cores were free)."""
    with multiprocessing.get_context("spawn").Pool(processes) as pool:
        pool.map(independent_run, [0.01] * processes, chunksize=1)  # start and import in every worker
        t0 = time.perf_counter()
        results = pool.map(independent_run, [SIM_SECONDS] * runs, chunksize=1)
        wall = time.perf_counter() - t0
    simulated = sum(r[0] for r in results)
    return simulated / wall, simulated / sum(r[1] for r in results)


def scaling() -> dict:
    """Throughput of independent runs in 1 and 2 processes, and their ratio, in the same run
    (best of :data:`REPEATS`, the two pool sizes taking turns)."""
    load = os.getloadavg()[0]
    one = two = one_cpu = two_cpu = 0.0
    for _ in range(REPEATS):  # interleaved, best of each: a burst of other work hits both alike
        wall, cpu = parallel_throughput(1, PARALLEL_RUNS)
        one, one_cpu = max(one, wall), max(one_cpu, cpu)
        wall, cpu = parallel_throughput(2, PARALLEL_RUNS)
        two, two_cpu = max(two, wall), max(two_cpu, cpu)
    print(
        f"independent runs ({PARALLEL_RUNS} x {SIM_SECONDS:g} s of {PARALLEL_ROBOT}; {os.cpu_count()} cores, "
        f"load {load:.2f} before): x real time per wall second 1 process {one:.1f}, 2 processes {two:.1f}, "
        f"ratio {two / one:.2f}; per CPU second {one_cpu:.1f} and {two_cpu:.1f}, ratio {two_cpu / one_cpu:.2f}"
    )
    return {
        "robot": PARALLEL_ROBOT,
        "runs": PARALLEL_RUNS,
        "repeats": REPEATS,
        "sim_seconds_each": SIM_SECONDS,
        "cores": os.cpu_count(),
        "load_before": load,
        "throughput_1_process": one,
        "throughput_2_processes": two,
        "ratio": two / one,
        "per_cpu_second_1_process": one_cpu,
        "per_cpu_second_2_processes": two_cpu,
        "per_cpu_ratio": two_cpu / one_cpu,
    }


def estimate_against_run() -> list[dict]:
    """The estimate of :data:`ESTIMATED`'s runs against their computing time (module docstring)."""
    from omnikin.motion.plans import parse_plan
    from omnikin.motion.timing import sample_plan
    from omnikin.physics.cost import physics_run_cost
    from omnikin.physics.run import simulate_physics

    rows = []
    print("  estimate against the run (CPU time of this process; est / run > 1 is on the safe side)")
    print(f"    {'robot':<14s} {'plan':<20s} {'step [s]':>9s} {'estimate [s]':>13s} {'run [s]':>9s} {'est / run':>10s}")
    for name, plan, rate, step in ESTIMATED:
        robot = load_robot(name)
        sampled = sample_plan(parse_plan(plan), robot, rate)
        estimate = physics_run_cost(sampled, robot, robot, step)
        cpu = time.process_time()
        run = simulate_physics(sampled, robot, robot, rate=rate, step=step)
        used = time.process_time() - cpu
        ratio = estimate.seconds / used
        rows.append(
            {
                "robot": name,
                "plan": plan,
                "rate_hz": rate,
                "step_s": step,
                "simulated_bound_s": estimate.simulated,
                "simulated_s": float(run.t[-1]),
                "step_us": estimate.step_seconds * 1e6,
                "estimate_s": estimate.seconds,
                "run_s": used,
                "ratio": ratio,
            }
        )
        print(f"    {name:<14s} {plan:<20s} {step:9g} {estimate.seconds:13.3f} {used:9.3f} {ratio:10.2f}")
    return rows


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
    out["parallel"] = scaling()
    out["estimate"] = estimate_against_run()
    return out


if __name__ == "__main__":
    save("physics", main())
