"""What the documentation claims of batch and streaming odometry on the same samples
(``docs/conventions.md``, "Batch and streaming odometry agree"): the same wheel increments, body
increments and twists, to the bit without steerable wheels; poses to rounding; and within the
streaming estimator, the generated kernel and the general path to the bit alike."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import Odometry, batch_odometry, batch_odometry_from_angles, load_robot
from omnikin.odometry.streaming import _decline

PLAIN = ["tomasi-omni3", "diff-drive", "mecanum4", "omni4"]
STEERED = ["ackermann", "xr4000", "synchro"]


def log(robot, seed: int, n: int = 400):
    """Uneven timestamps, wandering wheel speeds, and (steerable robots) slowly turning wheels."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.005, 0.02, n))
    ticks = np.cumsum(rng.integers(-3, 9, (n, len(robot.encoded))), axis=0)
    steer = None
    if robot.steerable:
        lower, upper = robot.steer_limits
        walk = np.cumsum(rng.normal(0.0, 0.01, (n, len(robot.steerable))), axis=0)
        steer = np.clip(walk, np.maximum(lower, -3.0), np.minimum(upper, 3.0))
    return t, ticks, steer


def stream(robot, t, values, steer, angles: bool, general: bool = False):
    """Poses, body increments and twists of the streaming estimator, sample by sample."""
    o = Odometry(robot, max_wheel_accel=math.inf)
    if general:
        o._step_ticks = o._step_angles = _decline
    poses, increments, twists, residuals = [], [], [], []
    for k in range(len(t)):
        feed = o.update_angles if angles else o.update
        poses.append(feed(float(t[k]), values[k].tolist(), None if steer is None else steer[k]))
        if k:
            increments.append(o._increment())
            twists.append(o.twist)
            residuals.append(o.residual)
    return np.array(poses), np.array(increments), np.array(twists), np.array(residuals)


def batch(robot, t, values, steer, angles: bool):
    f = batch_odometry_from_angles if angles else batch_odometry
    return f(robot, t, values, steer=steer, max_wheel_accel=math.inf)


@pytest.mark.parametrize("angles", [False, True])
@pytest.mark.parametrize("name", PLAIN)
def test_without_steering_increments_and_twists_agree_to_the_bit(name, angles):
    robot = load_robot(name)
    t, ticks, _ = log(robot, 7)
    values = ticks * 0.003 if angles else ticks
    poses, increments, twists, residuals = stream(robot, t, values, None, angles)
    b = batch(robot, t, values, None, angles)
    assert np.array_equal(increments, b.increments)
    assert np.array_equal(twists, b.twists)
    assert np.allclose(poses, b.poses, rtol=0.0, atol=1e-13)
    assert np.allclose(residuals, b.residual, rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("name", STEERED)
def test_with_steering_increments_agree_to_rounding(name):
    robot = load_robot(name)
    t, ticks, steer = log(robot, 11)
    poses, increments, twists, _ = stream(robot, t, ticks, steer, False)
    b = batch(robot, t, ticks, steer, False)
    assert np.allclose(increments, b.increments, rtol=1e-14, atol=1e-17)
    assert np.allclose(twists, b.twists, rtol=1e-14, atol=1e-15)
    assert np.allclose(poses, b.poses, rtol=0.0, atol=1e-13)


@pytest.mark.parametrize("angles", [False, True])
@pytest.mark.parametrize("name", PLAIN)
def test_the_kernel_and_the_general_path_agree_to_the_bit(name, angles):
    robot = load_robot(name)
    t, ticks, _ = log(robot, 3)
    values = ticks * 0.003 if angles else ticks
    fast = stream(robot, t, values, None, angles)
    general = stream(robot, t, values, None, angles, general=True)
    for a, b in zip(fast, general, strict=True):
        assert np.array_equal(a, b)
