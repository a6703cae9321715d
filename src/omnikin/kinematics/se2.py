"""SE(2) geometry on arrays: exp, log, compose, inverse, apply.

Poses are ``(..., 3)`` arrays ``(x, y, theta)``: a body frame expressed in a
parent frame [m, m, rad]. Tangent vectors (twist times duration) are ``(..., 3)``
arrays ``(a, b, phi)``: displacement along body x and y and rotation [m, m, rad].
All functions broadcast over leading axes, return headings wrapped to
``[-pi, pi)`` and know nothing of robots.

The exponential uses the half-angle form of the left Jacobian of SO(2),

    V(phi) = [[sin phi, -(1 - cos phi)], [1 - cos phi, sin phi]] / phi
           = sinc(phi / 2) R(phi / 2),

(Barfoot, *State Estimation for Robotics*, 2017, sec. 7.1.9; Sola, Deray and
Atchuthan, *A micro Lie theory*, 2018, eq. 156), so ``exp(a, b, phi)`` moves by
``sinc(phi/2) R(phi/2) (a, b)``: the chord of the arc driven at constant twist.
``sinc`` switches to its Taylor polynomial for ``|phi/2| < 0.1`` where the
truncation error is below 3e-18: no crude fallback, no cancellation.
"""

from __future__ import annotations

import math

import numpy as np

from ..common.arrays import as_components, as_real_array

TWO_PI = 2.0 * math.pi

MAX_ANGLE = 1e6
"""Largest ``|angle|`` [rad] the core accepts as a heading or a steering angle given to it (about
160 000 turns: an unwrapped heading of days of spinning). A double still resolves such an angle
to 1e-10 rad; beyond it a value like 1e308 is a typo whose sine and cosine mean nothing."""

MAX_DIRECTION_DEG = 720.0
"""Largest ``|direction|`` [deg] a person writes: a wheel's ``angle_deg`` and ``drive_deg`` in a
robot file, the ``HEADING_DEG`` of a path (:func:`omnikin.motion.plans.parse_plan`). Directions count
modulo 360; two turns leave room for computed layouts (``30 + k 120``), while ``1e300`` has no
digit left modulo 360 (its direction would be the rounding of the conversion to radians)."""

SCALAR_TAYLOR_LIMIT = 1e-4
"""Below this |x| the scalar :func:`sinc_scalar` uses ``1 - x^2/6`` (truncation < 1e-18)."""

TAYLOR_LIMIT = 0.1
"""Below this |x| :func:`sinc` uses its Taylor polynomial to x**8 (truncation < 3e-18)."""


def wrap_angle(angle):
    """Wrap angles [rad] to ``[-pi, pi)``: a Python float for a Python number, else an array.

    The one angle wrap of omnikin (the streaming kernel inlines the same expression):
    ``angle - 2 pi floor((angle + pi) / (2 pi))``.

    Parameters
    ----------
    angle : float or array_like
        Angles [rad].

    Returns
    -------
    float or ndarray
        The angles in ``[-pi, pi)`` [rad]: a float for a Python ``int`` or ``float``, else an
        array of the shape of ``angle``.
    """
    if isinstance(angle, (int, float)):
        a = float(angle)
        return a - TWO_PI * math.floor((a + math.pi) / TWO_PI)
    arr = np.asarray(angle, dtype=float)
    return arr - TWO_PI * np.floor((arr + np.pi) * (0.5 / np.pi))


def sinc(x):
    """``sin(x) / x`` [unnormalised]: exact 1 at 0, Taylor polynomial for ``|x| < 0.1``.

    The polynomial ``1 - x^2/6 + x^4/120 - x^6/5040 + x^8/362880`` is accurate to
    below 3e-18 there, avoids the division, and is what makes batch odometry fast:
    per-sample rotations are almost always small.

    Parameters
    ----------
    x : array_like
        Arguments [rad].

    Returns
    -------
    float or ndarray
        ``sin(x) / x``, of the shape of ``x`` (a NumPy scalar for a scalar ``x``).
    """
    x = np.asarray(x, dtype=float)
    scalar = x.ndim == 0
    x = np.atleast_1d(x)
    x2 = x * x
    out = x2 * (1.0 / 362880.0)
    out -= 1.0 / 5040.0
    out *= x2
    out += 1.0 / 120.0
    out *= x2
    out -= 1.0 / 6.0
    out *= x2
    out += 1.0
    big = np.abs(x) >= TAYLOR_LIMIT
    if np.any(big):
        xb = x[big]
        out[big] = np.sin(xb) / xb
    return out[0] if scalar else out


def sinc_scalar(x: float) -> float:
    """``sin(x) / x`` of one Python float (the scalar twin of :func:`sinc`).

    Parameters
    ----------
    x : float
        Argument [rad]; ``1 - x^2/6`` below :data:`SCALAR_TAYLOR_LIMIT` in size.

    Returns
    -------
    float
    """
    return 1.0 - x * x / 6.0 if -SCALAR_TAYLOR_LIMIT < x < SCALAR_TAYLOR_LIMIT else math.sin(x) / x


