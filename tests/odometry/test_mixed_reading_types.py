"""Float readings followed by integer readings (and the reverse) beyond 2**53: every increment is
the exact difference of the two readings rounded once, in the streaming estimator (whose
generated kernel subtracts the kept previous reading) and in batch odometry alike.

A float reading kept as a float would make the kernel compute ``int - float``, which rounds the
integer to a float first: 2**53 + 5 minus 2**53 + 2 would give 2 instead of 3. Expected poses
come from the closed form of tomasi-omni3 (``support.tomasi.tomasi_poses``); expected
increments are worked out by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import Encoder, Odometry, OdometryInputError, Robot, Wheel, batch_odometry
from support.tomasi import TOMASI_L, TOMASI_R, assert_poses_close, tomasi_poses

B = 2**53


def test_integer_reading_after_float_readings_beyond_2_53_streams_exactly(tomasi):
    """2**53 and 2**53 + 2 are floats exactly; 2**53 + 5 is not (an int64): the increments are
    2 then 3 ticks."""
    o = Odometry(tomasi)
    o.update(0.00, np.array([B, 0, 0], dtype=np.float64))
    o.update(0.01, np.array([B + 2, 0, 0], dtype=np.float64))
    pose = o.update(0.02, np.array([B + 5, 0, 0], dtype=np.int64))
    assert_poses_close([pose], tomasi_poses([[2, 0, 0], [3, 0, 0]])[-1:])


def test_float_reading_after_integer_readings_beyond_2_53_streams_exactly(tomasi):
    o = Odometry(tomasi)
    o.update(0.00, [B + 1, 0, 0])
    o.update(0.01, [B + 3, 0, 0])
    pose = o.update(0.02, [float(B + 6), 0.0, 0.0])
    assert_poses_close([pose], tomasi_poses([[2, 0, 0], [3, 0, 0]])[-1:])


def test_batch_takes_floats_mixed_with_integers_beyond_2_53_as_the_streaming_estimator(tomasi):
    """A list mixing them is read exactly, as streaming reads it (not refused as 'would be rounded')."""
    rows = [[float(B), 0.0, 0.0], [float(B + 2), 0.0, 0.0], [B + 5, 0, 0]]
    expected = tomasi_poses([[2, 0, 0], [3, 0, 0]])
    assert_poses_close(batch_odometry(tomasi, [0.0, 0.01, 0.02], rows).poses, expected)
    o = Odometry(tomasi)
    assert_poses_close([o.update(t, r) for t, r in zip([0.0, 0.01, 0.02], rows, strict=True)], expected)


def fine_encoder_robot():
    """tomasi-omni3 with encoders of 2**32 ticks per revolution behind a 1e4:1 gearbox (the
    finest a robot file allows), so that an increment beyond 2**53 ticks is a plausible step."""
    wheels = tuple(
        Wheel(
            f"w{i + 1}",
            "omni",
            TOMASI_L * math.cos(math.radians(a)),
            TOMASI_L * math.sin(math.radians(a)),
            math.radians(a) + math.pi / 2,
            TOMASI_R,
            encoder=Encoder(2.0**32, gear_ratio=1e4),
        )
        for i, a in enumerate((0, 120, 240))
    )
    return Robot("fine", wheels)


def test_integer_reading_after_a_non_integral_float_is_the_exact_increment_rounded_once():
    """0.5 then 2**53 + 3: the exact increment 2**53 + 2.5 rounds once to 2**53 + 2 (the
    neighbours are 2**53 + 2 and 2**53 + 4); ``int - float`` gave 2**53 + 4 (2**53 + 3 rounds to
    2**53 + 4 first). The twist must be that of integer readings 0 then 2**53 + 2."""
    robot = fine_encoder_robot()
    kw = {"max_wheel_speed": 1e4, "max_wheel_accel": math.inf}
    mixed, whole = Odometry(robot, **kw), Odometry(robot, **kw)
    mixed.update(0.0, [0.5, 0.0, 0.0])
    mixed.update(1.0, [B + 3, 0, 0])
    whole.update(0.0, [0, 0, 0])
    whole.update(1.0, [B + 2, 0, 0])
    assert mixed.twist == whole.twist
    assert mixed.pose == whole.pose
    batch = batch_odometry(robot, [0.0, 1.0], [[0.5, 0.0, 0.0], [B + 3, 0, 0]], **kw)
    exact = batch_odometry(robot, [0.0, 1.0], [[0, 0, 0], [B + 2, 0, 0]], **kw)
    assert np.array_equal(batch.increments, exact.increments)


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_float_among_big_integers_is_refused_at_its_sample(tomasi, bad):
    rows = [[B + 1, 0, 0], [B + 3, 0, 0], [bad, 0, 0]]
    with pytest.raises(OdometryInputError) as exc:
        batch_odometry(tomasi, [0.0, 0.01, 0.02], rows)
    assert exc.value.sample == 2 and "non-finite" in str(exc.value)
