"""Held-key teleop: presses set a component, releases clear it unless overridden, stop clears all."""

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.runtime.teleop import Teleop


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
