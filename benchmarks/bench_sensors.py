"""Sensors' cost (issue 23): the physics engine's speed with an IMU and a lidar in a world, against
the same robot without sensors on the empty floor, and the kinematic lidar's vectorised ray
casting against a plain Python loop; ratios measured in one run.

1. Physics real-time factor (simulated / wall time, best of :data:`REPEATS`, the configurations
   taking turns) of tomasi-omni3 driving a constant twist for :data:`SIM_SECONDS`: on the empty
   floor without sensors (the reference), in the UMBmark arena (``examples/worlds/arena.yaml``)
   without sensors, and in the arena as ``tomasi-omni3-lidar`` (IMU at 200 Hz, read at every
   time step around its samples; a 360-beam lidar at 10 Hz by ``mj_multiRay``). Target: the last
   at least 0.8 of the reference.
2. ``PhysicsSim.step`` against a bare ``mujoco.mj_step`` on the same compiled model (the wheel
   servos in Python at every 2 ms step): the overhead ratio, reported as it is.
3. One 360-beam scan of the kinematic lidar (:func:`omnikin.sensors.lidar.true_ranges`) against
   100 walls, against a plain Python loop over beams and walls (the slab test of each ray against
   each wall's rectangle in its own frame); the two agree to 1e-9 m. Target: at least 20x.

    python3 benchmarks/bench_sensors.py
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from _common import best_time, save
from omnikin import load_robot
from omnikin.io.world_file import load_world
from omnikin.kinematics.sensors import Lidar, Mount
from omnikin.sensors.lidar import true_ranges
from omnikin.world import Wall, make_world
from omnikin.world.plane import wall_rects
from omnikin.world.shapes import shapes_of

ROOT = Path(__file__).resolve().parents[1]
SIM_SECONDS = 5.0
REPEATS = 3
TWIST = (0.2, 0.1, 0.3)
WALLS = 100


def _drive(robot_name: str, world) -> float:
    """Simulated over wall seconds of one drive (the model built and settled before the clock)."""
    from omnikin.physics.simulator import PhysicsSim

    robot = load_robot(robot_name)
    sim = PhysicsSim(robot, start=(0.0, 0.0, 0.0) if world is None else world.start, world=world, sensors=True)
    sim.command(robot.ik(TWIST).wheel_speeds)
    t0 = time.perf_counter()
    sim.advance(SIM_SECONDS)
    wall = time.perf_counter() - t0
    if sim.sensors is not None:
        sim.sensors.truths()  # what a run does with them at its end
    return SIM_SECONDS / wall


def physics_factors() -> dict:
    arena = load_world(ROOT / "examples" / "worlds" / "arena.yaml")
    configurations = {
        "empty floor, no sensors": ("tomasi-omni3", None),
        "arena, no sensors": ("tomasi-omni3", arena),
        "arena, IMU 200 Hz + lidar 360 beams 10 Hz": ("tomasi-omni3-lidar", arena),
    }
    best = dict.fromkeys(configurations, 0.0)
    for _ in range(REPEATS):
        for name, (robot, world) in configurations.items():
            best[name] = max(best[name], _drive(robot, world))
    reference = best["empty floor, no sensors"]
    return {name: {"real_time_factor": rtf, "ratio": rtf / reference} for name, rtf in best.items()}


def step_overhead() -> dict:
    import mujoco

    from omnikin.physics.simulator import PhysicsSim

    robot = load_robot("tomasi-omni3")
    sim = PhysicsSim(robot)
    sim.command(robot.ik(TWIST).wheel_speeds)
    sim.advance(0.5)
    model, data = sim.model, sim.data
    steps = 500
    ours = best_time(lambda: sim.step(steps), repeat=5) / steps
    bare = best_time(lambda: [mujoco.mj_step(model, data) for _ in range(steps)], repeat=5) / steps
    return {"physics_sim_step_us": ours * 1e6, "mj_step_us": bare * 1e6, "ratio": ours / bare}


def _loop_ranges(rects, x: float, y: float, angles) -> list[float]:
    """The reference: each beam against each wall rectangle ``(cx, cy, half length, half width,
    yaw)``, the slab test in the rectangle's frame, in plain Python."""
    out = []
    for a in angles:
        dx, dy = math.cos(a), math.sin(a)
        best = math.inf
        for cx, cy, hx, hy, yaw in rects:
            c, s = math.cos(yaw), math.sin(yaw)
            px, py = c * (x - cx) + s * (y - cy), -s * (x - cx) + c * (y - cy)
            ux, uy = c * dx + s * dy, -s * dx + c * dy
            near, far = -math.inf, math.inf
            for p, u, h in ((px, ux, hx), (py, uy, hy)):
                if abs(u) < 1e-15:
                    if abs(p) > h:
                        near, far = math.inf, -math.inf
                        break
                    continue
                t1, t2 = (-h - p) / u, (h - p) / u
                near, far = max(near, min(t1, t2)), min(far, max(t1, t2))
            if near <= far and far >= 0.0 and near >= 0.0:
                best = min(best, near)
        out.append(best)
    return out


def scan_speed() -> dict:
    rng = np.random.default_rng(3)
    walls = []
    while len(walls) < WALLS:  # short walls scattered in a 20 m square, clear of the lidar at the origin
        a = rng.uniform(-10.0, 10.0, 2)
        if np.hypot(*a) < 1.0:
            continue
        b = a + rng.uniform(-1.0, 1.0, 2)
        walls.append(Wall((tuple(a), tuple(b)), 0.05, 0.5))
    world = make_world("scattered", walls=walls)
    shapes = shapes_of(world)
    lidar = Lidar("l", Mount(z=0.12), beams=360, range_max=30.0)
    angles = lidar.angles()
    rects = [tuple(r) for w in world.walls for r in wall_rects(np.asarray(w.points, dtype=float), w.thickness)]
    ours = true_ranges(shapes, (0.0, 0.0, 0.0), lidar)[0]
    loop = np.array(_loop_ranges(rects, 0.0, 0.0, angles))
    loop[loop > lidar.range_max] = math.inf
    assert np.array_equal(np.isinf(ours), np.isinf(loop)), "the two see different beams hit"
    finite = np.isfinite(ours)
    agree = float(np.max(np.abs(ours[finite] - loop[finite]), initial=0.0))
    assert agree < 1e-9, agree
    vectorised = best_time(lambda: true_ranges(shapes, (0.0, 0.0, 0.0), lidar), repeat=7, number=5)
    python_loop = best_time(lambda: _loop_ranges(rects, 0.0, 0.0, angles), repeat=3)
    return {
        "walls": WALLS,
        "beams": 360,
        "vectorised_ms": vectorised * 1e3,
        "python_loop_ms": python_loop * 1e3,
        "speedup": python_loop / vectorised,
        "largest_difference_m": agree,
    }


def main() -> dict:
    """Every figure of the module docstring (the physics ones when MuJoCo is installed)."""
    results: dict = {"scan": scan_speed()}
    print("kinematic scan:", results["scan"])
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print("physics: skipped (pip install -e '.[physics]')")
        return results
    results["step_overhead"] = step_overhead()
    print("PhysicsSim.step against mj_step:", results["step_overhead"])
    results["physics"] = physics_factors()
    for name, row in results["physics"].items():
        print(f"physics, {name}: real-time factor {row['real_time_factor']:.2f}, ratio {row['ratio']:.2f}")
    return results


if __name__ == "__main__":
    print("saved", save("sensors", main()))
