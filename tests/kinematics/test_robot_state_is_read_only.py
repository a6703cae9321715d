"""A robot's cached state cannot be changed through the arrays it hands out.

Robot.steer_limits, jacobian() and fk_matrix() hand out arrays that are read-only for good
(their data in immutable bytes: omnikin.common.arrays.frozen; ``setflags(write=True)`` cannot
make them writeable, as it could an array owning its data), or fresh copies where a robot
computes them anew (steered robots): writing one never changes a later result of the robot.
Expected results come from a second robot loaded from the same file, which nothing touched.
"""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import PRESET_NAMES, load_robot


def handed_out(robot) -> dict:
    """Every array a robot hands out, by name."""
    lower, upper = robot.steer_limits
    config = robot.generic_configuration
    return {
        "steer_limits[0]": lower,
        "steer_limits[1]": upper,
        "jacobian()": robot.jacobian(),
        "ik_matrix": robot.ik_matrix,
        "fk_matrix()": robot.fk_matrix(),
        "fk_matrix(wheels)": robot.fk_matrix(wheels=robot.rolling_names[:2])
        if not robot.steerable
        else robot.fk_matrix(),
        "admissible_basis": robot.admissible_basis,
        "fixed_constraints": robot.fixed_constraints,
        "generic_configuration.constraints": config.constraints,
        "generic_configuration.admissible": config.admissible,
        "generic_configuration.twist": config.twist,
    }


def results(robot) -> dict:
    twist = np.array([0.2, 0.1, 0.3]) if robot.mobility.holonomic else np.array([0.2, 0.0, 0.0])
    steer = np.zeros(len(robot.steerable))
    speeds = robot.ik(twist, on_infeasible="return").wheel_speeds
    return {
        "ik": speeds,
        "fk": robot.fk(speeds, steer if robot.steerable else None).twist,
        "jacobian": np.array(robot.jacobian(steer if robot.steerable else None)),
        "fk_matrix": np.array(robot.fk_matrix(steer if robot.steerable else None)),
        "steer_limits": np.array(robot.steer_limits),
        "rank": robot.mobility.rank,
        "condition": robot.mobility.condition_number,
    }


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_no_array_a_robot_hands_out_can_change_its_results(name):
    robot, untouched = load_robot(name), load_robot(name)
    for array in handed_out(robot).values():
        for target in (array, array.base, array.view()):
            if not isinstance(target, np.ndarray):
                continue
            try:
                target.setflags(write=True)
                target[...] = np.nan  # a fresh copy: the caller's to change
            except ValueError:
                pass
    after, expected = results(robot), results(untouched)
    for key, value in expected.items():
        np.testing.assert_array_equal(after[key], value, err_msg=f"{name}: {key}")


@pytest.mark.parametrize("name", ["tomasi-omni3", "omni4", "mecanum4", "diff-drive"])
def test_the_cached_matrices_of_an_unsteered_robot_cannot_be_made_writeable(name):
    """Without steering the matrices are built once and handed out each time: the very arrays
    the robot keeps, so making them writeable must fail, on them, their base and their views."""
    robot = load_robot(name)
    assert robot.jacobian() is robot.jacobian() and robot.fk_matrix() is robot.fk_matrix()
    for label, array in handed_out(robot).items():
        for target in (array, array.base, array.view()):
            if isinstance(target, np.ndarray):
                with pytest.raises(ValueError):
                    target.setflags(write=True)
                assert not target.flags.writeable, label


def test_steering_limits_cannot_be_made_writeable():
    """ackermann's front wheels steer within +-35 deg: the limits stay so."""
    robot = load_robot("ackermann")
    lower, upper = robot.steer_limits
    for array in (lower, upper):
        with pytest.raises(ValueError):
            array.setflags(write=True)
        with pytest.raises(ValueError):
            array.base.setflags(write=True)
    np.testing.assert_allclose(np.degrees(robot.steer_limits), [[-35, -35], [35, 35]], rtol=1e-12)


def test_a_copy_of_a_robot_keeps_its_arrays_read_only():
    import copy
    import pickle

    robot = load_robot("omni4")
    robot.fk_matrix(), robot.jacobian()
    for clone in (copy.deepcopy(robot), pickle.loads(pickle.dumps(robot))):
        with pytest.raises(ValueError):
            clone.jacobian().setflags(write=True)
        with pytest.raises(ValueError):
            clone.fk_matrix().setflags(write=True)
