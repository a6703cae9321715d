"""The runs a study keeps for its report (run_poses.csv) are the runs of its first procedure:
the same random draws, so each ends where that procedure's statistics say."""

import numpy as np
import pytest

from omnikin.evaluation.pipeline import first_procedure_poses
from omnikin.evaluation.procedure import draw_as_built, streams
from omnikin.evaluation.umbmark import simulate_umbmark
from omnikin.io.robot_file import load_robot
from omnikin.simulation.error_models import NOISE, PROFILES


def test_the_kept_runs_end_exactly_where_the_first_procedure_s_runs_end():
    """With slip and floor noise every run differs; the kept runs' true ends must be those of
    simulate_umbmark's first procedure with its ground truth kept (one vectorised simulation of all
    runs, where the kept runs are simulated one at a time), in the same order."""
    robot = load_robot("tomasi-omni3")
    rng = streams(7)
    true, _ = draw_as_built(robot, PROFILES["typical"], rng["robot"])
    opts = dict(side=1.0, mode="rotate", runs=3, noise=NOISE["typical"], rate=50.0)
    _, sims = simulate_umbmark(true, robot, trials=1, rng=rng["before"], keep_runs=True, **opts)
    kept = first_procedure_poses("before", true, robot, rng=rng["before"], **opts)
    assert [(p.direction, p.run) for p in kept] == [(d, k) for d in ("cw", "ccw") for k in (1, 2, 3)]
    for direction in ("cw", "ccw"):
        ends = np.array([p.truth[-1] for p in kept if p.direction == direction])
        assert np.array_equal(ends, sims[direction].truth[:, -1])
        assert len(np.unique(ends[:, 0])) == 3  # the runs do differ
        for p in kept:
            # 50 Hz kept at most 20 Hz: every 3rd sample (16.7 Hz), and the last one
            assert p.t[-1] == sims[direction].t[-1] and np.diff(p.t)[:-1] == pytest.approx(0.06)
