"""One robot as built, two engines: a stepper turns its wheel as commanded and its encoder only
measures, a dc motor's speed loop turns its wheel so that the *counts* follow the command
(docs/conventions.md, "Motors"). The kinematic engine (:func:`omnikin.simulate`) and the physics
engine (:func:`omnikin.physics.run.simulate_physics`) drive the same robot as built through the
same plan; truth and odometry agree between the engines and with the closed form.

Closed form, tomasi-omni3 on ``line 1`` (1 m along +x), nominal Jacobian ``J`` (``omega = J xi``),
the plan's body displacement ``xi = (1, 0, 0)``. Every wheel's set-points are proportional to
the same profile (the ramps move them along one line in wheel-speed space), so each robot moves
with one constant body twist direction and ends at the constant-twist pose of its total:

* encoder scale error ``s`` on wheel w2 (its encoder counts ``(1 + s)`` times the ticks per
  revolution the file says), ``S = diag(1, 1 + s, 1)``:
  stepper: truth ``xi``, odometry ``J^-1 S J xi`` (the counts of w2 read ``1 + s`` times its turn);
  dc: odometry ``xi`` (the counts follow the command), truth ``J^-1 S^-1 J xi``;
* radius error ``e`` on w2, either motor: the wheels turn ``J xi``, the odometry is ``xi``,
  the truth ``J_true^-1 J xi`` (``J_true``: w2's row over ``r (1 + e)``).

Tolerances: the physics' validation bound (docs/physics.md: twists within 0.5 % of the kinematics,
tomasi-omni3 0.04 %): 2 mm and 2 mrad on the 1 m line; between the engines the same. The errors
are large (5 %) so that the two motor models' answers lie 10 tolerances apart or more.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.kinematics.se2 import wrap_angle  # noqa: E402
from omnikin.motion.plans import line  # noqa: E402
from omnikin.physics.run import simulate_physics  # noqa: E402
from omnikin.simulation.error_models import NoiseModel, SystematicErrors, WheelErrors  # noqa: E402
from omnikin.simulation.kinematic import simulate_kinematic  # noqa: E402
from support.kinematics import constant_twist_pose  # noqa: E402

ERROR = 0.05
TOL_XY = 0.002
TOL_TH = 0.002
XI = np.array([1.0, 0.0, 0.0])


def with_motor(robot, motor: str):
    return replace(robot, wheels=tuple(replace(w, motor=motor) for w in robot.wheels))


def assert_pose(got, expected, what):
    got, expected = np.asarray(got, dtype=float), np.asarray(expected, dtype=float)
    assert np.hypot(*(got[:2] - expected[:2])) < TOL_XY, (what, got, expected)
    assert abs(wrap_angle(got[2] - expected[2])) < TOL_TH, (what, got, expected)


def closed_form(nominal, true, motor: str, error: str) -> tuple[np.ndarray, np.ndarray]:
    """(truth, odometry) end poses of the module docstring."""
    j = nominal.jacobian()
    scale = np.diag([1.0, 1.0 + ERROR, 1.0])
    if error == "radius":
        truth = np.linalg.solve(true.jacobian(), j @ XI)
        return constant_twist_pose(truth, 1.0), constant_twist_pose(XI, 1.0)
    if motor == "stepper":
        return constant_twist_pose(XI, 1.0), constant_twist_pose(np.linalg.solve(j, scale @ j @ XI), 1.0)
    return constant_twist_pose(np.linalg.solve(j, np.linalg.solve(scale, j @ XI)), 1.0), constant_twist_pose(XI, 1.0)


@pytest.mark.parametrize("error", ["ticks", "radius"])
@pytest.mark.parametrize("motor", ["stepper", "dc"])
def test_a_robot_as_built_drives_alike_in_both_engines_as_its_motors_turn_its_wheels(motor, error):
    nominal = with_motor(load_robot("tomasi-omni3"), motor)
    true = SystematicErrors({"w2": WheelErrors(**{error: ERROR})}).apply(nominal)
    truth, odometry = closed_form(nominal, true, motor, error)
    plan = line(1.0)
    kinematic = simulate_kinematic(plan, true, nominal, noise=NoiseModel())  # whole ticks, as the physics counts
    physics = simulate_physics(plan, true, nominal)
    print(
        f"{motor}, {error} error: closed form truth {truth}, odometry {odometry}; kinematic truth "
        f"{kinematic.truth[0, -1]}, odometry {kinematic.odometry[-1]}; physics truth {physics.truth[0, -1]}, "
        f"odometry {physics.odometry[-1]}; problems {physics.problems()}"
    )
    assert not physics.problems()
    for engine, run in (("kinematic", kinematic), ("physics", physics)):
        assert_pose(run.truth[0, -1], truth, f"{engine} truth")
        assert_pose(run.odometry[-1], odometry, f"{engine} odometry")
    assert_pose(physics.truth[0, -1], kinematic.truth[0, -1], "truth, physics against kinematic")
    assert_pose(physics.odometry[-1], kinematic.odometry[-1], "odometry, physics against kinematic")
    # the test can fail: the other motor's answer lies far off
    other_truth, other_odometry = closed_form(nominal, true, "dc" if motor == "stepper" else "stepper", error)
    if error == "ticks":
        assert np.hypot(*(other_truth[:2] - truth[:2])) > 10 * TOL_XY
        assert np.hypot(*(other_odometry[:2] - odometry[:2])) > 10 * TOL_XY
    else:  # a radius error moves the truth whatever the motor, far beyond the tolerance
        assert np.hypot(*(truth[:2] - odometry[:2])) > 10 * TOL_XY


def test_a_dc_motor_counts_by_the_scale_its_controller_was_told():
    """The physics engine's dc wheel turns ``rpt_true / rpt_told`` times the commanded speed (the
    counts of its encoder as built follow the command over the nominal scale); a stepper's 1."""
    from omnikin.physics.simulator import PhysicsSim

    for motor, expected in (("dc", 1.0 / (1.0 + ERROR)), ("stepper", 1.0)):
        nominal = with_motor(load_robot("tomasi-omni3"), motor)
        true = SystematicErrors({"w2": WheelErrors(ticks=ERROR)}).apply(nominal)
        sim = PhysicsSim(true)
        np.testing.assert_allclose(sim.loop_turn, [1.0, expected, 1.0], rtol=1e-12)


