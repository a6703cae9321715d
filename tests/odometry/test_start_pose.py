"""Start poses of the odometry: checked like every other ordered input."""

from __future__ import annotations

import pytest

from omnikin.errors import InputError


def test_a_start_pose_given_as_a_set_names_the_pose_order_not_wheels():
    """A set iterates in hash order: refused, and the message says what order would be lost."""
    from omnikin import load_robot
    from omnikin.odometry.streaming import Odometry

    with pytest.raises(InputError, match="x, y, theta") as info:
        Odometry(load_robot("diff-drive"), start={0.0, 1.0, 2.0})
    assert "wheels" not in str(info.value)
