"""Rank-revealing helpers shared by the model layers (NumPy SVD, relative tolerance)."""

from __future__ import annotations

import numpy as np

RANK_TOL = 1e-9
"""Singular values below ``RANK_TOL * max(1, s_max)`` count as zero."""


def rank(matrix: np.ndarray, tol: float = RANK_TOL) -> int:
    """Numerical rank of a 2-D matrix (0 for an empty one)."""
    if matrix.size == 0:
        return 0
    s = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(s > tol * max(1.0, s[0])))


def null_space(matrix: np.ndarray, cols: int, tol: float = RANK_TOL) -> np.ndarray:
    """Orthonormal basis ``(cols, k)`` of the null space of ``matrix`` ``(m, cols)``."""
    if matrix.size == 0:
        return np.eye(cols)
    _, s, vt = np.linalg.svd(matrix)
    r = int(np.sum(s > tol * max(1.0, s[0])))
    return vt[r:].T.copy()
