"""Command filter: halt keeps the acceleration limit, replaced limits apply at once.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import pytest

from omnikin import (
    load_robot,
)


def test_halt_then_command_keeps_the_acceleration_limit():
    """After halt() (link re-armed after an outage) a command must ramp up from rest at the
    acceleration limit, not jump across the outage as one long time step."""
    from omnikin.motion.limits import MotionLimits
    from omnikin.runtime.command import CommandFilter

    f = CommandFilter(load_robot("tomasi-omni3"), MotionLimits(linear=1.0, linear_accel=0.5), timeout=0.0)
    f.command((0.2, 0.0, 0.0), 0.0)
    for k in range(1, 100):
        f.update(0.01 * k)  # up to speed
    f.halt()  # the link was lost at t = 0.99 and re-armed at 2.0
    f.command((0.2, 0.0, 0.0), 2.0)
    first = f.update(2.0)
    second = f.update(2.01)
    assert first[0] == 0.0
    assert second[0] == pytest.approx(0.5 * 0.01, abs=1e-12)  # a_max * dt, from rest


def test_replaced_limits_apply_to_the_current_command():
    from dataclasses import replace

    from omnikin.motion.limits import MotionLimits
    from omnikin.runtime.command import CommandFilter

    f = CommandFilter(load_robot("tomasi-omni3"), MotionLimits(linear=1.0, linear_accel=None), timeout=0.0)
    f.command((0.8, 0.0, 0.0), 0.0)
    assert f.update(0.0)[0] == pytest.approx(0.8)
    f.limits = replace(f.limits, linear=0.3)
    assert f.update(0.01)[0] == pytest.approx(0.3)
