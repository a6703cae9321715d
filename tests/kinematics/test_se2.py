"""SE(2) group axioms and closed forms for omnikin.kinematics.se2 (property tests)."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnikin.errors import OmnikinError
from omnikin.kinematics import se2 as g

coord = st.floats(-50, 50, allow_nan=False)
angle = st.floats(-math.pi, math.pi, exclude_max=True, allow_nan=False)
poses = st.tuples(coord, coord, angle).map(np.array)
tangents = st.tuples(coord, coord, st.floats(-3.1, 3.1)).map(np.array)


def matrix(p):
    """Homogeneous 3x3 matrix of a pose: independent reference for compose/inverse."""
    c, s = math.cos(p[2]), math.sin(p[2])
    return np.array([[c, -s, p[0]], [s, c, p[1]], [0, 0, 1]])


def pose_of(m):
    return np.array([m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0])])


def assert_pose_close(a, b, tol=1e-9):
    np.testing.assert_allclose(a[..., :2], b[..., :2], atol=tol)
    d = (a[..., 2] - b[..., 2] + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(d, 0.0, atol=tol)


@given(poses, poses)
def test_compose_matches_matrix_product(a, b):
    assert_pose_close(g.compose(a, b), pose_of(matrix(a) @ matrix(b)))


@given(poses, poses, poses)
def test_compose_is_associative(a, b, c):
    assert_pose_close(g.compose(g.compose(a, b), c), g.compose(a, g.compose(b, c)), 1e-8)


@given(poses)
def test_inverse_gives_identity(a):
    assert_pose_close(g.compose(a, g.inverse(a)), np.zeros(3))
    assert_pose_close(g.compose(g.inverse(a), a), np.zeros(3))
    assert_pose_close(pose_of(np.linalg.inv(matrix(a))), g.inverse(a))


@given(tangents)
def test_exp_matches_matrix_exponential(xi):
    """exp against scipy-free matrix exponential of the se(2) generator (series, 40 terms)."""
    a, b, phi = xi
    gen = np.array([[0, -phi, a], [phi, 0, b], [0, 0, 0]], dtype=float)
    out, term = np.eye(3), np.eye(3)
    for k in range(1, 60):
        term = term @ gen / k
        out = out + term
    assert_pose_close(g.exp(xi), pose_of(out), 1e-7)


@given(poses)
def test_log_inverts_exp(p):
    assert_pose_close(g.exp(g.log(p)), p, 1e-8)


@given(tangents)
def test_exp_of_log_branch(xi):
    out = g.log(g.exp(xi))
    np.testing.assert_allclose(out, xi, atol=1e-8)


def test_exp_is_the_constant_twist_arc():
    """Driving 1 m/s forward while turning pi/2 rad: quarter circle of radius 2/pi."""
    r = 2 / math.pi
    assert_pose_close(g.exp([1.0, 0.0, math.pi / 2]), np.array([r, r, math.pi / 2]), 1e-12)


_EDGE = 2 * g.TAYLOR_LIMIT  # phi at which sinc(phi/2) switches from its polynomial to sin(x)/x


@pytest.mark.parametrize(
    "phi",
    [
        _EDGE * (1 - 1e-12),
        _EDGE,
        _EDGE * (1 + 1e-12),
        -_EDGE,
        -_EDGE * (1 - 1e-12),
        0.5 * _EDGE,
        1e-4,
        1e-9,
        0.0,
        1.0,
        3.0,
    ],
)
def test_small_angle_branch_is_continuous(phi):
    """Both sides of the Taylor switch agree with an exact-rational series reference to one ulp."""
    from fractions import Fraction

    x = Fraction(phi / 2)
    ref = sum((-1) ** k * x ** (2 * k) / math.factorial(2 * k + 1) for k in range(20))
    assert abs(float(g.sinc(phi / 2)) - float(ref)) <= 2.3e-16  # within one ulp
    out = g.exp([1.0, 0.5, phi])
    c, s = math.cos(phi / 2), math.sin(phi / 2)
    np.testing.assert_allclose(out[:2], float(ref) * np.array([c - 0.5 * s, s + 0.5 * c]), rtol=0, atol=4e-16)


def test_sinc_is_monotone_across_the_switch():
    """No step at the branch: values just below and above the switch differ by their slope only."""
    xs = g.TAYLOR_LIMIT * (1 + np.array([-4e-9, -2e-9, -1e-9, 0, 1e-9, 2e-9, 4e-9]))
    assert np.all(np.diff(g.sinc(xs)) < 0)


def test_vectorised_broadcasting():
    a = np.zeros((4, 5, 3))
    a[..., 0] = np.arange(5)
    b = np.array([1.0, 0.0, 0.5])
    out = g.compose(a, b)
    assert out.shape == (4, 5, 3)
    np.testing.assert_allclose(out[..., 0], np.broadcast_to(np.arange(5) + 1.0, (4, 5)))
    assert g.exp(np.zeros((7, 3))).shape == (7, 3)
    assert g.apply(np.zeros(3), np.ones((6, 2))).shape == (6, 2)


def test_apply_and_between():
    p = np.array([1.0, 2.0, math.pi / 2])
    np.testing.assert_allclose(g.apply(p, [1.0, 0.0]), [1.0, 3.0], atol=1e-15)
    q = np.array([-3.0, 0.5, 2.0])
    assert_pose_close(g.compose(p, g.between(p, q)), q)


def test_wrap_angle_range():
    w = g.wrap_angle(np.array([math.pi, -math.pi, 3 * math.pi, 7.0, -7.0]))
    assert np.all(w >= -math.pi) and np.all(w < math.pi)
    np.testing.assert_allclose(np.cos(w), np.cos([math.pi, -math.pi, 3 * math.pi, 7.0, -7.0]), atol=1e-15)


@pytest.mark.parametrize("bad", [[1.0, 2.0], np.zeros((2, 4)), 3.0])
def test_bad_shapes_are_named(bad):
    with pytest.raises(OmnikinError, match=r"expected shape \(\.\.\., 3\)"):
        g.exp(bad)
