"""Tracking in physics (MuJoCo: rollers, motors, contacts): every preset drives the figure-eight
and a square with blended corners at 80 % of the wheel limits, with its default controller, close
to the path (those that steer their wheels within a looser tolerance: the steering swings round
behind the corrections); the motors' own limits bound the reference."""

from __future__ import annotations

import pytest

from omnikin import load_robot
from omnikin.api.tracking import track
from omnikin.physics.engines import PhysicsEngine

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

SCALE = 0.8
TOLERANCE_RMS = 0.015
"""RMS distance to the path [m] every preset that does not steer keeps in physics (measured
0.2 to 11 mm, docs/control.md "Tracking in physics"): the slip of real rollers and contacts,
which the odometry the controllers steer by does not see."""
TOLERANCE_MAX = 0.05


@pytest.mark.parametrize("name", ["tomasi-omni3", "garcia-sillas-omni3", "diff-drive", "mecanum4", "omni4"])
@pytest.mark.parametrize("spec", ["figure8 1", "square 1 0.2"])
def test_a_preset_that_does_not_steer_tracks_the_path_in_physics(name, spec):
    done = track(name, spec, engine="physics", max_wheel_speed=12.0 * SCALE, max_wheel_accel=40.0 * SCALE)
    summary = done.summary()
    assert summary["rms_error_m"] < TOLERANCE_RMS, summary
    assert summary["max_error_m"] < TOLERANCE_MAX, summary
    assert summary["end_error_m"] < TOLERANCE_MAX, summary


STEERED_RMS = 0.04
"""RMS distance to the path [m] the presets that steer their wheels keep in physics on the paths
within their steering limits (measured 6 to 37 mm, docs/control.md): the steering servos swing
the wheels round behind the controller's corrections, which no controller here models."""
STEERED_MAX = 0.1


@pytest.mark.parametrize(
    ("name", "spec"), [("synchro", "figure8 1"), ("synchro", "square 1 0.2"), ("xr4000", "square 1 0.2")]
)
def test_a_preset_that_steers_its_wheels_tracks_the_path_in_physics_within_the_looser_tolerance(name, spec):
    done = track(name, spec, engine="physics", max_wheel_speed=12.0 * SCALE, max_wheel_accel=40.0 * SCALE)
    summary = done.summary()
    assert summary["rms_error_m"] < STEERED_RMS, summary
    assert summary["max_error_m"] < STEERED_MAX, summary


def test_the_motors_own_limits_bound_the_reference_in_physics():
    robot = load_robot("tomasi-omni3")
    motors = PhysicsEngine().motor_limits(robot)
    assert motors is not None and motors.speed < 100.0
    # asked for more than the motors give, the reference keeps to the motors
    done = track(robot, "circle 0.5", engine="physics", max_wheel_speed=1e3, max_wheel_accel=1e5)
    assert done.trajectory.limits.speed == pytest.approx(motors.speed)
    assert done.trajectory.limits.accel == pytest.approx(motors.accel)
