"""Model predictive tracking with the wheel limits as constraints (:class:`PoseMPC`), solved by
OSQP (Stellato et al., "OSQP: an operator splitting solver for quadratic programs", Math. Prog.
Comp. 12, 2020), after the linear time-varying MPC of omni robots of Wang et al. ("Trajectory
Tracking of an Omni-Directional Wheeled Mobile Robot Using a Model Predictive Control Strategy",
Applied Sciences 8, 2018), here on the SE(2) error and in wheel space for any layout whose wheels
do not steer.

At each tick ``t_0`` (period ``dt``), with the pose ``p`` the robot has (its odometry), the
references ``r_k = r(t_0 + k dt)``, ``k = 0..N`` (``N`` the horizon) and the reference's chord
twists ``xi_k = log(r_k^{-1} r_{k+1}) / dt`` (body frame):

    e_0     = log(r_0^{-1} p)                              the error in the reference's frame
    e_{k+1} = A_k e_k + dt N z_k,   A_k = Ad(exp(-xi_k dt))   its prediction, first order in e, z
    command = xi_0 + N z_0                                  the body twist held for one period

``z_k`` (``(m,)``) is the correction to the feedforward twist in the basis ``N`` ``(3, m)`` of
the twists the layout can make (the identity for omni and mecanum robots, the admissible basis
of the fixed wheels for a differential drive), ``Ad(x, y, theta) = [[R(theta), (y, -x)^T],
[0, 0, 1]]`` the adjoint of SE(2). The controller minimises

    sum_{k=1..N} e_k^T Q e_k  +  sum_{k=0..N-1} z_k^T R z_k

subject to every wheel's speed and acceleration limit at every step of the horizon,

    |J (xi_k + N z_k)| <= W,        |J (xi_k + N z_k) - J (xi_{k-1} + N z_{k-1})| <= A dt,

(``J`` the wheel Jacobian, ``xi_{-1} + N z_{-1}`` the twist commanded last), a quadratic
programme in the ``m N`` corrections once the errors are eliminated (``e_k = Phi_k e_0 + sum_j
Gamma_kj z_j``). Its matrix ``P`` changes with the reference, its constraint matrix does not, so
OSQP is set up once and updated each tick, warm-started from the last solution. If OSQP does not
solve a tick (an acceleration limit the last command already broke), the command is the
feedforward alone and the tick is counted in :attr:`PoseMPC.fallbacks`.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import compose, exp, inverse, log
from .trajectory import Trajectory, control_period

HORIZON = 20
"""Steps ``N`` of the prediction."""

ERROR_WEIGHT = (1e4, 1e4, 1e3)
"""Diagonal of ``Q``: a 1 cm or a 0.03 rad error costs about 1."""

CORRECTION_WEIGHT = (1.0, 1.0, 0.04)
"""Diagonal of ``R`` (``N`` the identity; a correction of 0.1 m/s or 0.5 rad/s costs 0.01)."""


def adjoint(pose) -> np.ndarray:
    """``Ad(T)`` ``(..., 3, 3)`` of SE(2) poses ``T = (x, y, theta)`` ``(..., 3)``: the map of a
    twist ``(vx, vy, omega)`` given in ``T``'s frame into its parent's, ``(R (vx, vy) + omega
    (y, -x), omega)``."""
    p = np.asarray(pose, dtype=float)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    out = np.zeros(p.shape[:-1] + (3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = c, -s, p[..., 1]
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = s, c, -p[..., 0]
    out[..., 2, 2] = 1.0
    return out


class PoseMPC:
    """Model predictive tracking under the wheel limits (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot; its wheels must not steer.
    trajectory : Trajectory
        The timed reference; its :class:`~omnikin.control.time_optimal.WheelLimits` are the
        constraints (speed [rad/s], acceleration [rad/s^2]).
    rate : float
        Control rate [Hz]: ``dt = 1 / rate``.
    horizon : int, default 20
        Steps ``N`` of the prediction, 1 to 200.

    Attributes
    ----------
    fallbacks : int
        Ticks OSQP did not solve, commanded by the feedforward alone.
    solve_seconds : list of float
        OSQP's own solve time per tick [s] (the machine's pace: for reports only).

    Raises
    ------
    InputError
        A steerable layout, a rate or horizon out of range.
    """

    name = "mpc"

    def __init__(self, robot: Robot, trajectory: Trajectory, *, rate: float, horizon: int = HORIZON):
        import scipy.sparse as sparse

        try:
            import osqp
        except ImportError:
            raise InputError("the MPC needs OSQP: pip install 'omnikin[control]'") from None
        if robot.steerable:
            raise InputError(
                f"robot {robot.name!r} steers its wheels: the MPC's wheel constraints are linear only for wheels "
                "that do not steer (pure pursuit drives a car; the feedback controller a layout that steers all "
                "its wheels)"
            )
        if isinstance(horizon, bool) or not isinstance(horizon, int) or not 1 <= horizon <= 200:
            raise InputError(f"horizon must be a whole number of steps in [1, 200], got {horizon!r}")
        self.robot = robot
        self.trajectory = trajectory
        self.dt = control_period(rate)
        self.horizon = horizon
        self.basis = np.eye(3) if not robot.fixed else np.asarray(robot.admissible_basis, dtype=float)
        self.jacobian = np.asarray(robot.ik_matrix, dtype=float)
        self.fallbacks = 0
        self.solve_seconds: list[float] = []
        self._last = np.zeros(3)  # the twist commanded last (at rest before the first tick)
        n, m = self.horizon, self.basis.shape[1]
        wheels = len(self.jacobian)
        self._q = np.diag(np.tile(ERROR_WEIGHT, n))
        weights = np.asarray(CORRECTION_WEIGHT, dtype=float)
        self._r = np.diag(np.tile(np.diag(self.basis.T @ np.diag(weights) @ self.basis), n))
        # constraints on the corrections z (m N): wheel speeds at each step, then their changes
        jn = self.jacobian @ self.basis
        speed = sparse.block_diag([jn] * n)
        change = sparse.lil_matrix((wheels * n, m * n))
        for k in range(n):
            change[k * wheels : (k + 1) * wheels, k * m : (k + 1) * m] = jn
            if k:
                change[k * wheels : (k + 1) * wheels, (k - 1) * m : k * m] = -jn
        self._a = sparse.vstack([speed, change.tocsc()], format="csc")
        # P's pattern: its whole upper triangle, kept even where a value is zero
        rows, cols = np.triu_indices(m * n)
        order = np.lexsort((rows, cols))  # column by column, rows increasing: CSC
        self._p_rows, self._p_cols = rows[order], cols[order]
        indptr = np.concatenate(([0], np.cumsum(np.bincount(self._p_cols, minlength=m * n))))
        self._p_pattern = (self._p_rows, indptr)
        self._solver = osqp.OSQP()
        self._setup = False
        self._osqp = osqp
        self._sparse = sparse

    def _matrices(self, t: float, pose: np.ndarray):
        """The reference twists ``(N, 3)``, ``e_0``, and the prediction ``e = Phi e_0 + Gamma z``
        stacked over the horizon: ``Phi`` ``(3N, 3)``, ``Gamma`` ``(3N, mN)``."""
        n, m, dt = self.horizon, self.basis.shape[1], self.dt
        ref, _, _ = self.trajectory.at(t + dt * np.arange(n + 1))
        xi = log(compose(inverse(ref[:-1]), ref[1:])) / dt
        if self.robot.fixed:  # the chords of a curve the layout drives leave it by rounding: onto N
            xi = xi @ self.basis @ self.basis.T
        e0 = log(compose(inverse(ref[0]), pose))
        phi = np.zeros((3 * n, 3))
        gamma = np.zeros((3 * n, m * n))
        step = dt * self.basis
        a_all = adjoint(exp(-xi * dt))  # (N, 3, 3)
        a_prev = np.eye(3)
        for k in range(n):  # e_{k+1} = A_k e_k + dt N z_k
            a_k = a_all[k]
            a_prev = a_k @ a_prev
            phi[3 * k : 3 * k + 3] = a_prev
            if k:
                gamma[3 * k : 3 * k + 3, : m * k] = a_k @ gamma[3 * (k - 1) : 3 * k, : m * k]
            gamma[3 * k : 3 * k + 3, m * k : m * (k + 1)] = step
        return xi, e0, phi, gamma

    def _bounds(self, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        limits = self.trajectory.limits
        wheel = xi @ self.jacobian.T  # (N, wheels): the feedforward's wheel speeds
        w = limits.speed * (1.0 + 1e-9)  # (the reference reaches the limit to rounding)
        speed_lo, speed_hi = (-w - wheel).ravel(), (w - wheel).ravel()
        room = limits.accel * self.dt * (1.0 + 1e-9)
        before = np.vstack((self.jacobian @ self._last, wheel[:-1]))
        change = wheel - before  # the feedforward's own change, step by step
        return np.concatenate((speed_lo, -room - change.ravel())), np.concatenate((speed_hi, room - change.ravel()))

    def command(self, t: float, pose) -> np.ndarray:
        """The body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] to hold from ``t`` [s] for one
        period, the robot at ``pose`` ``(x, y, theta)`` [m, m, rad] (world frame)."""
        p = np.asarray(pose, dtype=float)
        xi, e0, phi, gamma = self._matrices(t, p)
        hessian = 2.0 * (gamma.T @ self._q @ gamma + self._r)
        linear = 2.0 * gamma.T @ self._q @ (phi @ e0)
        lower, upper = self._bounds(xi)
        values = hessian[self._p_rows, self._p_cols]
        start = time.perf_counter()
        if not self._setup:
            size = hessian.shape[0]
            p_matrix = self._sparse.csc_matrix((values, *self._p_pattern), shape=(size, size))
            self._solver.setup(
                P=p_matrix, q=linear, A=self._a, l=lower, u=upper, verbose=False, eps_abs=1e-6, eps_rel=1e-6,
                polishing=False, max_iter=4000,
            )  # fmt: skip
            self._setup = True
        else:
            self._solver.update(Px=values, q=linear, l=lower, u=upper)
        result = self._solver.solve(raise_error=False)  # (a status to read, not an exception)
        self.solve_seconds.append(time.perf_counter() - start)
        solved = (self._osqp.SolverStatus.OSQP_SOLVED, self._osqp.SolverStatus.OSQP_SOLVED_INACCURATE)
        if result.info.status_val not in solved:
            self.fallbacks += 1
            twist = self.basis @ (self.basis.T @ xi[0])  # the feedforward, as the layout can make it
        else:
            twist = xi[0] + self.basis @ result.x[: self.basis.shape[1]]
        self._last = twist
        return twist
