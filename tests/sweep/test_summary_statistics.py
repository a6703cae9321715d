"""Per-point statistics of a tolerance study: counts, order-statistic intervals with ranks from an
exact binomial sum written out here, NumPy's quantile definition, shares below target."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from omnikin.evaluation.order_statistics import order_statistic_ranks, quantile_interval, values_for_bound
from omnikin.sweep.summary import SUMMARY_COLUMNS, summarize
from support.sweep_tables import grid, make_study, trial_table


def brute_force_ranks(n, q, level):
    """Equal-tailed ranks from exact binomial sums: l the largest with P(B <= l-1) <= alpha/2,
    u the smallest with P(B >= u) <= alpha/2, B ~ Binomial(n, q)."""
    q = Fraction(q).limit_denominator(10**6)
    half = (1 - Fraction(level).limit_denominator(10**6)) / 2

    def pmf(k):
        return math.comb(n, k) * q**k * (1 - q) ** (n - k)

    low = [k for k in range(1, n + 1) if sum(pmf(j) for j in range(k)) <= half]
    high = [k for k in range(1, n + 1) if sum(pmf(j) for j in range(k, n + 1)) <= half]
    return (max(low) if low else None), (min(high) if high else None)


@pytest.mark.parametrize("n", [1, 2, 5, 6, 10, 20, 50, 71, 72, 100, 200])
@pytest.mark.parametrize(("q", "level"), [(0.5, 0.95), (0.95, 0.95), (0.9, 0.9), (0.5, 0.99)])
def test_interval_ranks_equal_an_exact_binomial_sum(n, q, level):
    assert order_statistic_ranks(n, q, level) == brute_force_ranks(n, q, level)


def test_median_interval_of_ten_values_is_the_second_to_ninth():
    # the classic table value (coverage 1 - 2 * 11/1024 = 97.9 %)
    assert order_statistic_ranks(10, 0.5, 0.95) == (2, 9)


def test_upper_end_of_the_95th_percentile_needs_72_trials():
    assert order_statistic_ranks(71, 0.95, 0.95)[1] is None
    assert order_statistic_ranks(72, 0.95, 0.95)[1] == 72
    assert values_for_bound(0.95, 0.95) == 72  # 0.95**72 = 0.0249 <= 0.025 < 0.95**71
    assert values_for_bound(0.5, 0.95) == 6


def test_interval_covers_the_true_quantile_at_least_at_the_level():
    rng = np.random.default_rng(3)
    true_q95 = -math.log(0.05)  # exponential(1)
    hits = 0
    runs = 2000
    for _ in range(runs):
        _, low, high = quantile_interval(rng.exponential(size=120), 0.95, 0.95)
        hits += low <= true_q95 <= high
    assert hits / runs >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / runs)


def test_summary_has_one_row_per_point_in_study_order_with_counts_and_nan_for_missing():
    points = grid(scales=(4.0, 1.0, 2.0))
    study = make_study(points, target=0.010)
    values = [0.001 * v for v in range(1, 11)]
    rows = [(points[0], k, v, v / 10, None) for k, v in enumerate(values)]
    rows += [(points[0], 10, 0, 0, "tolerance_trial: wheel 2 radius <= 0")]
    rows += [(points[2], 0, 0.02, 0.001, None)]
    s = summarize(trial_table(rows), study)
    assert [name for name, _ in SUMMARY_COLUMNS] == list(s)
    assert list(s["scale"]) == [4.0, 1.0, 2.0]
    assert list(s["trials"]) == [11, 0, 1]
    assert list(s["failed"]) == [1, 0, 0]
    # point 0: 1..10 mm; numpy's linear quantile: median 5.5 mm, 95th 9.55 mm (x_(1 + 9 * 0.95))
    assert s["median_before"][0] == pytest.approx(0.0055)
    assert s["quantile_before"][0] == pytest.approx(0.00955)
    assert (s["median_before_low"][0], s["median_before_high"][0]) == pytest.approx((0.002, 0.009))
    assert math.isnan(s["quantile_before_high"][0])  # 10 trials cannot bound the 95th percentile
    assert s["below_before"][0] == pytest.approx(0.9)  # 1..9 mm < 10 mm
    assert s["below_after"][0] == 1.0
    assert s["median_reduction"][0] == pytest.approx(10.0)
    statistics = [name for name, _ in SUMMARY_COLUMNS][[name for name, _ in SUMMARY_COLUMNS].index("failed") + 1 :]
    assert all(math.isnan(s[name][1]) for name in statistics if name != "reduction_bound")
    assert not s["reduction_bound"].any()  # every after-value is 0.1 mm or more
    assert s["median_before"][2] == 0.02 and math.isnan(s["median_before_low"][2])


def test_points_without_calibration_have_nan_after_and_rows_of_other_points_are_not_read():
    points = grid(scales=(1.0,), calibrate=False)
    other = grid(scales=(9.0,))[0]
    s = summarize(trial_table([(points[0], 0, 0.003, math.nan, None), (other, 0, 1.0, 1.0, None)]), make_study(points))
    assert s["trials"][0] == 1 and s["median_before"][0] == 0.003
    assert math.isnan(s["median_after"][0]) and math.isnan(s["median_reduction"][0])


def test_empty_trial_table_gives_points_without_trials():
    points = grid()
    s = summarize(trial_table([]), make_study(points))
    assert list(s["trials"]) == [0] * len(points)
    assert np.isnan(s["quantile_before"]).all()


def test_a_reduction_past_the_reports_resolution_is_a_bound():
    points = grid(scales=(1.0, 2.0))
    study = make_study(points, target=0.010)
    # point 0: after-values far below 0.01 mm (a noise-free calibration); point 1: 2 mm, resolved
    rows = [(points[0], k, 1.4, 1.6e-8 * (k + 1), None) for k in range(3)]
    rows += [(points[1], k, 0.02 * (k + 1), 0.002, None) for k in range(3)]
    s = summarize(trial_table(rows), study)
    assert s["median_reduction"][0] == pytest.approx(1.4 / 1e-5)  # each after counted as 0.01 mm
    assert s["median_reduction"][1] == pytest.approx(20.0)  # 0.04 m / 2 mm
    assert s["reduction_bound"].tolist() == [True, False]
    from omnikin.sweep.report import study_markdown
    from omnikin.sweep.summary import answers

    text = study_markdown(study, s, answers(s, study), figures=[], failures=[])
    rows = [line for line in text.split("## Points")[1].split("\n## ")[0].splitlines() if line.startswith("| omni3")]
    cells = [row.split(" | ")[-1].rstrip(" |") for row in rows]
    assert cells == ["at least 140000", "20"]
