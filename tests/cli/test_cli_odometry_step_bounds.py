"""``omnikin odometry`` refuses a log line whose interval moves the robot beyond the bounds of a
pose (a rotation beyond 1e6 rad, a displacement beyond 1e8 m) and wheel-speed bounds outside the
range of a robot file's ``max_speed``, with one line naming the file line or the option."""

from __future__ import annotations

import pytest

from support.tomasi import cli, one_line_error, write_log


def test_a_log_line_of_a_1e17_s_interval_turning_the_robot_1e15_rad_is_refused(capsys, tmp_path):
    """The attack log: it exited 0 with headings of noise."""
    log = write_log(
        tmp_path / "big.csv",
        ["t", "left", "right"],
        [[0.0, 0, 0], [10**17, 9 * 10**18, 0], [2 * 10**17, 18 * 10**18, 0]],
    )
    rc, out, err = cli(capsys, "odometry", "diff-drive", log, "-o", "-")
    line = one_line_error(rc, err)
    assert f"{log.name}: line 3: impossible motion in one interval of 1e+17 s: a rotation of" in line, line
    assert "beyond +-1e+06 rad" in line and out == ""


@pytest.mark.parametrize("speed", ["1e300", "0", "1e5", "inf"])
def test_a_wheel_speed_bound_outside_the_robot_file_range_is_a_usage_error(capsys, tmp_path, speed):
    log = write_log(tmp_path / "log.csv", ["t", "left", "right"], [[0.0, 0, 0], [0.01, 1, 1]])
    rc, _, err = cli(capsys, "odometry", "diff-drive", log, "-o", "-", "--max-wheel-speed", speed)
    line = one_line_error(rc, err)
    assert f"'{speed}': must be a wheel speed in [0.001, 10000] rad/s" in line, line
