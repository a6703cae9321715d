"""The physics back-end (omnikin.physics.backend.PhysicsBackend) as a drop-in for SimBackend:
the runtime drives it, its odometry follows the physics' ground truth."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics back-end needs MuJoCo (extra 'physics')")

from omnikin import Encoder, load_robot  # noqa: E402
from omnikin.errors import InputError  # noqa: E402
from omnikin.kinematics.se2 import wrap_angle  # noqa: E402
from omnikin.physics.backend import PhysicsBackend  # noqa: E402
from omnikin.runtime.base import BaseRuntime  # noqa: E402

DT = 0.02


@pytest.mark.parametrize(
    "name, twist, tolerance",
    [
        ("tomasi-omni3", (0.2, 0.1, 0.5), 0.005),
        # the car's wheels slip while the steering turns in at the start (the physics, not the model)
        ("ackermann", (0.4, 0.0, 0.3), 0.015),
    ],
)
def test_the_runtime_drives_the_physics_and_its_odometry_follows_the_truth(name, twist, tolerance):
    robot = load_robot(name)
    backend = PhysicsBackend(robot)
    assert all(callable(getattr(backend, m)) for m in ("write", "read", "stats", "close"))
    rt = BaseRuntime(robot, backend, cmd_vel_timeout=0.0)
    rt.command(twist, 0.0)
    for k in range(151):  # 3 s
        res = rt.step(k * DT)
    truth = backend.truth
    travelled = np.hypot(*truth[:2])
    assert travelled > 0.5
    error = np.hypot(*(np.array(rt.pose[:2]) - truth[:2]))
    assert error < tolerance * travelled  # odometry from the physics' encoders
    assert abs(wrap_angle(rt.pose[2] - truth[2])) < 0.01
    assert res.state.t == pytest.approx(3.0)
    stats = backend.stats()
    assert stats["backend"] == "physics" and stats["writes"] == stats["reads"] == 151
    assert stats["sim_time"] == pytest.approx(3.0)


def test_positions_are_whole_ticks_of_the_built_encoder_in_the_nominal_scale():
    robot = load_robot("tomasi-omni3")
    # as built, the encoders count twice as many ticks per turn as the file says
    true = replace(robot, wheels=tuple(replace(w, encoder=Encoder(1200)) for w in robot.wheels))
    backend = PhysicsBackend(robot, true)
    backend.read(0.0)
    backend.write(0.0, [3.0, 3.0, 3.0])
    state = backend.read(1.0)
    nominal = 2 * math.pi / 600
    ticks = state.positions / nominal
    assert ticks == pytest.approx(np.rint(ticks), abs=1e-9)
    # the driver's scale is the file's: it reads twice the true angle
    assert state.positions == pytest.approx(2 * backend.sim.wheel_angles, abs=nominal)
    assert state.velocities == pytest.approx(2 * backend.sim.wheel_speeds)
    unquantised = PhysicsBackend(robot, quantise=False)
    unquantised.read(0.0)
    unquantised.write(0.0, [3.0, 3.0, 3.0])
    assert unquantised.read(0.5).positions == pytest.approx(unquantised.sim.wheel_angles, abs=1e-15)


def test_a_robot_as_built_with_other_wheels_or_bad_commands_is_refused():
    robot = load_robot("tomasi-omni3")
    with pytest.raises(InputError, match="does not fit"):
        PhysicsBackend(robot, load_robot("omni4"))
    backend = PhysicsBackend(robot)
    with pytest.raises(InputError, match="expected 3 finite wheel speeds"):
        backend.write(0.0, [1.0, float("inf"), 0.0])


def test_real_time_mode_drops_what_it_cannot_catch_up_and_counts_it():
    robot = load_robot("tomasi-omni3")
    exact = PhysicsBackend(robot)
    exact.read(10.0)
    exact.read(11.0)
    assert exact.stats()["sim_time"] == pytest.approx(1.0) and exact.stats()["time_dropped"] == 0.0
    backend = PhysicsBackend(robot, max_lag=0.1)
    backend.read(10.0)  # starts the clock
    backend.read(10.05)  # within max_lag: caught up exactly
    assert backend.stats()["sim_time"] == pytest.approx(0.05)
    backend.read(11.05)  # one second late: 0.1 s simulated, 0.9 s dropped
    stats = backend.stats()
    assert stats["sim_time"] == pytest.approx(0.15)
    assert stats["time_dropped"] == pytest.approx(0.9) and stats["lag_events"] == 1
    backend.read(11.07)  # on time again: the simulation follows 0.9 s behind the caller
    assert backend.stats()["sim_time"] == pytest.approx(0.17) and backend.stats()["lag_events"] == 1
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(InputError, match="max_lag"):
            PhysicsBackend(robot, max_lag=bad)


def test_a_wheel_braked_beyond_its_motor_is_named_in_the_stats_for_the_time_it_was():
    """The ROS node's /diagnostics carry the back-end's stats: wheel w2 of tomasi-omni3, braked by
    an external torque of twice its motor's from t = 0.5 s to 1.5 s, cannot follow its set-point;
    unbraked, no wheel is named (docs/physics.md, "Runs that do not drive as commanded")."""
    import mujoco

    robot = load_robot("tomasi-omni3")
    stats = []
    for brake in (0.0, 2.0):
        backend = PhysicsBackend(robot)
        sim = backend.sim
        body = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, "w2:wheel")
        torque = next(w.motor.max_torque for w in sim.description.wheels if w.name == "w2")
        backend.read(0.0)
        backend.write(0.0, [0.0, -4.2, 4.2])
        backend.read(0.5)
        axle = sim.data.xmat[body].reshape(3, 3)[:, 1]  # the wheel joint turns about the body's y axis
        sim.data.xfrc_applied[body, 3:] = brake * torque * axle  # against w2's negative speed
        backend.read(1.5)
        stats.append(backend.stats()["wheels_lagging"])
    assert stats[0] == ""
    named = dict(item.rsplit(" ", 2)[:2] for item in stats[1].split(", "))
    assert 0.8 <= float(named["w2"]) <= 1.0, stats[1]
