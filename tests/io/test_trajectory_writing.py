"""Trajectory files: round-off never written as a negative zero.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations


def test_round_off_is_not_written_as_negative_zero(tmp_path):
    from omnikin.io.trajectories import trajectory_lines

    poses = [[-1e-12, -4e-10, -1e-14], [1.0, 0.0, 0.0]]
    for fmt in ("csv", "tum"):
        text = "\n".join(trajectory_lines([0.0, 1.0], poses, fmt))
        assert "-0.000" not in text, (fmt, text)
