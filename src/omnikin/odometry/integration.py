"""Pose integration kernels: body-frame increments -> poses, exactly or not.

An increment ``(a, b, phi)`` is the body twist times the sample interval
(constant over the interval) [m, m, rad]. With heading ``theta_k`` before it, the
pose moves in the world by

* ``exact``:    ``sinc(phi/2) R(theta_k + phi/2) (a, b)``: the SE(2) exponential
  (:func:`omnikin.kinematics.se2.exp`), exact for constant twist;
* ``midpoint``: ``R(theta_k + phi/2) (a, b)``: second order, drops the chord factor;
* ``euler``:    ``R(theta_k) (a, b)``: first order, what most tools call odometry.

and the heading by ``phi``. The three differ only in the factor and the heading
used, so they share one vectorised kernel.
"""

from __future__ import annotations

import math

import numpy as np

from ..common.arrays import as_real_array, container_problem
from ..common.messages import digits_apart
from ..errors import InputError
from ..kinematics.se2 import MAX_ANGLE, sinc, wrap_angle

METHODS = ("exact", "midpoint", "euler")

POSITION_LIMIT = 1.0e8
"""Largest ``|x|``, ``|y|`` [m] of a start pose: 100 000 km, beyond any terrestrial coordinate
(UTM northings stay below 1e7 m); there a float still resolves 15 nm, so no increment of a
wheel is lost, while ``1e300`` would swallow every one. The heading is bounded like every heading
the core takes (:data:`omnikin.kinematics.se2.MAX_ANGLE`)."""


def check_method(method: str) -> str:
    if method not in METHODS:
        raise InputError(f"unknown integration method {method!r}; one of {list(METHODS)}")
    return method


FIELDS = (("x", "m", POSITION_LIMIT), ("y", "m", POSITION_LIMIT), ("theta", "rad", MAX_ANGLE))
"""Name, unit and bound of each component of a start pose."""

STEP_FIELDS = (
    ("displacement along the body x axis", "m", POSITION_LIMIT),
    ("displacement along the body y axis", "m", POSITION_LIMIT),
    ("rotation", "rad", MAX_ANGLE),
)
"""What each component ``(a, b, phi)`` of the body increment of one interval is, its unit and
its bound: the bounds of a pose (:data:`FIELDS`). A larger step is no motion of a wheeled robot
between two samples but a corrupt reading or a counter reset: a rotation of ``1e15`` rad has no
digit left modulo 2 pi (the heading becomes noise), a displacement of ``1e300`` m swallows every
later increment."""

STEP_BOUNDS = np.array([limit for _, _, limit in STEP_FIELDS])
"""The bounds of :data:`STEP_FIELDS` as an array ``(3,)`` [m, m, rad]."""


def step_problem(a: float, b: float, phi: float, dt: float) -> str | None:
    """Why the body increment ``(a, b, phi)`` [m, m, rad] of one interval of ``dt`` [s] cannot
    be integrated (a component beyond :data:`STEP_FIELDS`, or not a finite number), else None.
    Batch and streaming odometry refuse such an interval at its sample."""
    for k in (2, 0, 1):  # the rotation first: a wheel that jumps turns the body most of all
        (what, unit, limit), value = STEP_FIELDS[k], (a, b, phi)[k]
        if not abs(value) <= limit:
            size = f"of {value:.6g} {unit}" if math.isfinite(value) else "beyond the float range"
            return (
                f"impossible motion in one interval of {dt:.6g} s: a {what} {size}, beyond +-{limit:g} {unit} "
                f"(a corrupt reading or a counter reset?)"
            )
    return None


def check_start_pose(start, what: str = "start") -> np.ndarray:
    """A start pose ``(..., 3)`` (x, y, theta) [m, m, rad] as a float array, or
    :class:`InputError`: a list, tuple or array of finite numbers with ``|x|, |y| <=``
    :data:`POSITION_LIMIT` and ``|theta| <=`` :data:`~omnikin.kinematics.se2.MAX_ANGLE` (``1e308`` rad
    has no digit left modulo 2 pi: it silently became heading 0)."""
    why = container_problem(start, order="the order x, y, theta")
    if why is not None:
        raise InputError(f"{what}: expected (x, y, theta) as a list, tuple or array; {why}")
    p = as_real_array(start, what)
    if p.ndim == 0 or p.shape[-1] != 3:
        raise InputError(f"{what}: expected shape (..., 3) (x, y, theta), got {p.shape}")
    bad = ~(np.abs(p) <= np.array([limit for _, _, limit in FIELDS]))
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        name, unit, limit = FIELDS[index[-1]]
        where = f" at index {index[:-1]}" if p.ndim > 1 else ""
        digits = digits_apart(abs(float(p[index])), limit)
        raise InputError(
            f"{what}: {name} = {float(p[index]):.{digits}g} {unit}{where} is not a finite number within "
            f"+-{limit:.{digits}g} {unit}"
        )
    return p


