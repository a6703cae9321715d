"""A calibrated robot is the nominal robot with corrected kinematics: its physical fields (mass,
centre of mass, wheel width, rollers, ...) are not the calibration's business and carry over
unchanged, also into the robot file written for it."""

from __future__ import annotations

import math
from dataclasses import replace

from omnikin import load_robot
from omnikin.evaluation.calibration import borenstein_calibrate, least_squares_calibration, recommended_runs
from omnikin.evaluation.umbmark import simulate_umbmark
from omnikin.io.robot_file import parse_robot_text, robot_text
from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel
from omnikin.motion.plans import CalibrationRun
from omnikin.simulation.error_models import NOISE, NoiseModel, SystematicErrors, WheelErrors
from omnikin.simulation.kinematic import simulate_kinematic

BODY = PhysicalBody(mass=2.5, com=(0.0, 0.01, 0.06), height=0.02)


def with_physical(robot, wheel: PhysicalWheel):
    return replace(robot, wheels=tuple(replace(w, physical=wheel) for w in robot.wheels), physical=BODY)


def assert_kept(calibrated, nominal):
    assert calibrated.physical == nominal.physical == BODY
    assert [w.physical for w in calibrated.wheels] == [w.physical for w in nominal.wheels]
    again = parse_robot_text(robot_text(calibrated, "calibrated.yaml"), "calibrated.yaml")
    assert again.physical == BODY
    assert [w.physical for w in again.wheels] == [w.physical for w in nominal.wheels]


def test_least_squares_calibration_keeps_physical_fields():
    nominal = with_physical(load_robot("tomasi-omni3"), PhysicalWheel(width=0.03, rows=2, max_torque=0.4))
    true = SystematicErrors({"w1": WheelErrors(radius=0.01)}).apply(nominal)
    runs = []
    for label, plan in recommended_runs(nominal):
        sim = simulate_kinematic(
            plan, true, nominal, noise=NoiseModel(quantise=False), trials=1, rng=0, keep_truth=False
        )
        runs += [CalibrationRun(plan, tuple(m), label, (0.001, math.radians(0.2))) for m in sim.measured]
    result = least_squares_calibration(nominal, runs)
    assert result.robot.wheel("w1").radius != nominal.wheel("w1").radius  # it did calibrate
    assert_kept(result.robot, nominal)


def test_borenstein_correction_keeps_physical_fields():
    nominal = with_physical(load_robot("diff-drive"), PhysicalWheel(width=0.02, friction=0.9))
    true = SystematicErrors({"left": WheelErrors(radius=-0.002)}).apply(nominal)
    result = simulate_umbmark(true, nominal, noise=NOISE["none"], runs=1)[0]
    corrected = borenstein_calibrate(nominal, result)
    assert corrected.wheels != nominal.wheels  # it did correct
    assert_kept(corrected, nominal)
