"""Trial k of a Monte Carlo study does not depend on how many trials follow it: with the same
seed, ``--trials 1``, ``2`` and ``5`` give the same first procedure (and ``2``, ``5`` the same
second one), down to the last bit of every return error."""

from __future__ import annotations

import numpy as np
import pytest

import omnikin
from omnikin import load_robot
from omnikin.evaluation.umbmark import procedure_generators, simulate_umbmark
from omnikin.motion.plans import umbmark_square
from omnikin.simulation.error_models import NOISE, NoiseModel
from omnikin.simulation.kinematic import simulate_kinematic

FAST = dict(runs=3, rate=20.0, seed=7)


def epsilons(result) -> np.ndarray:
    return np.concatenate([result.cw.epsilon, result.ccw.epsilon])


@pytest.fixture(scope="module")
def reports():
    return {n: omnikin.run_umbmark("tomasi-omni3", trials=n, **FAST) for n in (1, 2, 5)}


def test_first_procedures_do_not_depend_on_the_number_of_trials(reports):
    for stage in ("before", "after"):
        first = [epsilons(getattr(reports[n], stage)[0]) for n in (1, 2, 5)]
        np.testing.assert_array_equal(first[0], first[1])
        np.testing.assert_array_equal(first[0], first[2])
        second = [epsilons(getattr(reports[n], stage)[1]) for n in (2, 5)]
        np.testing.assert_array_equal(second[0], second[1])
        assert not np.array_equal(first[0], second[0])  # the trials are not copies of each other


def test_headline_and_robot_do_not_depend_on_the_number_of_trials(reports):
    docs = {n: r.as_dict() for n, r in reports.items()}
    for key in ("before", "after", "true_robot", "calibrated_robot", "reduction_factor"):
        assert docs[1][key] == docs[2][key] == docs[5][key], key


def test_measurements_file_of_the_first_procedure_is_the_same_for_any_trials(tmp_path):
    from omnikin.cli.main import main

    texts = []
    for n in (1, 2, 3):
        out = tmp_path / f"t{n}"
        argv = ["umbmark", "--runs", "3", "--rate", "20", "--trials", str(n), "--no-calibrate", "-o", str(out)]
        assert main([*argv, "--json"]) == 0
        text = (out / "measurements_before.csv").read_text(encoding="utf-8")
        texts.append("\n".join(line for line in text.splitlines() if not line.startswith("#")))
    assert texts[0] == texts[1] == texts[2]


def test_procedure_streams_depend_only_on_the_seed_and_the_index():
    seq = np.random.SeedSequence(11)
    a = [g.standard_normal(4) for g in procedure_generators(seq, 3)]
    b = [g.standard_normal(4) for g in procedure_generators(seq, 5)]
    for x, y in zip(a, b[:3], strict=True):
        np.testing.assert_array_equal(x, y)
    assert seq.n_children_spawned == 0  # the caller's sequence is left as it was
    c = [g.standard_normal(4) for g in procedure_generators(11, 2)]
    np.testing.assert_array_equal(c[0], a[0])  # an integer seed is SeedSequence(seed)


def test_run_umbmark_trials_are_prefixes_of_each_other():
    robot = load_robot("diff-drive")
    opts = dict(runs=2, noise=NOISE["typical"], rng=5, rate=20.0)
    three = simulate_umbmark(robot, robot, trials=3, **opts)
    one = simulate_umbmark(robot, robot, trials=1, **opts)
    np.testing.assert_array_equal(epsilons(one[0]), epsilons(three[0]))


def test_simulate_trials_draw_in_trial_order():
    """One generator shared by every trial: trial k's slip, floor and measurement variates come
    after trial k-1's, so the first trials are the same however many follow."""
    robot = load_robot("tomasi-omni3")
    square = umbmark_square("cw", 4.0, "rotate")
    runs = {
        n: simulate_kinematic(square, robot, robot, rate=20.0, noise=NOISE["typical"], trials=n, rng=3) for n in (1, 4)
    }
    np.testing.assert_array_equal(runs[1].measured[0], runs[4].measured[0])
    np.testing.assert_array_equal(runs[1].truth[0], runs[4].truth[0])
    # measurement noise alone (no slip or floor): the same rule
    quiet = NoiseModel(measurement=0.001, measurement_theta=0.001)
    ends = {
        n: simulate_kinematic(square, robot, robot, rate=20.0, noise=quiet, trials=n, rng=3).measured for n in (1, 3)
    }
    np.testing.assert_array_equal(ends[1][0], ends[3][0])
    assert not np.array_equal(ends[3][0], ends[3][1])