def integrate(increments: np.ndarray, start=None, method: str = "exact") -> np.ndarray:
    """Poses ``(..., N + 1, 3)`` reached from ``start`` by the increments ``(..., N, 3)``.

    ``start`` ``(..., 3)`` (:func:`check_start_pose`) defaults to the origin; the first output pose
    is ``start``. Headings are wrapped to ``[-pi, pi)``.
    """
    inc = np.asarray(increments, dtype=float)
    if inc.ndim < 2 or inc.shape[-1] != 3:
        raise InputError(f"increments: expected shape (..., N, 3), got {inc.shape}")
    comps = np.ascontiguousarray(np.moveaxis(inc, -1, 0))
    return integrate_components(
        comps[0], comps[1], comps[2], None if start is None else check_start_pose(start), method
    )


def _world_steps(a, b, phi, heading0, method: str):
    """World-frame steps ``(dx, dy)`` ``(..., N)`` and headings ``(..., N + 1)`` (unwrapped)."""
    check_method(method)
    lead = np.broadcast_shapes(a.shape[:-1], b.shape[:-1], phi.shape[:-1], np.shape(heading0))
    n = phi.shape[-1]
    heading = np.empty(lead + (n + 1,))
    heading[..., 0] = heading0
    np.cumsum(phi, axis=-1, out=heading[..., 1:])
    heading[..., 1:] += np.asarray(heading0)[..., None]
    if method == "euler":
        direction = heading[..., :-1]
    else:
        direction = 0.5 * phi
        direction += heading[..., :-1]
    c, s = np.cos(direction), np.sin(direction)
    if method == "exact":
        k = sinc(0.5 * phi)
        a, b = a * k, b * k
    dx = c * a
    dx -= s * b
    dy = s * a
    dy += c * b
    return dx, dy, heading


def integrate_components(
    a: np.ndarray, b: np.ndarray, phi: np.ndarray, start=None, method: str = "exact", out: np.ndarray | None = None
) -> np.ndarray:
    """:func:`integrate` on the components ``(..., N)`` of the increments (the fast path).

    About two dozen passes over memory and three transcendental functions per sample
    (cos, sin, and sin only where ``|phi/2| >= 0.1``). ``out`` ``(..., N + 1, 3)``
    receives the poses if given.
    """
    lead = np.broadcast_shapes(a.shape[:-1], b.shape[:-1], phi.shape[:-1])
    n = phi.shape[-1]
    start = np.zeros(lead + (3,)) if start is None else np.broadcast_to(np.asarray(start, float), lead + (3,))
    dx, dy, heading = _world_steps(a, b, phi, start[..., 2], method)
    if out is None:
        out = np.empty(lead + (n + 1, 3))
    out[..., 0, :2] = start[..., :2]
    np.cumsum(dx, axis=-1, out=out[..., 1:, 0])
    np.cumsum(dy, axis=-1, out=out[..., 1:, 1])
    out[..., 1:, 0] += start[..., 0:1]
    out[..., 1:, 1] += start[..., 1:2]
    out[..., 2] = wrap_angle(heading)
    return out


def integrate_end(a: np.ndarray, b: np.ndarray, phi: np.ndarray, start=None, method: str = "exact") -> np.ndarray:
    """Only the last pose ``(..., 3)`` of :func:`integrate_components` (sums, no pose arrays)."""
    lead = np.broadcast_shapes(a.shape[:-1], b.shape[:-1], phi.shape[:-1])
    start = np.zeros(lead + (3,)) if start is None else np.broadcast_to(np.asarray(start, float), lead + (3,))
    dx, dy, heading = _world_steps(a, b, phi, start[..., 2], method)
    out = np.empty(lead + (3,))
    out[..., 0] = start[..., 0] + dx.sum(axis=-1)
    out[..., 1] = start[..., 1] + dy.sum(axis=-1)
    out[..., 2] = wrap_angle(heading[..., -1])
    return out
