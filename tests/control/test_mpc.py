"""The model predictive controller: its correction is the optimum of its quadratic programme written
independently here (the errors kept as variables with the dynamics as equalities, not eliminated)
and solved by another solver (Clarabel, interior point); on a robot it never asks a wheel beyond
its speed or acceleration limit, even while it corrects slip; it drives a differential drive."""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.control import WheelLimits, circle, figure8, plan_trajectory
from omnikin.control.mpc import PoseMPC
from omnikin.errors import InputError
from omnikin.evaluation.tracking import track, tracking_errors
from omnikin.kinematics.se2 import compose, inverse, log
from omnikin.simulation.error_models import noise_profile
from support.mpc_reference import reference_correction

LIMITS = WheelLimits(speed=12.0, accel=40.0)


@pytest.mark.parametrize(
    ("name", "path", "t", "offset"),
    [
        ("tomasi-omni3", figure8(1.0), 3.0, (0.02, -0.01, 0.05)),  # at the limits, 2 cm off
        ("mecanum4", circle(0.5), 1.0, (-0.01, 0.03, -0.1)),
        ("diff-drive", circle(1.0, heading="tangent"), 2.0, (0.0, 0.02, 0.03)),
    ],
)
def test_the_correction_is_the_optimum_of_the_programme_written_independently(name, path, t, offset):
    robot = load_robot(name)
    trajectory = plan_trajectory(robot, path, LIMITS)
    controller = PoseMPC(robot, trajectory, rate=50)
    reference = trajectory.at(t)[0]
    pose = compose(reference, np.array(offset))
    last = log(compose(inverse(trajectory.at(t - 0.02)[0]), reference)) / 0.02  # the feedforward just before
    if robot.fixed:
        basis = np.asarray(robot.admissible_basis)
        last = basis @ (basis.T @ last)
    controller._last = last
    twist = controller.command(t, pose)
    xi0 = log(compose(inverse(reference), trajectory.at(t + 0.02)[0])) / 0.02
    basis = np.eye(3) if not robot.fixed else np.asarray(robot.admissible_basis)
    if robot.fixed:
        xi0 = basis @ (basis.T @ xi0)
    ours = basis.T @ (twist - xi0)
    theirs = reference_correction(controller, t, pose, last)
    assert ours == pytest.approx(theirs, abs=2e-4 * max(1.0, np.max(np.abs(theirs))))
    assert controller.fallbacks == 0


@pytest.mark.parametrize("noise", [None, "typical"])
def test_no_wheel_is_asked_beyond_its_speed_or_acceleration_limit(noise):
    robot = load_robot("tomasi-omni3")
    trajectory = plan_trajectory(robot, figure8(1.0), LIMITS)
    controller = PoseMPC(robot, trajectory, rate=50)
    model = None if noise is None else noise_profile(noise)
    run = track(robot, trajectory, controller, rate=50, noise=model, rng=3)
    asked = robot.ik(run.command).wheel_speeds
    assert np.max(np.abs(asked)) <= LIMITS.speed * (1 + 1e-6)
    # every change within A dt, to OSQP's tolerance (1e-6 of the constraint: 1e-5 rad/s is ten times that)
    assert np.max(np.abs(np.diff(asked, axis=0))) <= LIMITS.accel / 50 + 1e-5
    assert run.saturated == 0 and controller.fallbacks == 0
    errors = tracking_errors(run, trajectory)
    if noise is None:  # an exact model: on the path to far below a millimetre
        assert errors["max_error_m"] < 1e-5
    else:  # the slip is corrected (the controller sees the odometry), not left to grow
        assert errors["max_error_m"] < 0.01


def test_a_differential_drive_tracks_a_circle_along_its_tangent_without_moving_sideways():
    robot = load_robot("diff-drive")
    trajectory = plan_trajectory(robot, circle(1.0, heading="tangent"), LIMITS)
    run = track(robot, trajectory, PoseMPC(robot, trajectory, rate=50), rate=50)
    assert np.max(np.abs(run.command[:, 1])) < 1e-12  # no sideways twist asked
    assert tracking_errors(run, trajectory)["max_error_m"] < 1e-5


@pytest.mark.parametrize(
    ("name", "kwargs", "message"),
    [
        ("ackermann", {}, r"robot 'ackermann' steers its wheels"),
        ("tomasi-omni3", {"horizon": 0}, r"horizon must be a whole number of steps in \[1, 200\]"),
        ("tomasi-omni3", {"horizon": 2.5}, r"horizon must be a whole number"),
        ("tomasi-omni3", {"rate": -1}, r"rate must be in \(0, 10000\] Hz"),
    ],
)
def test_what_the_controller_cannot_do_is_refused_in_one_line(name, kwargs, message):
    robot = load_robot(name)
    trajectory = plan_trajectory(load_robot("tomasi-omni3"), circle(1.0), LIMITS)
    with pytest.raises(InputError, match=message):
        PoseMPC(robot, trajectory, **{"rate": 50, **kwargs})
