"""Physical fields of the core types (omnikin.kinematics.physical, Wheel.physical, Robot.physical).

The ranges are those of docs/conventions.md, "Physical fields", typed in here; the range checks
are one helper (omnikin.common.arrays.range_problem / whole_problem) shared with every other parameter,
so a wheel's radius and a wheel's width refuse the same kinds of value in the same words.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from omnikin import Encoder, Robot, Wheel
from omnikin.errors import InputError
from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel


def omni(name, angle_deg, physical=None, kind="omni", **extra):
    b = math.radians(angle_deg)
    return Wheel(
        name, kind, 0.113 * math.cos(b), 0.113 * math.sin(b), b + math.pi / 2, 0.04125, physical=physical, **extra
    )


def test_every_wheel_field_is_kept_as_given():
    p = PhysicalWheel(width=0.03, mass=0.12, rollers=12, rows=2, friction=0.8, max_torque=0.4)
    w = omni("w1", 0, p)
    assert w.physical == p
    assert p.given == {"width": 0.03, "mass": 0.12, "rollers": 12, "rows": 2, "friction": 0.8, "max_torque": 0.4}


def test_every_body_field_is_kept_and_com_becomes_a_float_triple():
    body = PhysicalBody(mass=2.5, com=[0, 0.01, 0.06], height=0.02)
    robot = Robot("r", (omni("w1", 0), omni("w2", 120), omni("w3", 240)), physical=body)
    assert robot.physical.com == (0.0, 0.01, 0.06) and all(type(v) is float for v in robot.physical.com)
    assert robot.physical.given == {"mass": 2.5, "com": (0.0, 0.01, 0.06), "height": 0.02}


def test_without_physical_fields_nothing_is_invented():
    robot = Robot("r", (omni("w1", 0), omni("w2", 120), omni("w3", 240)))
    assert robot.physical is None and all(w.physical is None for w in robot.wheels)
    assert PhysicalWheel().given == {} and PhysicalBody().given == {}


@pytest.mark.parametrize(
    "field, low, high",
    [("width", 1e-4, 10.0), ("mass", 1e-4, 1e5), ("friction", 1e-3, 10.0), ("max_torque", 1e-5, 1e5)],
)
def test_wheel_numbers_accept_their_bounds_and_refuse_beyond(field, low, high):
    """Inclusive ranges of docs/conventions.md: the bounds pass, 1 % beyond them fails."""
    for ok in (low, high, np.float32(high / 2), np.int64(1) if low <= 1 <= high else low):
        PhysicalWheel(**{field: ok})
    for bad in (low * 0.99, high * 1.01, -low):
        with pytest.raises(InputError, match=rf"^wheel: physical\.{field} must lie in \["):
            PhysicalWheel(**{field: bad})


@pytest.mark.parametrize("field, low, high", [("rollers", 3, 64), ("rows", 1, 4)])
def test_roller_counts_are_whole_numbers_in_range(field, low, high):
    for ok in (low, high, np.int16(low)):
        PhysicalWheel(**{field: ok})
    for bad in (low - 1, high + 1, float(low), True, "2"):
        with pytest.raises(
            InputError, match=rf"^wheel: physical\.{field} must be a whole number from {low} to {high}, got "
        ):
            PhysicalWheel(**{field: bad})


@pytest.mark.parametrize(
    "value, words",
    [
        (float("nan"), "must be finite, got nan"),
        (float("inf"), "must be finite, got inf"),
        (True, "must be a number, got True"),
        ("0.03", "must be a number, got '0.03'"),
        (10**400, "must lie in ["),
    ],
)
def test_wheel_width_refuses_what_a_radius_refuses_in_the_same_words(value, words):
    """One range helper: the width and the radius (an old field) say the same thing."""
    with pytest.raises(InputError) as width:
        PhysicalWheel(width=value)
    with pytest.raises(InputError) as radius:
        Wheel("a", "omni", 0.1, 0.0, 1.0, value)
    assert str(width.value).startswith(f"wheel: physical.width {words}")
    assert str(radius.value).startswith(f"wheel 'a': radius {words}")


@pytest.mark.parametrize(
    "kw, fragment",
    [
        ({"mass": 0.0}, "physical.mass must lie in [0.0001, 100000] kg, got 0"),
        ({"height": 20.0}, "physical.height must lie in [0.001, 10] m, got 20"),
        ({"com": (0.0, 0.0)}, "physical.com must be 3 numbers"),
        ({"com": (0.0, 0.0, 0.0)}, "physical.com.z must lie in [0.0001, 1000] m, got 0"),
        ({"com": (2e3, 0.0, 0.1)}, "physical.com.x must lie in [-1000, 1000] m, got 2000"),
        ({"com": (0.0, "0", 0.1)}, "physical.com.y must be a number, got '0'"),
    ],
)
def test_body_fields_out_of_range_are_refused_naming_the_field(kw, fragment):
    with pytest.raises(InputError) as info:
        PhysicalBody(**kw)
    assert str(info.value).startswith("body: ") and fragment in str(info.value)


@pytest.mark.parametrize(
    "com, fragment",
    [
        ({0.5, 3.0, 0.25}, "a set has no defined order (the order x, y, z would be lost)"),
        ({"x": 0.0, "y": 0.0, "z": 0.1}, "a dict has no defined order (the order x, y, z would be lost)"),
        (
            {"x": 0.0, "y": 0.0, "z": 0.1}.values(),
            "a dict_values has no defined order (the order x, y, z would be lost)",
        ),
        ("0.1", "str '0.1' is text, not numbers"),
        (0.1, "a float is not a sequence"),
    ],
)
def test_a_centre_of_mass_in_a_container_without_order_is_refused(com, fragment):
    # a set of (0.5, 3.0, 0.25) iterates as (0.25, 0.5, 3.0) or so: z would become 3 m
    with pytest.raises(InputError) as info:
        PhysicalBody(com=com)
    assert str(info.value) == f"body: physical.com must be 3 numbers (x, y, z) [m] in order: {fragment}"


def test_a_centre_of_mass_from_any_ordered_container_is_kept_in_order():
    for com in ([0.5, -0.25, 0.1], (0.5, -0.25, 0.1), np.array([0.5, -0.25, 0.1]), iter([0.5, -0.25, 0.1])):
        assert PhysicalBody(com=com).com == (0.5, -0.25, 0.1)
    with pytest.raises(InputError, match=r"^body: physical\.com must be 3 numbers \(x, y, z\) \[m\], got count"):
        PhysicalBody(com=itertools.count(1))  # endless: read no further than a fourth item


@pytest.mark.parametrize("kind", ["standard", "steerable", "castor"])
def test_rollers_only_on_swedish_wheels(kind):
    from omnikin.kinematics.wheels import Steer

    steer = Steer(offset=0.02) if kind == "castor" else None
    for field in ("rollers", "rows"):
        with pytest.raises(InputError, match=r"wheel 'w1': only Swedish wheels have rollers"):
            Wheel("w1", kind, 0.1, 0.0, 0.0, 0.05, steer=steer, physical=PhysicalWheel(**{field: 3}))
    for kind_ok in ("omni", "mecanum", "swedish"):
        roller = math.radians(45) if kind_ok == "mecanum" else 0.0
        Wheel("w1", kind_ok, 0.1, 0.0, 0.0, 0.05, roller, physical=PhysicalWheel(rollers=3, rows=1))


def test_a_castor_has_no_motor_torque():
    from omnikin.kinematics.wheels import Steer

    with pytest.raises(InputError, match=r"^wheel 'c': a castor is passive: it has no motor \(physical\.max_torque\)$"):
        Wheel("c", "castor", -0.2, 0.0, 0.0, 0.03, steer=Steer(offset=0.02), physical=PhysicalWheel(max_torque=1.0))
    Wheel("c", "castor", -0.2, 0.0, 0.0, 0.03, steer=Steer(offset=0.02), physical=PhysicalWheel(mass=0.05))


def test_physical_must_be_the_physical_type():
    with pytest.raises(InputError, match=r"physical must be a PhysicalWheel or None"):
        omni("w1", 0, {"rows": 2})
    with pytest.raises(InputError, match=r"physical must be a PhysicalBody or None"):
        Robot("r", (omni("w1", 0), omni("w2", 120), omni("w3", 240)), physical={"mass": 1.0})


def test_encoder_counter_bits_use_the_same_whole_number_check():
    """counter_bits, rollers and rows: one whole-number check, one wording."""
    for bad in (1, 65, 16.0, True):
        with pytest.raises(InputError, match=r"^encoder: counter_bits must be a whole number from 2 to 64, got "):
            Encoder(600, counter_bits=bad)
    assert Encoder(600, counter_bits=np.uint8(16)).counter_bits == 16
