"""Trajectory metrics: plain numbers in messages, one KITTI file against itself.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from omnikin import (
    OmnikinError,
)
from omnikin.cli.main import main


def test_metrics_messages_show_plain_numbers():
    from omnikin.evaluation.metrics import check_trajectory

    with pytest.raises(OmnikinError) as exc:
        check_trajectory([0.0, 1.0, 1.0], np.zeros((3, 3)))
    assert "np.float64" not in str(exc.value)


def test_metrics_of_one_kitti_file_against_itself(tmp_path, capsys):
    from omnikin.io.trajectories import write_trajectory

    t = np.arange(20) * 0.1
    write_trajectory(tmp_path / "a.kitti", t, np.column_stack([t, t, 0 * t]), "kitti")
    assert main(["metrics", str(tmp_path / "a.kitti"), str(tmp_path / "a.kitti"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ate"]["translation"]["rmse"] == 0.0
