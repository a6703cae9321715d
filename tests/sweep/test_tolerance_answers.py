"""The answer of a tolerance study: the largest tolerance at which the quantile of E_max,syst
stays below the target, checked against closed forms (E = c * scale exactly: threshold target / c;
E = c * scale^2: sqrt(target / c)) and hand-worked interpolations."""

from __future__ import annotations

import math

import pytest

from omnikin.evaluation.threshold import ABOVE, ABOVE_FIRST, BELOW, CROSSES, threshold
from omnikin.sweep.points import Point
from omnikin.sweep.summary import answers, series_of, summarize
from support.sweep_tables import grid, make_study, proportional_table, trial_table

SCALES = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)


def test_proportional_error_crosses_at_target_over_c_before_and_after():
    points = grid(scales=SCALES)
    study = make_study(points, trials=80, target=0.010)
    found = answers(summarize(proportional_table(points, 0.008, 0.002, 80), study), study)
    by_phase = {a.phase: a for a in found}
    assert set(by_phase) == {"before", "after"}
    assert by_phase["before"].estimate.status == CROSSES
    assert by_phase["before"].estimate.value == pytest.approx(0.010 / 0.008)
    assert by_phase["after"].estimate.value == pytest.approx(0.010 / 0.002)
    # 80 identical trials: the interval's upper end is the value itself
    assert by_phase["before"].conservative.value == pytest.approx(0.010 / 0.008)
    assert by_phase["before"].estimate.interpolation == "log-log"


def test_scale_answer_is_expressed_as_the_three_tolerances():
    points = grid(scales=SCALES, radius=0.004, hub=0.002, drive_deg=0.3)
    study = make_study(points, trials=80)
    before = answers(summarize(proportional_table(points, 0.008, 0.002, 80), study), study)[0]
    s = 0.010 / 0.008
    assert before.tolerances(before.estimate.value) == pytest.approx((s * 0.4, s * 2.0, s * 0.3))


def test_power_law_is_interpolated_exactly_in_log_log():
    points = grid(scales=SCALES)
    study = make_study(points, trials=3, target=0.010)
    table = trial_table((p, k, 0.004 * p.scale**2, math.nan, None) for p in points for k in range(3))
    before = answers(summarize(table, study), study)[0]
    assert before.estimate.value == pytest.approx(math.sqrt(0.010 / 0.004))


def test_conservative_answer_stops_at_the_last_bounded_point_with_too_few_trials():
    # 10 trials cannot bound the 95th percentile from above: every upper end is unbounded
    points = grid(scales=SCALES)
    study = make_study(points, trials=10)
    before = answers(summarize(proportional_table(points, 0.008, 0.002, 10), study), study)[0]
    assert before.estimate.value == pytest.approx(1.25)
    assert before.conservative.status == ABOVE and before.conservative.value is None


def test_linear_interpolation_when_a_quantile_is_zero():
    crossing = threshold([0.0, 1.0, 2.0], [0.0, 0.004, 0.016], 0.010)
    assert crossing.interpolation == "linear"
    assert crossing.value == pytest.approx(1.0 + (0.010 - 0.004) / (0.016 - 0.004))


def test_interpolated_value_lies_between_the_grid_points_around_the_crossing():
    for k in (0.8, 1.0, 3.0):
        c = threshold(SCALES, [0.002 * s**k for s in SCALES], 0.010)
        below = max(s for s in SCALES if 0.002 * s**k < 0.010)
        above = min(s for s in SCALES if 0.002 * s**k >= 0.010)
        assert below <= c.value <= above
        assert c.value == pytest.approx((0.010 / 0.002) ** (1 / k))  # power law: exact in log-log


def test_statuses_below_above_and_not_monotone():
    below = threshold([1, 2, 3], [0.001, 0.002, 0.003], 0.010)
    assert (below.status, below.value) == (BELOW, 3.0)
    above = threshold([1, 2, 3], [0.02, 0.03, 0.04], 0.010)
    assert (above.status, above.value, above.first) == (ABOVE, None, (1.0, 0.02))
    first_above = threshold([1, 2, 3], [0.02, 0.005, 0.04], 0.010)
    assert first_above.status == ABOVE_FIRST and "not monotone" in first_above.note
    wiggle = threshold([1, 2, 4, 8], [0.005, 0.020, 0.005, 0.030], 0.010)
    assert wiggle.status == CROSSES and 1 < wiggle.value < 2 and "first crossing" in wiggle.note


def test_series_without_calibration_answers_before_only_and_series_split_by_other_factors():
    points = grid(scales=SCALES, calibrate=False) + grid(scales=SCALES, noise="none")
    study = make_study(points, trials=3)
    labels = [s.label for s in series_of(study)]
    assert labels == ["omni3, noise=typical, calibrate=False", "omni3, noise=none, calibrate=True"]
    table = proportional_table(points, 0.008, 0.002, 3)
    assert [(a.series.label, a.phase) for a in answers(summarize(table, study), study)] == [
        (labels[0], "before"),
        (labels[1], "before"),
        (labels[1], "after"),
    ]


def test_random_design_reads_points_sorted_by_the_axis_as_approximate():
    points = [
        Point(robot="omni3", robot_hash="0123456789abcdef", scale=s, radius=r)
        for s, r in ((3.1, 0.004), (0.7, 0.006), (1.9, 0.005), (0.3, 0.004))
    ]
    study = make_study(points, design="random", trials=3)
    (series,) = series_of(study)
    assert [study.points[i].scale for i in series.rows] == [0.3, 0.7, 1.9, 3.1]
    before = answers(summarize(proportional_table(points, 0.008, 0.002, 3), study), study)[0]
    assert before.approximate and before.estimate.value == pytest.approx(1.25)
    assert before.tolerances(1.25) is None  # radius differs between the points


def test_answer_text_is_one_line_with_the_tolerance_and_its_three_build_tolerances():
    points = grid(robot="omni3\nsecond line", scales=SCALES, radius=0.004, hub=0.002, drive_deg=0.3)
    study = make_study(points, trials=80)
    before = answers(summarize(proportional_table(points, 0.008, 0.002, 80), study), study)[0]
    assert before.text == (
        "omni3 second line, before calibration: scale [-] 1.25 (crosses; radius 0.5 %, hub 2.5 mm, "
        "drive 0.375 deg); conservative: 1.25"
    )