def dsinc_scalar(x: float) -> float:
    """``d sinc(x) / dx = (x cos x - sin x) / x^2`` of one Python float (``-x/3`` near 0).

    Parameters
    ----------
    x : float
        Argument [rad]; ``-x/3`` below :data:`SCALAR_TAYLOR_LIMIT` in size.

    Returns
    -------
    float
    """
    if -SCALAR_TAYLOR_LIMIT < x < SCALAR_TAYLOR_LIMIT:
        return -x / 3.0
    return (math.cos(x) * x - math.sin(x)) / (x * x)


def exp(tangent) -> np.ndarray:
    """Exponential map: tangent ``(a, b, phi)`` -> pose ``(x, y, theta)``.

    The pose reached from the identity by moving with the constant body twist
    ``(a, b, phi)`` for unit time: ``(x, y) = sinc(phi/2) R(phi/2) (a, b)``, ``theta = phi``
    wrapped (module docstring).

    Parameters
    ----------
    tangent : array_like, shape (..., 3)
        Body displacement ``(a, b, phi)`` [m, m, rad]: twist times duration, in body axes.

    Returns
    -------
    ndarray, shape (..., 3)
        Pose ``(x, y, theta)`` [m, m, rad] of the moved body frame in its start frame,
        ``theta`` in ``[-pi, pi)``.

    Raises
    ------
    InputError
        Not three real components.
    """
    xi = as_components(tangent, 3, "tangent")
    half = 0.5 * xi[..., 2]
    s = sinc(half)
    c, sn = np.cos(half), np.sin(half)
    out = np.empty(np.broadcast_shapes(xi.shape), dtype=float)
    out[..., 0] = s * (c * xi[..., 0] - sn * xi[..., 1])
    out[..., 1] = s * (sn * xi[..., 0] + c * xi[..., 1])
    out[..., 2] = wrap_angle(xi[..., 2])
    return out


def log(pose) -> np.ndarray:
    """Logarithm: pose -> tangent ``(a, b, phi)`` with ``phi`` in ``[-pi, pi)``.

    Inverse of :func:`exp` on that principal branch.

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Pose ``(x, y, theta)`` [m, m, rad] of a body frame in a parent frame.

    Returns
    -------
    ndarray, shape (..., 3)
        Tangent ``(a, b, phi)`` [m, m, rad] in body axes, ``phi`` in ``[-pi, pi)``.

    Raises
    ------
    InputError
        Not three real components.
    """
    p = as_components(pose, 3, "pose")
    phi = wrap_angle(p[..., 2])
    half = 0.5 * phi
    s = sinc(half)
    c, sn = np.cos(half), np.sin(half)
    out = np.empty(p.shape, dtype=float)
    out[..., 0] = (c * p[..., 0] + sn * p[..., 1]) / s
    out[..., 1] = (-sn * p[..., 0] + c * p[..., 1]) / s
    out[..., 2] = phi
    return out


def compose(a, b) -> np.ndarray:
    """``a (+) b``: pose ``b`` given in frame ``a``, expressed in ``a``'s parent.

    ``(x, y) = (x_a, y_a) + R(theta_a) (x_b, y_b)``, ``theta = theta_a + theta_b`` wrapped.

    Parameters
    ----------
    a : array_like, shape (..., 3)
        Pose ``(x, y, theta)`` [m, m, rad] of frame ``a`` in its parent frame.
    b : array_like, shape (..., 3)
        Pose [m, m, rad] of frame ``b`` in frame ``a``; broadcasts with ``a``.

    Returns
    -------
    ndarray, shape (..., 3)
        Pose [m, m, rad] of frame ``b`` in ``a``'s parent, ``theta`` in ``[-pi, pi)``.

    Raises
    ------
    InputError
        Not three real components.
    """
    a = as_components(a, 3, "a")
    b = as_components(b, 3, "b")
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    shape = np.broadcast_shapes(a.shape, b.shape)
    out = np.empty(shape, dtype=float)
    out[..., 0] = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    out[..., 1] = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    out[..., 2] = wrap_angle(a[..., 2] + b[..., 2])
    return out


def inverse(pose) -> np.ndarray:
    """Inverse pose: the parent frame expressed in the body frame.

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Pose ``(x, y, theta)`` [m, m, rad] of a body frame in its parent frame.

    Returns
    -------
    ndarray, shape (..., 3)
        Pose [m, m, rad] of the parent frame in the body frame: ``(-R(-theta) (x, y), -theta)``,
        ``theta`` wrapped to ``[-pi, pi)``.

    Raises
    ------
    InputError
        Not three real components.
    """
    p = as_components(pose, 3, "pose")
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    out = np.empty(p.shape, dtype=float)
    out[..., 0] = -c * p[..., 0] - s * p[..., 1]
    out[..., 1] = s * p[..., 0] - c * p[..., 1]
    out[..., 2] = wrap_angle(-p[..., 2])
    return out


