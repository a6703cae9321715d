"""Only real numbers are numbers: complex, boolean, string and object input to the public
functions that take twists, wheel speeds, poses, steering angles, headings and times is refused
with one line naming the argument and saying what arrived (never silently converted: NumPy
drops an imaginary part with only a ComplexWarning and reads True as 1, "0.5" as 0.5)."""

from __future__ import annotations

import warnings
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

from omnikin import InputError, load_robot, se2
from omnikin.common.arrays import as_components, as_real_array
from omnikin.errors import MetricsInputError
from omnikin.evaluation.metrics import ate, check_trajectory
from omnikin.motion.limits import MotionLimits, saturate
from omnikin.odometry.streaming import Odometry

HOSTILE = {
    "complex": (np.array([0.2, 0.0, 0.5 + 3j]), "complex numbers (complex128)"),
    "complex-zero-imaginary": ([0.2, 0.0, 0.5 + 0j], "complex numbers (complex128)"),
    "bool": ([True, False, True], "booleans (bool)"),
    "numpy-bool": (np.array([True, False, True]), "booleans (bool)"),
    "strings": (["0.2", "0", "0.5"], "strings (<U3)"),
    "bytes": ([b"1", b"0", b"0"], "bytes (|S1)"),
    "none": ([0.2, None, 0.5], "got NoneType None"),
    "decimal": ([Decimal("0.2"), 0, 0], "got Decimal Decimal('0.2')"),
    "bool-among-floats": ([0.2, True, 0.5], "got a boolean among them"),
    "bool-among-objects": ([0.2, True, 10**30], "got bool True"),
    "datetime": (np.array(["2024-01-01"] * 3, dtype="datetime64[D]"), "datetimes (datetime64[D])"),
}


@pytest.fixture(scope="module")
def tomasi():
    return load_robot("tomasi-omni3")


@pytest.fixture(scope="module")
def ackermann():
    return load_robot("ackermann")


def calls(tomasi, ackermann):
    """``(argument name, function of one 3-vector)`` for each public entry that takes one."""
    twist = np.array([0.2, 0.0, 0.5])
    return [
        ("twist", lambda v: tomasi.ik(v)),
        ("twist", lambda v: tomasi.wheel_speeds(v)),
        ("twist", lambda v: tomasi.roller_speeds(v)),
        ("wheel_speeds", lambda v: tomasi.fk(v)),
        ("velocity", lambda v: tomasi.body_twist(v, 0.0)),
        ("twist", lambda v: saturate(tomasi, v, MotionLimits())),
        ("tangent", se2.exp),
        ("pose", se2.log),
        ("a", lambda v: se2.compose(v, twist)),
        ("b", lambda v: se2.compose(twist, v)),
        ("pose", se2.inverse),
        ("pose", lambda v: se2.apply(v, [1.0, 0.0])),
        ("pose", lambda v: Odometry(tomasi).reset(v)),
        ("trajectory: poses", lambda v: check_trajectory([0.0], [v])),
    ]


@pytest.mark.parametrize("kind", sorted(HOSTILE))
def test_public_functions_refuse_what_is_not_real(tomasi, ackermann, kind):
    value, said = HOSTILE[kind]
    for name, call in calls(tomasi, ackermann):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no ComplexWarning: an error, not a warning
            with pytest.raises(InputError) as info:
                call(value)
        message = str(info.value)
        assert message.startswith(f"{name}: ") and said in message and "\n" not in message, (name, message)


@pytest.mark.parametrize("kind", ["complex", "bool", "strings"])
def test_angles_and_times_refuse_what_is_not_real(tomasi, ackermann, kind):
    bad = {"complex": 0.1 + 1j, "bool": True, "strings": "0.1"}[kind]
    said = {"complex": "complex numbers", "bool": "boolean", "strings": "strings"}[kind]
    cases = [
        ("heading", lambda: tomasi.ik([0.2, 0.0, 0.0], heading=bad)),
        ("heading", lambda: tomasi.body_twist([0.2, 0.0, 0.0], bad)),
        ("steer", lambda: ackermann.fk([1.0, 1.0, 1.0, 1.0], steer=[bad, 0.0])),
        ("steer", lambda: ackermann.jacobian([0.0, bad])),
        ("steer_hint", lambda: ackermann.ik([0.2, 0.0, 0.1], steer_hint=[bad, 0.0])),
        ("angle", lambda: se2.rotate(bad, [1.0, 0.0])),
        ("trajectory: timestamps", lambda: check_trajectory([bad], [[0.0, 0.0, 0.0]])),
        ("reference: timestamps", lambda: ate([bad], [[0.0, 0.0, 0.0]], [0.0], [[0.0, 0.0, 0.0]])),
    ]
    for name, call in cases:
        with pytest.raises(InputError) as info:
            call()
        message = str(info.value)
        assert message.startswith(f"{name}: ") and said in message, (name, message)


def test_real_numbers_of_every_kind_are_read_exactly(tomasi):
    """Python ints and floats, NumPy integers of every width, float32 and Fractions are real:
    they give the same wheel speeds as the float64 twist (J twist, J from the closed form)."""
    expected = tomasi.ik(np.array([1.0, 0.0, 2.0])).wheel_speeds
    for twist in (
        [1, 0, 2],
        [1.0, 0, 2],
        np.array([1, 0, 2], dtype=np.int8),
        np.array([1, 0, 2], dtype=np.uint64),
        np.array([1, 0, 2], dtype=np.float32),
        [Fraction(1), 0, Fraction(4, 2)],
        [np.float64(1.0), np.int32(0), 2],
    ):
        np.testing.assert_array_equal(tomasi.ik(twist).wheel_speeds, expected)
    # tomasi-omni3: wheels at 0, 120, 240 deg, L = 0.113 m, r = 0.04125 m: omega_i = (-sin b vx + cos b vy + L w) / r
    betas = np.radians([0.0, 120.0, 240.0])
    np.testing.assert_allclose(expected, (-np.sin(betas) * 1.0 + 0.113 * 2.0) / 0.04125, rtol=1e-12)


def test_errors_of_time_arrays_take_the_callers_class():
    """``as_real_array`` is the shared check for time arrays too (odometry, metrics): the caller
    chooses the error class, so an edge can still name a sample or a file line."""
    with pytest.raises(MetricsInputError, match=r"^t: expected real numbers \(int or float\), got complex"):
        as_real_array(np.array([0.0, 1j]), "t", MetricsInputError)
    np.testing.assert_array_equal(as_real_array(np.arange(3, dtype=np.int16), "t"), [0.0, 1.0, 2.0])
    assert as_real_array([1, 2], "t").dtype == np.float64


def test_ragged_and_oversized_input_is_one_line():
    with pytest.raises(InputError, match=r"^twist: not a rectangular array of numbers") as info:
        as_components([[1.0, 2.0, 3.0], [1.0, 2.0]], 3, "twist")
    assert "\n" not in str(info.value) and len(str(info.value)) < 300
    with pytest.raises(InputError, match=r"^twist: a number too large for a float"):
        as_components([10**400, 0, 0], 3, "twist")
