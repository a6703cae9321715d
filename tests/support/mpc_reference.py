"""The model predictive controller's programme written independently (:func:`reference_correction`):
the errors kept as variables with the dynamics as equalities (not eliminated as the controller
does), the adjoint from homogeneous matrices (not its closed form), solved by Clarabel (interior
point, not OSQP). The MPC tests compare the controller's correction with it; the benchmark times it
as the reference formulation."""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sparse

from omnikin.control.mpc import CORRECTION_WEIGHT, ERROR_WEIGHT, PoseMPC
from omnikin.kinematics.se2 import compose, exp, inverse, log


def se2_adjoint(pose) -> np.ndarray:
    """Ad(T): the twist (v, omega) in T's frame seen from T's parent; from T (v, omega) T^-1 written
    out as 3x3 homogeneous matrices (not the closed form of the module)."""
    x, y, theta = pose
    c, s = math.cos(theta), math.sin(theta)
    t = np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])
    columns = []
    for k in range(3):
        twist = np.zeros(3)
        twist[k] = 1.0
        hat = np.array([[0.0, -twist[2], twist[0]], [twist[2], 0.0, twist[1]], [0.0, 0.0, 0.0]])
        moved = t @ hat @ np.linalg.inv(t)
        columns.append([moved[0, 2], moved[1, 2], moved[1, 0]])
    return np.array(columns).T


def reference_correction(controller: PoseMPC, t: float, pose, last) -> np.ndarray:
    """The first correction ``z_0`` of the module docstring's programme, with the errors as
    variables: minimise sum e_k^T Q e_k + z_k^T R z_k over (z_0..z_{N-1}, e_1..e_N) subject to
    e_{k+1} = A_k e_k + dt N z_k and the wheel limits, solved by Clarabel."""
    import clarabel

    robot, n, dt = controller.robot, controller.horizon, controller.dt
    basis = np.eye(3) if not robot.fixed else np.asarray(robot.admissible_basis)
    m = basis.shape[1]
    jac = np.asarray(robot.ik_matrix)
    wheels = len(jac)
    ref = np.array([controller.trajectory.at(t + k * dt)[0] for k in range(n + 1)])
    xi = np.array([log(compose(inverse(ref[k]), ref[k + 1])) / dt for k in range(n)])
    if robot.fixed:
        xi = xi @ basis @ basis.T
    e0 = log(compose(inverse(ref[0]), pose))
    nz, ne = m * n, 3 * n
    hessian = np.zeros((nz + ne, nz + ne))
    for k in range(n):
        hessian[k * m : (k + 1) * m, k * m : (k + 1) * m] = basis.T @ np.diag(CORRECTION_WEIGHT) @ basis
        hessian[nz + 3 * k : nz + 3 * k + 3, nz + 3 * k : nz + 3 * k + 3] = np.diag(ERROR_WEIGHT)
    hessian *= 2.0
    rows, lower, upper = [], [], []
    for k in range(n):  # dynamics: e_{k+1} - A_k e_k - dt N z_k = (k == 0: A_0 e_0)
        row = np.zeros((3, nz + ne))
        row[:, nz + 3 * k : nz + 3 * k + 3] = np.eye(3)
        row[:, k * m : (k + 1) * m] = -dt * basis
        a_k = se2_adjoint(exp(-xi[k] * dt))
        rhs = a_k @ e0 if k == 0 else np.zeros(3)
        if k:
            row[:, nz + 3 * (k - 1) : nz + 3 * k] = -a_k
        rows.append(row)
        lower.append(rhs)
        upper.append(rhs)
    limits = controller.trajectory.limits
    for k in range(n):  # speeds
        row = np.zeros((wheels, nz + ne))
        row[:, k * m : (k + 1) * m] = jac @ basis
        feed = jac @ xi[k]
        rows.append(row)
        lower.append(-limits.speed * (1 + 1e-9) - feed)
        upper.append(limits.speed * (1 + 1e-9) - feed)
    for k in range(n):  # changes
        row = np.zeros((wheels, nz + ne))
        row[:, k * m : (k + 1) * m] = jac @ basis
        before = jac @ (last if k == 0 else xi[k - 1])
        if k:
            row[:, (k - 1) * m : k * m] = -jac @ basis
        room = limits.accel * dt * (1 + 1e-9)
        rows.append(row)
        lower.append(-room - (jac @ xi[k] - before))
        upper.append(room - (jac @ xi[k] - before))
    a = np.vstack(rows)
    lo, hi = np.concatenate(lower), np.concatenate(upper)
    # Clarabel: A x + s = b, s in cones; equalities in the zero cone, l <= A x <= u as two halves
    n_eq = 3 * n
    a_all = np.vstack((a[:n_eq], a[n_eq:], -a[n_eq:]))
    b_all = np.concatenate((lo[:n_eq], hi[n_eq:], -lo[n_eq:]))
    cones = [clarabel.ZeroConeT(n_eq), clarabel.NonnegativeConeT(2 * (len(lo) - n_eq))]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solver = clarabel.DefaultSolver(
        sparse.csc_matrix(np.triu(hessian)), np.zeros(nz + ne), sparse.csc_matrix(a_all), b_all, cones, settings
    )
    solution = solver.solve()
    assert str(solution.status) == "Solved"
    return np.asarray(solution.x[:m])
