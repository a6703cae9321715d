r"""Distribution-free statistics of a sample's quantiles from its order statistics.

The ``q`` quantile is NumPy's default estimate (linear interpolation between order statistics,
Hyndman and Fan's type 7, "Sample quantiles in statistical packages": ``x_(1 + (n-1) q)``).
Its confidence interval at ``level`` needs no distribution (David and Nagaraja, "Order
Statistics", section 7.1): the number ``B`` of the ``n`` independent values below the true
quantile is binomial ``(n, q)``, so ``[x_(l), x_(u)]`` covers it with probability
``P(l <= B <= u - 1)``. The ranks are equal-tailed: ``l`` the largest with
``P(B <= l - 1) <= alpha/2``, ``u`` the smallest with ``P(B >= u) <= alpha/2``
(``alpha = 1 - level``), so the coverage is at least ``level``. Too few values reach no rank:
that end is unbounded (None; NaN in tables). The 95 % interval of the 95th percentile needs
``0.95^n <= 0.025``, 72 values, for its upper end (:func:`values_for_bound`); the median's
ends need 6.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import binom


def order_statistic_ranks(n: int, q: float, level: float) -> tuple[int | None, int | None]:
    """The 1-based ranks ``(l, u)`` of the order statistics bounding the ``q`` quantile of ``n``
    independent values at confidence ``level`` (module docstring); None for an end no rank reaches
    (``P(B <= 0) > alpha/2`` for the lower, ``P(B >= n) > alpha/2`` for the upper)."""
    if n < 1:
        return None, None
    half = (1.0 - level) / 2.0
    cdf = binom.cdf(np.arange(n + 1), n, q)  # cdf[k] = P(B <= k)
    lower = [k for k in range(1, n + 1) if cdf[k - 1] <= half]
    upper = [k for k in range(1, n + 1) if 1.0 - cdf[k - 1] <= half]
    return (max(lower) if lower else None), (min(upper) if upper else None)


def values_for_bound(q: float, level: float, end: str = "upper") -> int:
    """The fewest values whose order statistics bound the ``q`` quantile at ``level`` at ``end``
    (``upper``: ``q^n <= alpha/2``; ``lower``: ``(1 - q)^n <= alpha/2``)."""
    p = q if end == "upper" else 1.0 - q
    return max(1, math.ceil(math.log((1.0 - level) / 2.0) / math.log(p)))


def quantile_interval(values: np.ndarray, q: float, level: float) -> tuple[float, float, float]:
    """The ``q`` quantile of the finite ``values`` and the ends of its interval at ``level``
    (module docstring): ``(estimate, low, high)``, NaN for an unbounded end or no finite value."""
    x = np.sort(np.asarray(values, dtype=float))
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    low, high = order_statistic_ranks(len(x), q, level)
    return (
        float(np.quantile(x, q)),
        float(x[low - 1]) if low is not None else math.nan,
        float(x[high - 1]) if high is not None else math.nan,
    )
