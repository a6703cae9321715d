"""A value refused for lying outside a range is printed so that it visibly lies outside it.

``:g`` (6 significant digits) printed 4.9999999999 as 5 against ``[5, 10000]``, 0.000999999999 as
0.001 against ``[0.001, 10]``: the message contradicted itself. Each test reads the numbers back
from the message and checks them against the printed bounds (and the true ones), so the
expectation is the arithmetic, not the message text of the code under test.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import omnikin
from omnikin import InputError, RobotFileError, load_robot
from omnikin.common.messages import digits_apart
from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel
from omnikin.kinematics.robot import heading_array
from omnikin.kinematics.se2 import MAX_ANGLE
from omnikin.kinematics.wheels import Steer
from omnikin.motion.limits import MotionLimits
from omnikin.odometry.integration import check_start_pose
from omnikin.runtime.command import CommandFilter

RANGE = re.compile(r"must lie in \[(\S+), (\S+)\](?: [^,]*)?, got (\S+)$")


def refused(call) -> str:
    with pytest.raises(InputError) as info:
        call()
    text = str(info.value)
    assert "\n" not in text, text
    return text


def assert_printed_outside(text: str, value: float, low: float, high: float) -> None:
    """The printed value lies outside the printed range, on the side the true value lies."""
    m = RANGE.search(text)
    assert m, text
    shown_low, shown_high, shown = (float(g) for g in m.groups())
    assert (shown_low, shown_high) == (pytest.approx(low, rel=1e-9), pytest.approx(high, rel=1e-9)), text
    if value < low:
        assert shown < shown_low and shown < low, text
    else:
        assert shown > shown_high and shown > high, text


@pytest.mark.parametrize(
    "field, value, low, high",
    [
        ("friction", 0.000999999999, 1e-3, 10.0),
        ("mass", 100000.0000001, 1e-4, 1e5),
        ("width", np.float32(1e-4), 1e-4, 10.0),  # 9.9999997e-05 as a double
        ("max_torque", 1e5 * (1 + 1e-15), 1e-5, 1e5),
    ],
)
def test_physical_fields_just_outside_their_range_print_outside_it(field, value, low, high):
    text = refused(lambda: PhysicalWheel(**{field: value}))
    assert text.startswith(f"wheel: physical.{field} must lie in ["), text
    assert_printed_outside(text, float(value), low, high)


def test_a_centre_of_mass_just_below_the_floor_bound_prints_below_it():
    text = refused(lambda: PhysicalBody(com=(0.0, 0.0, 0.99999999e-4)))
    assert_printed_outside(text, 0.99999999e-4, 1e-4, 1e3)


def test_a_sample_rate_just_below_the_range_prints_below_it():
    text = refused(lambda: omnikin.simulate("tomasi-omni3", rate=4.9999999999))
    assert text.startswith("rate: the sample rate must lie in [5, 10000] Hz, got "), text
    assert_printed_outside(text, 4.9999999999, 5.0, 1e4)


def test_a_sample_rate_too_large_for_a_float_is_refused_in_words_that_read():
    text = refused(lambda: omnikin.simulate("tomasi-omni3", rate=10**400))
    assert text.startswith("rate: the sample rate must lie in [5, 10000] Hz, got 1000"), text
    assert len(text) < 200, text


def test_a_steering_limit_just_beyond_pi_prints_beyond_it():
    text = refused(lambda: Steer(0.0, -1.0, 3.1415926536))
    assert text.startswith("steer: upper must lie in ["), text
    assert_printed_outside(text, 3.1415926536, -math.pi, math.pi)


def test_steering_limits_in_the_wrong_order_print_apart():
    text = refused(lambda: Steer(0.0, 1.0000001, 1.0))
    lower, upper = (float(v) for v in re.search(r"got (\S+) and (\S+) rad$", text).groups())
    assert lower > upper, text


def test_robot_file_fields_just_outside_their_range_print_outside_it(tmp_path):
    path = tmp_path / "robot.yaml"
    wheel = "{name: %s, type: omni, distance: 0.1, angle_deg: %s, radius: 0.05%s}"
    path.write_text(
        "omnikin: 1\nname: r\nwheels:\n"
        f"  - {wheel % ('a', 0, ', physical: {friction: 0.000999999999}')}\n"
        f"  - {wheel % ('b', 120, '')}\n  - {wheel % ('c', 240, '')}\n"
    )
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    text = str(info.value)
    assert "field 'physical.friction': must lie in [" in text, text
    assert_printed_outside(text, 0.000999999999, 1e-3, 10.0)
    steer = "{offset: 0.0, min_deg: 10.0000001, max_deg: 10}"
    path.write_text(
        "omnikin: 1\nname: r\nwheels:\n"
        f"  - {{name: s, type: steerable, x: 0.2, y: 0, drive_deg: 0, radius: 0.05, steer: {steer}}}\n"
        "  - {name: l, type: standard, x: 0, y: 0.2, drive_deg: 0, radius: 0.05}\n"
        "  - {name: r, type: standard, x: 0, y: -0.2, drive_deg: 0, radius: 0.05}\n"
    )
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    low, high = (float(v) for v in re.search(r"got (\S+) and (\S+)$", str(info.value)).groups())
    assert low > high, str(info.value)


def test_a_heading_just_beyond_the_bound_prints_beyond_it():
    heading = MAX_ANGLE * (1 + 1e-12)
    text = refused(lambda: heading_array(heading))
    shown = float(re.search(r"heading: (\S+) rad is beyond \+-(\S+) rad", text).group(1))
    assert shown > MAX_ANGLE, text


def test_a_steering_angle_just_beyond_its_limit_prints_beyond_it():
    ackermann = load_robot("ackermann")  # front wheels steer within -35 .. 35 deg
    angle = math.radians(35.0) + 2e-9  # beyond the limit and its round-off slack of 1e-9 rad
    text = refused(lambda: ackermann.jacobian([angle, 0.0]))
    m = re.search(r"steered to \S+ rad \((\S+) deg\), outside its limits \[(\S+), (\S+)\] deg", text)
    assert m, text
    shown, low, high = (float(g) for g in m.groups())
    assert shown > high and high == pytest.approx(35.0), text


def test_a_start_pose_just_beyond_the_bound_prints_beyond_it():
    text = refused(lambda: check_start_pose([0.0, 0.0, MAX_ANGLE * (1 + 1e-12)]))
    m = re.search(r"theta = (\S+) rad is not a finite number within \+-(\S+) rad", text)
    assert m and float(m.group(1)) > float(m.group(2)), text


def test_a_command_just_beyond_the_rejection_bound_prints_beyond_it():
    limits = MotionLimits(linear=0.3, angular=1.0)
    f = CommandFilter(load_robot("omni4"), limits, reject_above=100.0)
    assert not f.command([30.000001, 0.0, 0.0], 0.0)
    text = f.stats.last_reject_reason
    m = re.search(r"vx = (\S+) is beyond (\S+) \(", text)
    assert m and float(m.group(1)) > float(m.group(2)) >= 30.0, text


@given(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.floats(allow_nan=False, allow_infinity=False, width=64),
)
def test_digits_apart_keeps_the_order_of_a_value_and_its_bound(x, bound):
    p = digits_apart(x, bound)
    shown, shown_bound = float(f"{x:.{p}g}"), float(f"{bound:.{p}g}")
    if x > bound:
        assert shown > shown_bound and shown > bound
    elif x < bound:
        assert shown < shown_bound and shown < bound
    else:
        assert shown == shown_bound
