"""Held-key teleop: presses set a component, releases clear it unless overridden, stop clears all."""

import numpy as np
import pytest

from omnikin import PRESET_NAMES, load_robot
from omnikin.errors import InputError
from omnikin.runtime.teleop import MOVES, Teleop, moves_not_obeyed


def test_forward_and_turn_held_together_drive_an_arc_and_releasing_one_keeps_the_other():
    t = Teleop(speed=0.2, turn=0.5)
    assert t.press("forward") and t.press("turn_left")
    np.testing.assert_array_equal(t.target, [0.2, 0.0, 0.5])
    assert t.release("forward")
    np.testing.assert_array_equal(t.target, [0.0, 0.0, 0.5])


def test_a_release_does_not_clear_a_component_another_key_set_since():
    t = Teleop(speed=0.3, turn=1.0)
    t.press("left")
    t.press("right")  # the later key wins while both are held
    assert not t.release("left")
    np.testing.assert_array_equal(t.target, [0.0, -0.3, 0.0])
    assert t.release("right")
    np.testing.assert_array_equal(t.target, [0.0, 0.0, 0.0])


def test_stop_and_release_all_clear_every_component_and_other_actions_only_count():
    t = Teleop(speed=0.1, turn=0.2)
    t.press("back")
    t.press("turn_right")
    assert t.press("stop")
    np.testing.assert_array_equal(t.target, [0.0, 0.0, 0.0])
    t.press("forward")
    assert t.release_all() and not t.release_all()
    assert not t.press("camera_top")
    assert t.presses == {"back": 1, "turn_right": 1, "stop": 1, "forward": 1, "camera_top": 1}


@pytest.mark.parametrize("speed, turn", [(0.0, 1.0), (1.0, float("nan")), (-1.0, 1.0), (1.0, float("inf"))])
def test_speeds_that_are_not_positive_finite_numbers_are_refused(speed, turn):
    with pytest.raises(InputError, match="must be a positive number"):
        Teleop(speed, turn)


# --- moves a layout cannot obey ------------------------------------------------------------------------
EXPECTED_NOT_OBEYED = {
    # two fixed wheels on one axle cannot slide sideways (Campion et al. 1996: type (2,0))
    "diff-drive": {"left", "right"},
    # a car: fixed rear axle (no vy) and front steering limited to less than 90 deg, so a pure
    # rotation (instantaneous centre at the body origin, on the rear axle) cannot be steered
    "ackermann": {"left", "right", "turn_left", "turn_right"},
    # legs steer within limits that cannot point all three tangentially: no turn on the spot
    "villasenor-omni3": {"turn_left", "turn_right"},
}


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_the_moves_a_preset_cannot_obey_are_those_its_wheels_forbid(name):
    robot = load_robot(name)
    found = moves_not_obeyed(robot)
    assert set(found) == EXPECTED_NOT_OBEYED.get(name, set())
    for action, why in found.items():
        component = ("vx", "vy", "omega")[MOVES[action][0]]
        assert component in why and "\n" not in why and len(why) < 100


def test_the_sim_help_names_the_presets_whose_keys_are_not_obeyed():
    """``omnikin sim --help`` lists, for A/D and Q/E, exactly the presets that do not obey them."""
    from omnikin.cli.sim import EPILOG

    notes = " ".join(EPILOG.split("* not obeyed by every layout")[1].split("\n\n")[0].split())
    sideways, turning = notes.split("Q / E")
    for name in PRESET_NAMES:
        found = moves_not_obeyed(load_robot(name))
        assert (name in sideways.split("(presets:")[1].split(")")[0]) == ("left" in found), name
        assert (name in turning.split("(presets:")[1].split(")")[0]) == ("turn_left" in found), name
