"""The start time of a simulated run, checked against every output that stamps its samples
(omnikin.motion.timing.check_start_time): the stamps must fit what the output holds and stay
distinct at the sample rate.

'omnikin simulate --start 1e16 --log a.csv' exited 0 with every row at 1e16 or 1e16 + 2 (the
spacing of doubles there is 2 s), a log 'omnikin odometry' then refused; '--start -5 --bag'
with MCAP storage failed after the simulation. Expected bounds come from IEEE 754 doubles: the
spacing of the doubles in [2**e, 2**(e+1)) is 2**(e-52).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.errors import InputError
from omnikin.motion.timing import STAMP_RESOLUTION, check_start_time
from support.cli import run_cli


def test_the_resolution_is_a_thousandth_of_the_sample_interval():
    assert STAMP_RESOLUTION == 1e-3


@pytest.mark.parametrize("rate", [5.0, 100.0, 10_000.0])
def test_a_float_stamp_may_be_rounded_to_a_thousandth_of_the_interval(rate):
    """Largest power of two e with 2**(e-52) <= 1e-3 / rate: stamps below 2**(e+1) are fine,
    stamps at or beyond 2**(e+1) (spacing 2**(e-51) > 1e-3 / rate) are refused."""
    e = math.floor(math.log2(1e-3 / rate)) + 52
    top = 2.0 ** (e + 1)
    assert check_start_time(top * 0.99, 0.5, rate, "--start") == top * 0.99
    assert check_start_time(-top * 0.99, 0.5, rate, "--start") == -top * 0.99
    for start in (top, -top - 1.0, top * 0.999 - 1.0):  # the last one ends beyond 2**(e+1)
        with pytest.raises(InputError, match=r"^--start: the output holds a time near .* the stamps would collapse"):
            check_start_time(start, 0.5 + top * 0.002, rate, "--start")


@pytest.mark.parametrize("start", [math.inf, -math.inf, math.nan, "0", True, None])
def test_a_start_time_is_a_finite_number(start):
    with pytest.raises(InputError, match=r"^start: the start time must be"):
        check_start_time(start, 1.0, 100.0)


def test_integer_nanosecond_stamps_hold_any_start_within_their_span():
    """A ROS 2 bag stamps integer nanoseconds (1e-9 s, far below 1e-3 / 10 kHz) from 0 to
    2**31 - 1 s: a start of 2e9 s is fine at 10 kHz, -1 s and a run ending after 2**31 - 1 s are not."""
    span, ns = (0.0, 2.0**31 - 1), 1e-9
    assert check_start_time(2e9, 60.0, 10_000.0, output="a ROS 2 bag", span=span, step=ns) == 2e9
    for start, duration in ((-1.0, 10.0), (2.0**31 - 10, 20.0), (1e300, 1.0)):
        with pytest.raises(InputError, match=r"do not fit a ROS 2 bag, whose times run from 0 to 2147483647 s"):
            check_start_time(start, duration, 100.0, output="a ROS 2 bag", span=span, step=ns)


# --- omnikin simulate ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("start", ["1e16", "-1e16", "1e300", "7e10"])
def test_simulate_refuses_a_start_whose_log_stamps_would_collapse(capsys, tmp_path, start):
    """At 100 Hz a thousandth of the interval is 1e-5 s: doubles from 2**36 = 6.87e10 s on are
    2**-16 = 1.5e-5 s apart, too coarse."""
    log = tmp_path / "a.csv"
    rc, out, err = run_cli(capsys, "simulate", "diff-drive", "--start", start, "--log", log, "--errors", "none")
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith("omnikin: error: --start: a tick log holds a time near") and "100 Hz" in err
    assert list(tmp_path.iterdir()) == []


def test_a_log_started_at_a_unix_time_is_read_back_by_the_odometry(capsys, tmp_path):
    """1.7e9 s (2023) at 100 Hz: doubles there are 2**-22 = 2.4e-7 s apart; the stamps stay
    distinct and the log is integrated."""
    log = tmp_path / "a.csv"
    rc, _, err = run_cli(
        capsys, "simulate", "diff-drive", "--start", "1.7e9", "--path", "line 0.3", "--log", log, "--errors", "none"
    )
    assert rc == 0, err
    rows = [line.split(",") for line in log.read_text().splitlines() if line and not line.startswith(("#", "t"))]
    t = np.array([float(r[0]) for r in rows])
    assert t[0] == 1.7e9 and np.all(np.diff(t) > 0.01 - 1e-6)
    rc, _, err = run_cli(capsys, "odometry", "diff-drive", log, "-o", tmp_path / "odom.csv")
    assert rc == 0, err


@pytest.mark.parametrize(
    "start, why", [("-5", "-5 s"), ("2147483600", "2.1474836e+09 s to 2.1474837e+09 s"), ("3e9", "3e+09 s")]
)
def test_simulate_refuses_a_start_a_bag_cannot_stamp_before_simulating(capsys, tmp_path, start, why):
    """ROS 2 times run from 0 (rclcpp, rclpy and MCAP refuse negative ones) to 2**31 - 1 s; the
    default square takes 64 s, so 2147483600 s ends beyond. MCAP failed after the simulation."""
    pytest.importorskip("rosbags")
    bag = tmp_path / "s.bag"
    argv = ["simulate", "diff-drive", "--start", start, "--bag", bag, "--storage", "mcap", "--errors", "none"]
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    assert f"--start: stamps from {why}" in err and "do not fit a ROS 2 bag" in err
    assert list(tmp_path.iterdir()) == []