@pytest.mark.parametrize("motor", ["stepper", "dc"])
def test_the_runtime_back_ends_turn_the_wheels_by_their_motors_alike(motor):
    """The runtime's back-ends (``--backend sim`` and ``--backend physics`` of the ROS node, the
    viewer's engines): the robot as built with the 5 % encoder scale error on w2 is commanded the
    wheel speeds ``J (0.5, 0, 0)`` for 1 s, then zero, and read at 2 s. Closed form (module
    docstring, ``xi`` = 0.5 m along x): stepper: truth ``xi``, readings ``S J xi``; dc: readings
    ``J xi``, truth ``J^-1 S^-1 J xi``. The readings are the true encoders' counts converted with
    the nominal scale, as a driver converts them. The physics' ramps lag and lead by the same angle."""
    from omnikin.physics.backend import PhysicsBackend
    from omnikin.simulation.backend import SimBackend

    nominal = with_motor(load_robot("tomasi-omni3"), motor)
    true = SystematicErrors({"w2": WheelErrors(ticks=ERROR)}).apply(nominal)
    j = nominal.jacobian()
    xi = 0.5 * XI
    scale = np.diag([1.0, 1.0 + ERROR, 1.0])
    if motor == "stepper":
        truth, readings = constant_twist_pose(xi, 1.0), scale @ j @ xi
    else:
        truth, readings = constant_twist_pose(np.linalg.solve(j, np.linalg.solve(scale, j @ xi)), 1.0), j @ xi
    for backend in (SimBackend(nominal, true, NoiseModel(quantise=False)), PhysicsBackend(nominal, true)):
        backend.write(0.0, j @ xi)
        backend.write(1.0, np.zeros(3))
        state = backend.read(2.0)
        name = type(backend).__name__
        print(f"{motor}, {name}: truth {backend.truth}, readings {state.positions}; expected {truth}, {readings}")
        assert_pose(backend.truth, truth, f"{name} truth")
        tick = 2 * np.pi / 600 if name == "PhysicsBackend" else 1e-12  # the physics counts whole ticks
        np.testing.assert_allclose(state.positions, readings, atol=tick + 0.002 / 0.04125)
