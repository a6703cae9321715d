"""The fastest timing of a path under every wheel's speed and acceleration limit.

Along a path ``q(s)`` (:class:`~omnikin.control.path.Path`) driven at path speed ``sdot`` and
acceleration ``sddot``, the wheels turn at

    omega(s) = w(s) sdot,                     w = J(beta(s)) R(theta)^T q'(s)  (rad per m of s)
    omegadot = w(s) sddot + w'(s) sdot^2,

``J`` the robot's wheel Jacobian at the steering ``beta(s)`` the path needs (the steering of a
steered wheel depends only on the direction of the body's motion, not on its speed), ``R`` the
rotation by the heading. A speed limit ``|omega_j| <= W_j`` and an acceleration limit
``|omegadot_j| <= A_j`` per wheel, and a steering-rate limit ``|beta_k'(s) sdot| <= B_k``, are
linear in ``(u, x) = (sddot, sdot^2)``: the limits of the wheel space (a polytope of twists for
each heading), not boxes per axis of the body.

The fastest timing is found on the path's samples by reachability analysis (Pham & Pham,
"A New Approach to Time-Optimal Path Parameterization Based on Reachability Analysis",
IEEE T-RO 34(3), 2018): with ``x_{i+1} = x_i + 2 (s_{i+1} - s_i) u_i`` (``sddot`` constant over
each interval), a backward pass gives the largest ``x_i`` from which the end can still be
reached at rest, and a forward pass takes the largest ``u_i`` that stays inside it. Both are
exact for the discretised problem; the problem's variables being two, every step is a few
closed-form line intersections (:func:`_row_lines`, :func:`_static_cap`), not a solver call.

Time follows from ``dt_i = 2 ds_i / (sqrt(x_i) + sqrt(x_{i+1}))`` (constant ``sddot``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits
from .path import Path, body_rates, derivative

ACCEL_DIRECTIONS = 16
"""Directions in which a body's linear acceleration limit is written as rows (:func:`body_rows`):
the limit ``|a| <= A`` becomes ``|a . d_k| <= A cos(pi / (2 K))`` for ``K`` directions ``d_k``
``pi / K`` apart, which keeps ``|a| <= A`` (every vector is within ``pi / (2 K)`` of some ``d_k``
or its opposite) and gives up at most ``1 - cos(pi / 32)`` = 0.48 % of it."""


@dataclass(frozen=True)
class WheelLimits:
    """Limits of every rolling wheel and steering joint (``inf``: none).

    Attributes
    ----------
    speed : float
        Largest wheel speed ``|omega|`` [rad/s] (a wheel's own ``max_speed`` applies too).
    accel : float
        Largest wheel acceleration ``|omegadot|`` [rad/s^2].

    With ``inf`` speed or acceleration the wheels are not what limits the timing: the body's
    limits of :func:`time_optimal` must then bound it.
    steer_rate : float
        Largest steering rate [rad/s] of a steerable wheel.
    """

    speed: float = 12.0
    accel: float = 40.0
    steer_rate: float = math.inf

    def __post_init__(self):
        for name in ("speed", "accel", "steer_rate"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and v > 0 and not math.isnan(v)):
                raise InputError(f"WheelLimits.{name} must be a number > 0 (inf: no limit), got {v!r}")


@dataclass(frozen=True)
class PathRates:
    """What the limits see along a path: the wheel speeds per unit path speed and their
    derivative, at every sample.

    Attributes
    ----------
    w : ndarray, shape (n, n_wheels)
        ``omega / sdot`` [rad/m].
    dw : ndarray, shape (n, n_wheels)
        ``d w / ds`` [rad/m^2].
    steer : ndarray, shape (n, n_steer)
        Steering angles [rad] the path needs.
    dsteer : ndarray, shape (n, n_steer)
        ``d beta / ds`` [rad/m].
    """

    w: np.ndarray
    dw: np.ndarray
    steer: np.ndarray
    dsteer: np.ndarray


def path_rates(robot: Robot, path: Path) -> PathRates:
    """:class:`PathRates` of ``robot`` along ``path`` (module docstring).

    Raises
    ------
    InputError
        The robot cannot drive the path: a fixed wheel would slide (a layout that cannot strafe
        on a path that needs it) or a steering leaves its limits, named with the path length
        ``s`` [m] where it first happens.
    """
    th = path.pose[:, 2]
    body = body_rates(path)
    res = robot.ik(body, on_infeasible="return")
    # a slide below 1e-4 of the path's travel is the finite differences' (a figure-eight's
    # tangent differs from its 2 mm chords by a few 1e-6): a path that needs sideways motion
    # needs it at the size of its travel
    scale = max(1e-6, 1e-4 * float(np.max(np.abs(body[:, :2]), initial=0.0)))
    slide = np.abs(res.violation) > scale if res.violation.size else np.zeros((len(th), 0), dtype=bool)
    bad = np.flatnonzero(np.any(slide, axis=1) | np.any(res.steer_limited, axis=1))
    if bad.size:
        k = int(bad[0])
        why = (
            "it cannot move sideways there (a fixed wheel would slide)"
            if np.any(slide[k])
            else "a steered wheel would leave its steering limits"
        )
        raise InputError(
            f"robot {robot.name!r} cannot drive path {path.name!r}: at s = {path.s[k]:.6g} m "
            f"(x {path.pose[k, 0]:.6g} m, y {path.pose[k, 1]:.6g} m) {why}"
        )
    w = res.wheel_speeds
    steer = res.steer_angles
    dw = derivative(path, w)
    dsteer = derivative(path, np.unwrap(steer, axis=0)) if steer.shape[1] else np.zeros_like(steer)
    return PathRates(w, dw, steer, dsteer)


def speed_ceiling(rates: PathRates, speed: np.ndarray, steer_rate: float) -> np.ndarray:
    """Largest ``x = sdot^2`` [m^2/s^2] at each sample from the speed limits ``(n_wheels,)``
    [rad/s] and the steering rate [rad/s] alone (the maximum velocity curve)."""
    with np.errstate(divide="ignore", over="ignore"):  # (a row near zero: no bound from it)
        x = np.min((speed / np.abs(rates.w)) ** 2, axis=1, initial=np.inf)
        if rates.dsteer.shape[1] and math.isfinite(steer_rate):
            x = np.minimum(x, np.min((steer_rate / np.abs(rates.dsteer)) ** 2, axis=1))
    return x


def _row_lines(a: np.ndarray, b: np.ndarray, accel: float | np.ndarray):
    """The acceleration rows ``|a u + b x| <= accel`` as bounds on ``u`` linear in ``x``:
    ``u >= p + q x`` and ``u <= -p + q x`` with ``p = -accel/|a|``, ``q = -b/a`` (rows with
    ``a = 0`` bound ``x`` alone: returned as ``xcap``)."""
    zero = np.abs(a) < 1e-12
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        p = np.where(zero, -np.inf, -accel / np.abs(a))
        q = np.where(zero, 0.0, -b / a)
        xcap = np.where(zero & (np.abs(b) > 0), accel / np.abs(b), np.inf)
    return p, q, np.min(xcap, axis=1, initial=np.inf)


STATIC_CAP_BLOCK = 2048
"""Samples :func:`_static_cap` compares rows of at a time (its work is ``rows^2`` per sample:
in blocks, its memory stays some 2048 rows^2 numbers whatever the path's length)."""


def _static_cap(p: np.ndarray, q: np.ndarray, ds: np.ndarray) -> np.ndarray:
    """Largest ``x_i`` for which some ``u`` meets every row and ``x_{i+1} >= 0``, the rows being
    ``u in [p + q x, -p + q x]`` ``(n, m)``: every lower bound against every upper one,
    ``(q_k - q_m) x <= -p_m - p_k``, and ``u >= -x / (2 ds)`` (the interval does not end below
    rest) against every upper one; :data:`STATIC_CAP_BLOCK` samples at a time."""
    out = np.empty(len(p))
    for a in range(0, len(p), STATIC_CAP_BLOCK):
        b = slice(a, a + STATIC_CAP_BLOCK)
        pb, qb = p[b], q[b]
        dq = qb[:, :, None] - qb[:, None, :]  # lower k against upper m
        room = -pb[:, None, :] - pb[:, :, None]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            cap = np.where(dq > 0, room / dq, np.inf)
            # u >= -x/(2 ds) against u <= -p_m + q_m x:  (-1/(2ds) - q_m) x <= -p_m
            c2 = -1.0 / (2 * ds[b])[:, None] - qb
            cap2 = np.where(c2 > 0, -pb / c2, np.inf)
        out[b] = np.minimum(
            np.min(cap.reshape(len(pb), -1), axis=1, initial=np.inf), np.min(cap2, axis=1, initial=np.inf)
        )
    return out


@dataclass(frozen=True)
class Timing:
    """The fastest timing of a path (:func:`time_optimal`).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] at the path's samples, from 0.
    sdot : ndarray, shape (n,)
        Path speed [m/s] at the samples.
    sddot : ndarray, shape (n,)
        Path acceleration [m/s^2] over the interval after each sample (0 at the last).
    ceiling : ndarray, shape (n,)
        Largest path speed [m/s] from which the end is still reached at rest.
    """

    t: np.ndarray
    sdot: np.ndarray
    sddot: np.ndarray
    ceiling: np.ndarray

    @property
    def duration(self) -> float:
        """Time [s] from start to end."""
        return float(self.t[-1])


def body_rows(path: Path, body: MotionLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The limits of the body's motion (a runtime's :class:`~omnikin.motion.limits.MotionLimits`:
    the speed ``hypot(vx, vy)``, the turn rate ``|omega|`` and their accelerations) as rows along
    ``path`` for :func:`time_rates`, from the body twist per unit path speed ``xi(s)``
    (:func:`~omnikin.control.path.body_rates`, body frame, as the runtime's command filter sees
    it):

    - speed: ``hypot(xi_x, xi_y) sdot <= linear`` (no acceleration of its own);
    - turn: ``|xi_w sdot| <= angular`` and ``|xi_w sddot + xi_w' sdot^2| <= angular_accel``;
    - linear acceleration ``|xi_xy sddot + xi_xy' sdot^2| <= linear_accel``: the rows of
      :data:`ACCEL_DIRECTIONS` directions (no speed limit of their own).

    ``body.wheel`` is not among them (a wheel limit is :class:`WheelLimits`'). Returns the rows
    ``(n, m)``, their speed limits ``(m,)`` and their acceleration limits ``(m,)`` (``inf``:
    none)."""
    xi = body_rates(path)
    rows, speed, accel = [], [], []
    if body.linear is not None:
        rows.append(np.hypot(xi[:, 0], xi[:, 1]))
        speed.append(body.linear)
        accel.append(math.inf)
    if body.angular is not None or body.angular_accel is not None:
        rows.append(xi[:, 2])
        speed.append(math.inf if body.angular is None else body.angular)
        accel.append(math.inf if body.angular_accel is None else body.angular_accel)
    if body.linear_accel is not None:
        phi = np.pi * np.arange(ACCEL_DIRECTIONS) / ACCEL_DIRECTIONS
        rows.extend(list((xi[:, :1] * np.cos(phi) + xi[:, 1:2] * np.sin(phi)).T))
        speed.extend([math.inf] * ACCEL_DIRECTIONS)
        accel.extend([body.linear_accel * math.cos(math.pi / (2 * ACCEL_DIRECTIONS))] * ACCEL_DIRECTIONS)
    w = np.column_stack(rows) if rows else np.zeros((len(path.s), 0))
    return w, np.array(speed, dtype=float), np.array(accel, dtype=float)


def time_optimal(
    robot: Robot, path: Path, limits: WheelLimits | None = None, body: MotionLimits | None = None
) -> Timing:
    """The fastest timing of ``path`` by ``robot`` from rest to rest, every wheel within
    ``limits`` and the body within ``body`` (module docstring), stopping where the path says
    (``path.stops``).

    Parameters
    ----------
    robot : Robot
        The robot whose wheels turn (its Jacobian; a wheel's own ``max_speed`` applies).
    path : Path
        The path, with its samples and derivatives.
    limits : WheelLimits, optional
        Default :class:`WheelLimits` ().
    body : MotionLimits, optional
        Limits of the body's speed, turn rate and their accelerations, as a runtime's command
        filter applies them (:func:`body_rows`); its ``wheel`` limits the wheel speeds too.
        Default none.

    Returns
    -------
    Timing
        Time, path speed and acceleration at the samples.

    Raises
    ------
    InputError
        A path the robot cannot drive (:func:`path_rates`), or no limit that bounds its speed.
    """
    limits = WheelLimits() if limits is None else limits
    rates = path_rates(robot, path)
    wheel = limits.speed if body is None or body.wheel is None else min(limits.speed, body.wheel)
    speed = np.array([min(wheel, w.max_speed or math.inf) for w in robot.rolling])
    accel = np.full(len(speed), float(limits.accel))
    if body is not None:
        rows, body_speed, body_accel = body_rows(path, body)
        rates = PathRates(
            np.column_stack((rates.w, rows)),
            np.column_stack((rates.dw, derivative(path, rows))),
            rates.steer,
            rates.dsteer,
        )
        speed = np.concatenate((speed, body_speed))
        accel = np.concatenate((accel, body_accel))
    return time_rates(path, rates, speed, accel, limits.steer_rate)


def time_rates(path: Path, rates: PathRates, speed, accel, steer_rate: float = math.inf) -> Timing:
    """The fastest timing of ``path`` from rest to rest under rows of any meaning: each row ``j``
    of ``rates.w`` (a rate per unit path speed, ``rates.dw`` its derivative) kept within
    ``|w_j sdot| <= speed_j`` and ``|w_j sddot + w_j' sdot^2| <= accel_j`` (module docstring).
    :func:`time_optimal` gives it the wheels' rows; other limits of the body's motion written as
    rows (a box or a polygon of twists, :mod:`omnikin.control.twist_limits`) are timed the same way.

    Parameters
    ----------
    path : Path
        The path (its samples, lengths and stops).
    rates : PathRates
        The rows ``(n, rows)`` along the path and their derivatives; steering angles and their
        derivative ``(n, n_steer)``.
    speed : array_like, shape (rows,)
        The speed limit of each row (``inf``: none).
    accel : float or array_like, shape (rows,)
        The acceleration limit of every row, or of each (``inf``: none).
    steer_rate : float, default inf
        Largest steering rate [rad/s].

    Returns
    -------
    Timing

    Raises
    ------
    InputError
        No limit bounds the path speed somewhere (every row's limits infinite there).
    """
    speed = np.asarray(speed, dtype=float)
    accel = np.broadcast_to(np.asarray(accel, dtype=float), speed.shape)
    ds = np.diff(path.s)
    n = len(path.s)
    xmax = speed_ceiling(rates, speed, steer_rate)
    held = np.isfinite(accel)  # the rows with an acceleration limit
    p, q, xcap = _row_lines(rates.w[:, held], rates.dw[:, held], accel[held])
    xmax = np.minimum(xmax, xcap)
    xmax[:-1] = np.minimum(xmax[:-1], _static_cap(p[:-1], q[:-1], ds))
    xmax[path.stops] = 0.0
    # backward pass: the controllable sets [0, xbar_i]
    # u <= (xbar_{i+1} - x) / (2 ds) against each lower bound u >= p_k + q_k x:
    #   (1 + 2 ds q_k) x <= xbar_{i+1} - 2 ds p_k
    coef = 1.0 + 2.0 * ds[:, None] * q[:-1]
    with np.errstate(over="ignore", invalid="ignore"):
        off = -2.0 * ds[:, None] * p[:-1]
        valid = coef > 0
        inv = np.where(valid, 1.0 / np.where(valid, coef, 1.0), 0.0)
        off_over = np.where(valid, off * inv, np.inf)
    xbar = np.empty(n)
    xbar[-1] = 0.0
    xm = xmax.tolist()
    inv_l = inv.tolist()
    off_l = off_over.tolist()
    nxt = 0.0
    for i in range(n - 2, -1, -1):
        best = xm[i]
        for a_, o_ in zip(inv_l[i], off_l[i], strict=True):
            v = nxt * a_ + o_
            if v < best:
                best = v
        nxt = best if best > 0.0 else 0.0
        xbar[i] = nxt
    # forward pass: the largest acceleration that stays controllable
    x = np.empty(n)
    u = np.zeros(n)
    x[0] = 0.0
    up_p = (-p[:-1]).tolist()
    up_q = q[:-1].tolist()
    xb = xbar.tolist()
    ds_l = ds.tolist()
    cur = 0.0
    for i in range(n - 1):
        two = 2.0 * ds_l[i]
        ui = (xb[i + 1] - cur) / two
        for pp, qq in zip(up_p[i], up_q[i], strict=True):
            v = pp + qq * cur
            if v < ui:
                ui = v
        new = cur + two * ui
        if new < 0.0:
            new = 0.0
        elif new > xb[i + 1]:
            new = xb[i + 1]
        u[i] = (new - cur) / two
        cur = new
        x[i + 1] = cur
    if not np.all(np.isfinite(x)):
        k = int(np.argmax(~np.isfinite(x)))
        raise InputError(
            f"path {path.name!r}: nothing limits the speed at s = {path.s[k]:.6g} m (every limit there is infinite)"
        )
    sdot = np.sqrt(x)
    mean = sdot[:-1] + sdot[1:]
    if np.any(mean <= 0):
        k = int(np.argmax(mean <= 0))
        raise InputError(f"path {path.name!r}: the robot cannot move at s = {path.s[k]:.6g} m within the wheel limits")
    t = np.concatenate(([0.0], np.cumsum(2.0 * ds / mean)))
    return Timing(t, sdot, u, np.sqrt(xbar))
