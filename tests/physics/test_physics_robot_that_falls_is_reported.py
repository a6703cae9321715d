"""A simulated robot that falls over is reported by every user of the physics engine, as
``simulate --engine physics`` does (:meth:`omnikin.physics.simulator.PhysicsSim.fall`: the chassis
tilted beyond ``TIPPED``): the runtime's physics back-end stops its wheels and says so
(``fallen``, ``stats()``), the viewer's live robot stops and shows one line, and a study's trial
whose robot fell is a row with that reason, not a number.

Two ways to make tomasi-omni3 fall in real MuJoCo: a push (a torque of 1.5 N m about the world
x axis on the chassis for 0.5 s: its weight, about 19 N, acts on a lever of at most the 57 mm
from its centre to the nearest edge of its wheels' triangle, 1.1 N m, so the push tips it; it
rolls onto its back) and a centre of mass 2 m above the floor (``physical.com``), which the
ramp's acceleration, bounded by traction and not by tipping, throws over on ``line 1``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.errors import OmnikinError, PhysicsError  # noqa: E402
from omnikin.kinematics.physical import PhysicalBody  # noqa: E402
from omnikin.physics.backend import PhysicsBackend  # noqa: E402
from omnikin.physics.simulator import TIPPED  # noqa: E402

DT = 0.02
PUSH = 1.5  # [N m] about world x
PUSH_TIME = 0.5  # [s]


def push(sim, t: float) -> None:
    """The push of the module docstring, while ``t`` [s] < PUSH_TIME."""
    sim.data.xfrc_applied[sim._chassis, 3] = PUSH if t < PUSH_TIME else 0.0


def tall_robot():
    robot = load_robot("tomasi-omni3")
    return replace(robot, physical=PhysicalBody(com=(0.0, 0.0, 2.0)))


def test_the_physics_backend_reports_a_fall_and_stops_the_wheels_whatever_it_is_commanded():
    backend = PhysicsBackend(load_robot("tomasi-omni3"))
    fast = np.full(3, 5.0)  # [rad/s]
    fell_at = None
    for k in range(101):  # 2 s
        t = k * DT
        push(backend.sim, t)
        backend.write(t, fast if backend.fallen else np.zeros(3))  # drive hard once it fell
        backend.read(t)
        if backend.fallen and fell_at is None:
            fell_at = t
    print(f"fallen: {backend.fallen!r} (seen at t = {fell_at}); tilt {math.degrees(backend.sim.tilt):.1f} deg")
    assert fell_at is not None and fell_at < PUSH_TIME + 0.2
    assert "tipped over" in backend.fallen and "tomasi-omni3" in backend.fallen
    assert backend.stats()["fallen"] == backend.fallen
    assert backend.sim.tilt > TIPPED
    # commanded 5 rad/s for over a second after the fall, the wheels stand
    assert np.max(np.abs(backend.sim.wheel_speeds)) < 0.05, backend.sim.wheel_speeds


def test_a_standing_physics_backend_reports_nothing_and_drives():
    backend = PhysicsBackend(load_robot("tomasi-omni3"))
    for k in range(51):
        backend.write(k * DT, np.full(3, 5.0))
        backend.read(k * DT)
    assert backend.fallen == "" and backend.stats()["fallen"] == ""
    np.testing.assert_allclose(backend.sim.wheel_speeds, 5.0, rtol=0.02)


def test_the_viewers_live_physics_robot_says_once_that_it_fell_and_stops():
    from omnikin.physics.engines import PhysicsEngine
    from omnikin.viewer.live import LiveRobot

    live = LiveRobot(load_robot("tomasi-omni3"), PhysicsEngine())
    told: list[str] = []
    live.tell = told.append
    live.set_twist((0.2, 0.0, 0.0))
    for k in range(101):
        t = k * DT
        push(live.backend.sim, t)
        snapshot, _ = live.step(t)
    live.close()
    print(f"page: {live.fallen!r}; terminal: {told}")
    assert len(told) == 1 and told[0] == live.fallen
    assert "tipped over" in live.fallen and "wheels are stopped" in live.fallen
    assert "\n" not in live.fallen
    assert np.all(live.target == 0.0) and snapshot.command == (0.0, 0.0, 0.0)
    assert np.max(np.abs(live.backend.sim.wheel_speeds)) < 0.05


def test_a_tall_robot_falls_over_in_simulate_physics():
    from omnikin.motion.plans import line
    from omnikin.physics.run import simulate_physics

    robot = tall_robot()
    with pytest.raises(PhysicsError, match="tipped over at t = "):
        simulate_physics(line(0.5), robot, robot)


def test_a_study_trial_whose_robot_fell_is_a_row_with_that_reason_not_a_number(tmp_path):
    from omnikin.io.robot_file import save_robot
    from omnikin.sweep.points import Point, robot_hash
    from omnikin.sweep.trials import run_trials

    robot = tall_robot()
    save_robot(robot, tmp_path / "tall.yaml")
    point = Point(
        robot="tall.yaml",
        robot_hash=robot_hash(robot),
        scale=0.0,
        noise=None,
        calibrate=False,
        engine="physics",
        side=1.0,
        runs=1,
    )
    rows = run_trials(robot, point, seed=1, first=0, stop=1)
    print(rows["error"])
    assert rows["trial"] == [0]
    assert "tipped over" in rows["error"][0]
    assert math.isnan(rows["e_max_syst_before"][0]) and math.isnan(rows["reduction"][0])


def test_the_physics_umbmark_study_of_a_robot_that_falls_ends_saying_so():
    from omnikin.evaluation.physics_study import PHYSICS
    from omnikin.evaluation.procedure import umbmark_study

    robot = tall_robot()
    with pytest.raises(OmnikinError, match="tipped over"):
        umbmark_study(
            robot,
            robot,
            side=1.0,
            mode="rotate",
            runs=1,
            rate=100.0,
            trials=1,
            calibrate=False,
            seed=1,
            engine=PHYSICS,
        )
