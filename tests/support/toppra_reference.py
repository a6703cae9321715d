"""toppra (Pham & Pham's reachability analysis, an independent implementation) solving the
time-optimal timing of a path under wheel limits, given the wheel rows along the path: the
reference of the control tests and of ``benchmarks/bench_control.py``."""

from __future__ import annotations

import numpy as np


def toppra_sdot(s, w, dw, speed: float, accel: float) -> np.ndarray:
    """toppra's path speed [m/s] at the grid ``s`` ``(n,)``, rest to rest, for wheels turning at
    ``w sdot`` with accelerations ``w sddot + dw sdot^2`` (``w``, ``dw`` ``(n, m)``), every one
    within ``speed`` [rad/s] and ``accel`` [rad/s^2] (collocation: each grid point's limits
    hold there)."""
    import toppra
    import toppra.algorithm
    import toppra.constraint as tc

    n, m = w.shape

    class WheelRows(tc.LinearConstraint):
        def __init__(self):
            super().__init__()
            self.dof = 3
            self.identical = True
            self.discretization_type = tc.DiscretizationType.Collocation

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            with np.errstate(divide="ignore"):
                xmax = np.min((speed / np.abs(w)) ** 2, axis=1)
            xbound = np.column_stack((np.zeros(n), xmax))
            return w, dw, np.zeros((n, m)), np.vstack((np.eye(m), -np.eye(m))), np.full(2 * m, accel), None, xbound

    unused = toppra.SplineInterpolator(np.linspace(s[0], s[-1], 5), np.zeros((5, 3)))
    algorithm = toppra.algorithm.TOPPRA([WheelRows()], unused, gridpoints=s, solver_wrapper="seidel")
    _, sd, _, _ = algorithm.compute_parameterization(0, 0, return_data=True)
    return np.asarray(sd)


def duration(s, sdot) -> float:
    """Time [s] along the grid ``s`` at path speeds ``sdot`` (constant acceleration between points)."""
    return float(np.sum(2 * np.diff(s) / (sdot[:-1] + sdot[1:])))
