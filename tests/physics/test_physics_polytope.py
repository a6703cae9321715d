"""The largest ``|c . x|`` over the polytope of body accelerations the wheels can produce
(:func:`omnikin.physics.description.polytope_max`), against the definition (a vertex is where
``rank`` independent constraints are active) and a closed form, and its cost in the wheel count."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from omnikin import Encoder, Robot, Wheel, load_robot
from omnikin.physics.description import describe, drivable_rows, polytope_max
from omnikin.presets import PRESET_NAMES


def vertex_maximum(rows: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """The definition: every choice of ``d`` constraints ``rows_i x = +-1`` with independent
    rows is a candidate vertex; keep the feasible ones (``rows`` of full column rank ``d``)."""
    n, d = rows.shape
    best = np.zeros(len(costs))
    for chosen in itertools.combinations(range(n), d):
        a = rows[list(chosen)]
        if abs(np.linalg.det(a)) < 1e-9:
            continue
        for signs in itertools.product([-1.0, 1.0], repeat=d):
            x = np.linalg.solve(a, np.array(signs))
            if np.abs(rows @ x).max() <= 1.0 + 1e-9:
                best = np.maximum(best, np.abs(costs @ x))
    return best


def test_a_square_s_largest_value_is_the_sum_of_the_cost_s_magnitudes():
    # |x| <= 1, |y| <= 1: the vertices (+-1, +-1) give |c_x| + |c_y|
    costs = np.array([[3.0, -2.0], [0.5, 0.0], [-1.0, -1.0]])
    np.testing.assert_allclose(polytope_max(np.eye(2), costs), [5.0, 0.5, 2.0], rtol=1e-12)


def test_a_rank_one_set_of_rows_bounds_a_segment():
    # rows along (1, 1, 0): x = t (1, 1, 0) / sqrt 2; the second row bounds |2 sqrt 2 t| <= 1
    rows = np.array([[1.0, 1.0, 0.0], [2.0, 2.0, 0.0]])
    costs = np.array([[1.0, 0.0, 5.0]])  # c . x = t / sqrt 2, the z part off the row space
    np.testing.assert_allclose(polytope_max(rows, costs), [1 / 4], rtol=1e-12)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_the_presets_rim_polytopes_give_the_vertex_enumeration_s_values(name):
    robot = load_robot(name)
    radii = np.array([w.radius for w in robot.rolling])
    rows = drivable_rows(np.asarray(robot.jacobian(), dtype=float), radii, 0.2)
    rim = radii[:, None] * rows
    costs = np.random.default_rng(7).normal(size=(5, 3))
    _, sv, vt = np.linalg.svd(rim, full_matrices=False)
    basis = vt[: int(np.sum(sv > sv[0] * 1e-9))].T
    expected = vertex_maximum(rim @ basis, costs @ basis)
    np.testing.assert_allclose(polytope_max(rim, costs), expected, rtol=1e-9)


@pytest.mark.parametrize("seed", range(12))
def test_random_layouts_give_the_vertex_enumeration_s_values(seed):
    rng = np.random.default_rng(seed)
    n, d = int(rng.integers(3, 10)), int(rng.integers(2, 4))
    rows, costs = rng.normal(size=(n, d)), rng.normal(size=(4, d))
    np.testing.assert_allclose(polytope_max(rows, costs), vertex_maximum(rows, costs), rtol=1e-9)


def ring_of_omni_wheels(count: int) -> Robot:
    distance = 0.04 * count  # room for the wheels on the ring
    wheels = [
        Wheel(
            f"w{i + 1}",
            "omni",
            distance * math.cos(2 * math.pi * i / count),
            distance * math.sin(2 * math.pi * i / count),
            2 * math.pi * i / count + math.pi / 2,
            0.04,
            encoder=Encoder(600),
        )
        for i in range(count)
    ]
    return Robot(f"ring{count}", wheels)


def test_describing_a_robot_of_many_wheels_does_not_enumerate_choices_of_wheels(monkeypatch):
    # enumerating every choice of 3 of 256 wheels took minutes (128 wheels: 9 s): a determinant
    # and a solve for each of the 2.7 million choices. Counted, not timed: the hull needs none.
    robot = ring_of_omni_wheels(256)
    calls = []
    for name in ("det", "solve", "lstsq", "inv"):
        original = getattr(np.linalg, name)

        def counted(*args, _original=original, _name=name, **kwargs):
            calls.append(_name)
            if len(calls) > len(robot.wheels):
                pytest.fail(f"describe() solves per choice of wheels: over {len(robot.wheels)} calls of {_name}")
            return _original(*args, **kwargs)

        monkeypatch.setattr(np.linalg, name, counted)
    described = describe(robot)
    assert len(calls) <= len(robot.wheels)
    assert all(w.motor is not None and w.motor.max_accel > 0 for w in described.wheels)
