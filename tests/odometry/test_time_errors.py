"""Batch odometry names the sample of a timestamp that is no number or has no float, as the
streaming estimator does (the error's ``.sample`` is set, never ``None``), and reports the same
first problem when an earlier sample has another one."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from omnikin import Odometry, OdometryInputError, batch_odometry, batch_odometry_from_angles

ROWS = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]


def streaming_error(robot, t, rows, angles=False):
    o = Odometry(robot)
    with pytest.raises(OdometryInputError) as exc:
        for tk, r in zip(t, rows, strict=True):
            (o.update_angles if angles else o.update)(tk, r)
    return exc.value


def batch_error(robot, t, rows, angles=False):
    with pytest.raises(OdometryInputError) as exc:
        (batch_odometry_from_angles if angles else batch_odometry)(robot, t, rows)
    return exc.value


@pytest.mark.parametrize(
    ("t", "sample", "words"),
    [
        ([0, 1, 10**400], 2, "non-finite timestamp"),
        ([0, True, 2], 1, "timestamp must be a number [s], got True"),
        ([0, np.bool_(True), 2], 1, "timestamp must be a number [s], got"),
        ([0, "1", 2], 1, "timestamp must be a number [s], got '1'"),
        ([0, 1, 2 + 0j], 2, "timestamp must be a number [s], got (2+0j)"),
        ([0, None, 2], 1, "timestamp must be a number [s], got None"),
        ([-(10**400), 1, 2], 0, "non-finite timestamp"),
    ],
)
@pytest.mark.parametrize("angles", [False, True])
def test_a_timestamp_that_is_no_float_is_refused_at_its_sample(tomasi, t, sample, words, angles):
    rows = [[0.01 * v for v in r] for r in ROWS] if angles else ROWS
    b, s = batch_error(tomasi, t, rows, angles), streaming_error(tomasi, t, rows, angles)
    assert b.sample == s.sample == sample, (b, s)
    assert words in b.detail and words in s.detail, (b.detail, s.detail)
    assert "\n" not in str(b)


def test_an_earlier_bad_reading_comes_first(tomasi):
    """Sample 0 holds a NaN reading, sample 1 a bool timestamp: both refuse sample 0."""
    rows = [[math.nan, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]
    b, s = batch_error(tomasi, [0, True, 2], rows), streaming_error(tomasi, [0, True, 2], rows)
    assert b.sample == s.sample == 0 and "non-finite" in b.detail and "non-finite" in s.detail


def test_a_bad_timestamp_of_a_later_trial_names_its_trial_and_sample(tomasi):
    with pytest.raises(OdometryInputError) as exc:
        batch_odometry(tomasi, [[0, 1, 2], [0, 1, True]], ROWS)
    assert exc.value.sample == 2 and "(trial (1,))" in str(exc.value)


def test_a_single_sample_with_a_bad_timestamp_is_refused(tomasi):
    """No interval to check, yet the sample is refused (as streaming refuses it)."""
    b, s = batch_error(tomasi, [True], ROWS[:1]), streaming_error(tomasi, [True], ROWS[:1])
    assert b.sample == s.sample == 0


def test_exact_numbers_are_timestamps(tomasi):
    """A Fraction or a big int within the float range is a real number: accepted by both."""
    t = [Fraction(0), Fraction(1, 100), 2**60]
    poses = batch_odometry(tomasi, t, ROWS, max_wheel_accel=math.inf).poses
    o = Odometry(tomasi, max_wheel_accel=math.inf)
    assert np.allclose([o.update(tk, r) for tk, r in zip(t, ROWS, strict=True)], poses, atol=1e-12)
