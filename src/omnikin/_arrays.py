"""Small input checks shared by the core: shapes and finiteness with clear messages."""

from __future__ import annotations

import numpy as np

from .errors import InputError


def as_components(value, size: int, name: str) -> np.ndarray:
    """Return ``value`` as a float array of shape ``(..., size)``.

    Raises :class:`OmnikinError` saying what was expected and what arrived, e.g.
    ``twist: expected shape (..., 3), got (4,)``.
    """
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != size:
        raise InputError(f"{name}: expected shape (..., {size}), got {arr.shape}")
    return arr


def require_finite(arr: np.ndarray, name: str) -> None:
    """Raise if ``arr`` holds NaN or infinity, naming the first bad index."""
    bad = ~np.isfinite(arr)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"{name}: non-finite value {float(arr[index])} at index {index}")
