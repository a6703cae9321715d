"""Robot model edge cases: infeasible pure rotation, wheel validation, cached matrices that copies
cannot corrupt, FK of any iterable of names, zero wheel limits.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import omnikin
from omnikin import (
    OmnikinError,
    Robot,
    Wheel,
    load_robot,
)

TOM_BETAS = np.radians([0.0, 120.0, 240.0])


def test_villasenor_pure_rotation_returned_as_infeasible():
    v = load_robot("villasenor-omni3")
    # a pure rotation about the origin has no steady swivel angle where offset > |p| (hub too slow)
    expected = [w.offset > math.hypot(w.x, w.y) for w in v.steerable]
    assert any(expected)
    res = v.ik([0, 0, 1.0], on_infeasible="return")
    assert not bool(res.feasible)
    assert res.steer_limited.tolist() == expected
    with pytest.raises(omnikin.InfeasibleTwistError):
        v.ik([0, 0, 1.0])


@pytest.mark.parametrize(
    "kw", [{"radius": 0.0}, {"x": math.nan}, {"type": "omny"}, {"radius": 1e-320}, {"radius": -0.05}, {"y": math.inf}]
)
def test_wheel_validation(kw):
    args = {"name": "a", "type": "omni", "x": 0.1, "y": 0.0, "drive": math.pi / 2, "radius": 0.05}
    args.update(kw)
    with pytest.raises(OmnikinError):
        Wheel(**args)


def test_copied_robot_cannot_corrupt_cached_matrices():
    """Pickle and deepcopy drop the read-only caches; the copy rebuilds its own, still read-only."""
    import copy
    import pickle

    robot = load_robot("omni4")
    robot.jacobian(), robot.fk_matrix(), robot.fk_matrix(None, ["w1", "w2", "w3"])
    for clone in (copy.deepcopy(robot), pickle.loads(pickle.dumps(robot))):
        jac = clone.jacobian()
        with pytest.raises(ValueError):
            jac *= 2
        with pytest.raises(ValueError):
            clone.fk_matrix()[0, 0] = 1.0
        np.testing.assert_array_equal(clone.jacobian(), robot.jacobian())


def test_fk_matrix_accepts_any_iterable_of_wheel_names():
    robot = load_robot("omni4")
    ref = np.linalg.pinv(robot.jacobian()[:3])
    np.testing.assert_allclose(robot.fk_matrix(None, (n for n in ["w1", "w2", "w3"])), ref, atol=1e-12)
    np.testing.assert_allclose(robot.fk_matrix(None, np.array(["w1", "w2", "w3"])), ref, atol=1e-12)


def test_zero_wheel_limit_with_zero_twist_is_not_nan():
    from omnikin.motion.limits import MotionLimits, saturate, speed_scale

    wheels = tuple(
        Wheel(
            f"w{i}",
            "omni",
            0.1 * math.cos(a),
            0.1 * math.sin(a),
            a + math.pi / 2,
            0.03,
            max_speed=0.0 if i == 0 else None,
        )
        for i, a in enumerate(TOM_BETAS)
    )
    robot = Robot("zero-limit", wheels)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert speed_scale(robot, [0.0, 0.0, 0.0], MotionLimits()) == np.inf
        np.testing.assert_array_equal(saturate(robot, [0.0, 0.0, 0.0], MotionLimits()), [0.0, 0.0, 0.0])
