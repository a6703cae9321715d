"""Outputs refuse stamps they cannot hold, whoever writes them: a simulated run recorded to a bag
(ROS 2 times from 0 to 2**31 - 1 s, omnikin.motion.timing.check_start_time) and a tick log
whose times, as written and read back, must increase (the odometry refuses any other log)."""

from __future__ import annotations

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.errors import InputError
from omnikin.io.logs import write_tick_log
from omnikin.motion.plans import line
from omnikin.simulation.error_models import NoiseModel
from omnikin.simulation.kinematic import simulate_kinematic


@pytest.mark.parametrize("start", [-5.0, 2.0**31 - 1.0])
def test_record_run_refuses_a_start_a_ros_time_cannot_hold(tmp_path, start):
    pytest.importorskip("rosbags")
    from omnikin.io.bags import record_run

    robot = load_robot("diff-drive")
    run = simulate_kinematic(line(0.3), robot, robot, rate=50.0, noise=NoiseModel(quantise=False))  # 1.6 s
    with pytest.raises(InputError, match=r"^start: stamps from .* do not fit a ROS 2 bag, whose times run from 0 to"):
        record_run(tmp_path / "s.bag", run, robot, start=start)
    assert list(tmp_path.iterdir()) == []


def test_a_tick_log_whose_times_collapse_is_not_written(tmp_path):
    """1e16 + 1 is 1e16 as a double: two samples on one time, a log no odometry reads."""
    path = tmp_path / "log.csv"
    t = 1e16 + np.array([0.0, 1.0, 2.0])
    with pytest.raises(InputError, match=r"^t: sample 1 at '10000000000000000.000000000' s does not come after"):
        write_tick_log(path, t, [[0, 0], [1, 1], [2, 2]], ["left", "right"])
    with pytest.raises(InputError, match=r"^t: sample 2 at .* must increase"):
        write_tick_log(path, [0.0, 0.2, 0.1], [[0, 0], [1, 1], [2, 2]], ["left", "right"])
    assert list(tmp_path.iterdir()) == []
