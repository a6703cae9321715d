"""One trial of a tolerance study: exact where the answer is known, repeatable, and a calibration
that removes most of a robot's systematic error."""

import math

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.evaluation.tolerance_trial import TrialSettings, tolerance_trial
from omnikin.io.robot_file import load_robot
from omnikin.simulation.error_models import NOISE, PROFILES, ErrorProfile

EXACT = TrialSettings(side=1.0, runs=2, noise=NOISE["none"])


def test_a_robot_built_exactly_and_driven_without_random_errors_returns_to_its_start():
    """A perfect robot commanded by its own model drives the exact square and its odometry is
    exact: every return error is zero, before and after its (trivial) calibration."""
    result = tolerance_trial(load_robot("tomasi-omni3"), ErrorProfile(), EXACT, np.random.SeedSequence(3))
    for value in result.as_dict().values():
        assert abs(value) < 1e-9


def test_the_same_seed_gives_the_same_trial_and_another_seed_another_robot():
    robot = load_robot("tomasi-omni3")
    settings = TrialSettings(side=1.0, runs=2)
    a = tolerance_trial(robot, PROFILES["typical"], settings, np.random.SeedSequence(7, spawn_key=(4, 1)))
    b = tolerance_trial(robot, PROFILES["typical"], settings, np.random.SeedSequence(7, spawn_key=(4, 1)))
    c = tolerance_trial(robot, PROFILES["typical"], settings, np.random.SeedSequence(7, spawn_key=(4, 2)))
    assert a == b
    assert a.systematic_before != c.systematic_before


@pytest.mark.parametrize("name", ["tomasi-omni3", "omni4", "mecanum4"])
def test_calibration_removes_most_of_the_systematic_error_of_a_robot_built_within_typical_tolerances(name):
    robot = load_robot(name)
    for k in range(3):
        result = tolerance_trial(robot, PROFILES["typical"], EXACT, np.random.SeedSequence(11, spawn_key=(k,)))
        assert result.systematic_before > 1e-3
        assert result.systematic_after < 0.1 * result.systematic_before


def test_without_calibration_the_after_values_are_not_numbers():
    settings = TrialSettings(side=1.0, runs=2, calibrate=False)
    result = tolerance_trial(load_robot("omni4"), PROFILES["typical"], settings, np.random.SeedSequence(1))
    assert result.e_max_syst_before > 0
    assert math.isnan(result.e_max_syst_after) and math.isnan(result.systematic_after) and math.isnan(result.reduction)


@pytest.mark.parametrize("kw", [{"runs": 0}, {"side": -1.0}, {"rate": 0.0}])
def test_settings_out_of_range_are_refused(kw):
    with pytest.raises(InputError):
        TrialSettings(**kw)
