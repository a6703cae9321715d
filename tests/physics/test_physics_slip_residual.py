"""The slip indicator, tested with real slip: the forward-kinematics residual of the streaming
odometry (from the encoder readings only) of an over-constrained base driven in MuJoCo.

omni4 has four omni wheels for three body motions, so the four wheel speeds must agree on one
twist; the residual ``(dtheta - A xi) / dt`` [rad/s] is their disagreement over a sampling
interval. Closed forms, from the layout alone (wheel ``i`` at ``p_i`` with drive direction
``u_i`` at 45 deg to the diagonals, all at the same distance ``d``, radius ``r``):

- the wheels' rows ``(u_i, d) / r`` have the left null vector ``n = (1, -1, 1, -1)``, so the
  residual is ``n (n . s) / |n|^2`` of the wheels' slip rates ``s`` [rad/s]: always along ``n``,
  the same pattern whichever wheel slips (one redundant direction cannot name a wheel);
- quantisation: each reading is the angle rounded to a tick ``q = 2 pi / 2048``, each
  increment is off by less than ``q``, so without slip ``|residual| <= q |n|_1 / |n|_2 / dt =
  2 q / dt`` (0.123 rad/s at 20 Hz);
- true slip of a wheel: its measured angle minus the angle it would roll through under the true
  body motion, ``u_i . (v + omega z x p_i) / r`` integrated (for a constant twist over an
  interval, ``(u_i, d) . log(increment) / r``). Slip the same body motion explains on every
  wheel (``s`` in the rows' column space: the contacts creeping together) has no component along
  ``n`` and is invisible to the residual.

The slipping wheel: ``physical.friction`` 0.02 (wet ice) on ``w1``; its motor's torque limit is then
the torque at which it slips (the description's default ``mu N r``), so it cannot follow the
commanded ramp (the motors' ramp is the one derived for the dry floor: the robot was built for
it; the ice is under w1 only) and the other three drag the robot on while it turns too slowly. The ramp of the
commanded twist is 1 m/s^2 to 0.5 m/s (the runtime's acceleration limit would give it).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.kinematics.physical import PhysicalWheel  # noqa: E402
from omnikin.kinematics.se2 import between, log  # noqa: E402
from omnikin.odometry.streaming import Odometry  # noqa: E402
from omnikin.physics.description import describe  # noqa: E402
from omnikin.physics.simulator import PhysicsSim  # noqa: E402

DT = 0.05  # encoder sampling interval [s]
ACCEL, SPEED = 1.0, 0.5  # commanded ramp [m/s^2] and cruise [m/s], forward
TICKS = 2048  # omni4's encoders, ticks per wheel turn (gear ratio 1)
NULL = np.array([1.0, -1.0, 1.0, -1.0])
QUANTISATION = 2.0 * math.pi / TICKS * np.abs(NULL).sum() / np.linalg.norm(NULL) / DT


def wheel_rows(robot) -> np.ndarray:
    """Rolling rows ``(u_x, u_y, p x u) / r`` of the wheels: wheel speed = row . body twist."""
    rows = []
    for w in robot.wheels:
        ux, uy = math.cos(w.drive), math.sin(w.drive)
        rows.append(np.array([ux, uy, w.x * uy - w.y * ux]) / w.radius)
    return np.array(rows)


def drive(robot, description=None):
    """Ramp up to SPEED, cruise, ramp down; per interval the odometry residual and the true slip
    of every wheel [rad/s], and the odometry's and the truth's final poses."""
    sim = PhysicsSim(robot, description=description)
    odometry = Odometry(robot)
    rows = wheel_rows(robot)
    odometry.update(0.0, sim.encoder_ticks())
    pose, angles = sim.pose, sim.wheel_angles.copy()
    residual, slip = [], []
    for k in range(1, round(2.0 / DT) + 1):
        t = k * DT
        speed = min(ACCEL * t, SPEED, max(0.0, ACCEL * (1.6 - t)))
        sim.command(robot.ik((speed, 0.0, 0.0)).wheel_speeds)
        sim.advance(t)
        odometry.update(t, sim.encoder_ticks())
        residual.append(odometry.residual)
        new_pose, new_angles = sim.pose, sim.wheel_angles.copy()
        slip.append((new_angles - angles - rows @ log(between(pose, new_pose))) / DT)
        pose, angles = new_pose, new_angles
    return np.array(residual), np.array(slip), np.array(odometry.pose), sim.pose


def test_the_layouts_null_vector_is_the_closed_form():
    rows = wheel_rows(load_robot("omni4"))
    assert NULL @ rows == pytest.approx(np.zeros(3), abs=1e-12)


def test_without_slip_the_residual_stays_within_encoder_quantisation():
    robot = load_robot("omni4")
    residual, slip, odo, truth = drive(robot)
    worst = np.linalg.norm(residual, axis=1).max()
    print(f"no slip: largest residual {worst:.4f} rad/s, quantisation bound {QUANTISATION:.4f} rad/s")
    assert worst <= QUANTISATION * (1 + 1e-9)
    # the truth agrees: what slip there is (the soft contacts creep under the traction of the
    # first ramp step, up to 0.35 rad/s) is the same body motion on every wheel, none along n
    differential = np.abs(slip @ NULL).max() / np.linalg.norm(NULL)
    print(f"no slip: common creep up to {np.abs(slip).max():.3f} rad/s, differential {differential:.2e} rad/s")
    assert differential < 0.01
    assert np.hypot(*(odo[:2] - truth[:2])) < 1e-3 and abs(odo[2] - truth[2]) < 1e-3


def test_a_wheel_slipping_on_ice_shows_in_the_residual_along_the_null_vector():
    robot = load_robot("omni4")
    ice = replace(robot.wheels[0], physical=PhysicalWheel(friction=0.02))
    on_ice = describe(replace(robot, wheels=(ice, *robot.wheels[1:])))
    # the robot is built for the floor (its ramp from the nominal friction); w1 meets the ice and
    # its motor tops out at a tenth of the cruise speed, so it holds back while the others drag it on
    built = describe(robot)
    cruise = abs(robot.ik((SPEED, 0.0, 0.0)).wheel_speeds[0])
    motor = replace(on_ice.wheels[0].motor, max_accel=built.wheels[0].motor.max_accel, max_speed=cruise / 10)
    wheels = (replace(on_ice.wheels[0], motor=motor), *on_ice.wheels[1:])
    residual, slip, odo, truth = drive(robot, replace(on_ice, wheels=wheels))
    norms = np.linalg.norm(residual, axis=1)
    worst = int(norms.argmax())
    print(
        f"w1 on ice: largest residual {norms[worst]:.3f} rad/s ({norms[worst] / QUANTISATION:.0f} x the "
        f"quantisation bound) at t = {(worst + 1) * DT:.2f} s; true slip rates {np.round(slip[worst], 3)} rad/s; "
        f"odometry off the truth by {np.hypot(*(odo[:2] - truth[:2])) * 1e3:.1f} mm, "
        f"{abs(odo[2] - truth[2]):.4f} rad"
    )
    assert norms[worst] > 3 * QUANTISATION
    # real slip, of w1: the truth says so; the other wheels roll
    assert np.abs(slip[:, 0]).max() > 0.5
    assert np.abs(slip[:, 1:]).max() < 0.2 * np.abs(slip[:, 0]).max()
    # the residual is the projection of the true slip on the null vector, up to quantisation
    expected = np.outer(slip @ NULL, NULL) / (NULL @ NULL)
    assert np.abs(residual - expected).max() <= QUANTISATION
    # and always along the null vector: the same pattern whichever wheel slips
    direction = residual[worst] / norms[worst]
    assert abs(direction @ NULL) / np.linalg.norm(NULL) == pytest.approx(1.0, abs=1e-9)
    # what the indicator is for: the odometry drifts from the truth while it is raised
    assert abs(odo[2] - truth[2]) > 0.02