def between(a, b) -> np.ndarray:
    """Relative pose ``a^-1 (+) b``: frame ``b`` seen from frame ``a``.

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Poses ``(x, y, theta)`` [m, m, rad] of two frames in one parent frame; they broadcast.

    Returns
    -------
    ndarray, shape (..., 3)
        Pose [m, m, rad] of frame ``b`` in frame ``a``, ``theta`` in ``[-pi, pi)``.

    Raises
    ------
    InputError
        Not three real components.
    """
    return compose(inverse(a), b)


def apply(pose, points) -> np.ndarray:
    """Map body-frame points ``(..., 2)`` into the parent frame of ``pose``.

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Pose ``(x, y, theta)`` [m, m, rad] of the body frame in its parent frame.
    points : array_like, shape (..., 2)
        Points ``(x, y)`` [m] in the body frame; broadcast with ``pose``'s leading axes.

    Returns
    -------
    ndarray, shape (..., 2)
        The points [m] in the parent frame: ``(x, y)_pose + R(theta) points``.

    Raises
    ------
    InputError
        A pose without three, or points without two, real components.
    """
    p = as_components(pose, 3, "pose")
    q = as_components(points, 2, "points")
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    shape = np.broadcast_shapes(p.shape[:-1] + (2,), q.shape)
    out = np.empty(shape, dtype=float)
    out[..., 0] = p[..., 0] + c * q[..., 0] - s * q[..., 1]
    out[..., 1] = p[..., 1] + s * q[..., 0] + c * q[..., 1]
    return out


def rotate(angle, vectors) -> np.ndarray:
    """Rotate 2-vectors ``(..., 2)`` counter-clockwise by ``angle`` [rad].

    Parameters
    ----------
    angle : array_like, shape (...)
        Rotation angles [rad], counter-clockwise.
    vectors : array_like, shape (..., 2)
        Vectors; broadcast with ``angle``.

    Returns
    -------
    ndarray, shape (..., 2)
        ``R(angle) vectors``, in the units of ``vectors``.

    Raises
    ------
    InputError
        Vectors without two real components, or an angle that is not real.
    """
    v = as_components(vectors, 2, "vectors")
    angle = as_real_array(angle, "angle")
    c, s = np.cos(angle), np.sin(angle)
    shape = np.broadcast_shapes(np.shape(angle) + (2,), v.shape)
    out = np.empty(shape, dtype=float)
    out[..., 0] = c * v[..., 0] - s * v[..., 1]
    out[..., 1] = s * v[..., 0] + c * v[..., 1]
    return out


def compose_exp_jacobians(theta: float, tangent) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians ``(J_out_pose, J_out_tangent)`` of ``out = compose(pose, exp(tangent))``.

    ``pose = (x, y, theta)``, ``tangent = (a, b, phi)``; the update is
    ``(x, y)' = (x, y) + sinc(phi/2) R(theta + phi/2) (a, b)``, ``theta' = theta + phi``.
    Both Jacobians are taken in the pose's own coordinates ``(x, y, theta)`` of the parent
    frame (not in the tangent space, unlike the right-plus Jacobians ``J_out_x``, ``J_out_tau``
    of Sola, Deray and Atchuthan, "A micro Lie theory for state estimation in robotics",
    2018, eqs. 170-171): ``J_out_pose = d out / d pose`` (3x3; it does not depend on x, y),
    ``J_out_tangent = d out / d tangent`` (3x3). Used to propagate the odometry covariance
    ``P' = J_out_pose P J_out_pose^T + J_out_tangent Sigma J_out_tangent^T``.

    Parameters
    ----------
    theta : float
        Heading [rad] of the pose composed onto.
    tangent : sequence of float, length 3
        Tangent ``(a, b, phi)`` [m, m, rad] in body axes.

    Returns
    -------
    j_pose : ndarray, shape (3, 3)
        ``d out / d (x, y, theta)``.
    j_tangent : ndarray, shape (3, 3)
        ``d out / d (a, b, phi)``.
    """
    a, b, phi = (float(v) for v in tangent)
    h = 0.5 * phi
    k = sinc_scalar(h)
    dk = dsinc_scalar(h)
    c, s = math.cos(theta + h), math.sin(theta + h)
    ra, rb = c * a - s * b, s * a + c * b  # R(theta + phi/2) (a, b)
    j_pose = np.array([[1.0, 0.0, -k * rb], [0.0, 1.0, k * ra], [0.0, 0.0, 1.0]])
    # d/dphi of k(phi/2) R(theta + phi/2) (a, b): 0.5 dk R t + 0.5 k R' t
    j_tangent = np.array(
        [[k * c, -k * s, 0.5 * dk * ra - 0.5 * k * rb], [k * s, k * c, 0.5 * dk * rb + 0.5 * k * ra], [0.0, 0.0, 1.0]]
    )
    return j_pose, j_tangent
