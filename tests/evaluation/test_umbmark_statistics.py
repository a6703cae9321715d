"""Confidence intervals of E_max,syst and of the reduction factor, and the noise floor.

Expected values: the interval of a direction whose runs have an isotropic sample covariance is
a disc; with n = 4 runs Hotelling's threshold is 2 (n - 1)/(n - 2) F_{2,2}(g) = 3 g / (1 - g)
(the F(2, 2) quantile is p / (1 - p)), so the disc's radius is r sqrt(g / (2 (1 - g))) for runs
at the cg +- r along x and y. Coverage: seeded Gaussian runs around known expected return
positions (the truth is known by construction).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.evaluation.umbmark import analyze, reduction_interval

LEVEL = 0.95


def plus_runs(cg, r):
    """Four runs at cg +- r along x and y: sample covariance (2 r^2 / 3) I."""
    x, y = cg
    return [(x + r, y), (x - r, y), (x, y + r), (x, y - r)]


def disc_radius(r, level):
    """Radius of the Hotelling region of plus_runs (module docstring)."""
    return r * math.sqrt(level / (2 * (1 - level)))


def test_e_max_interval_of_isotropic_runs_is_the_closed_form_disc():
    g = math.sqrt(LEVEL)
    cw, ccw = plus_runs((0.3, -0.4), 0.01), plus_runs((0.1, 0.0), 0.02)
    res = analyze(cw, ccw)
    r_cw, r_ccw = disc_radius(0.01, g), disc_radius(0.02, g)
    low, high = res.e_max_interval(LEVEL)
    # E = max(|mu_cw|, |mu_ccw|): between the larger nearest and the larger farthest distance
    assert low == pytest.approx(max(0.5 - r_cw, 0.1 - r_ccw), rel=1e-6)
    assert high == pytest.approx(max(0.5 + r_cw, 0.1 + r_ccw), rel=1e-6)
    assert low < res.e_max_syst < high


def test_e_max_interval_reaches_zero_when_the_origin_is_inside():
    g = math.sqrt(LEVEL)
    small = plus_runs((0.03, 0.0), 0.02)  # disc radius 0.088 > 0.03
    res = analyze(small, small)
    low, high = res.e_max_interval(LEVEL)
    assert low == 0.0
    assert high == pytest.approx(0.03 + disc_radius(0.02, g), rel=1e-6)


def test_reduction_interval_closed_form_and_unbounded_above():
    g = LEVEL**0.25  # each E at sqrt(level), each direction at its sqrt
    before = analyze(plus_runs((0.3, -0.4), 0.01), plus_runs((0.1, 0.0), 0.02))
    after = analyze(plus_runs((0.004, 0.0), 0.01), plus_runs((0.0, 0.002), 0.01))
    low, high = reduction_interval(before, after, LEVEL)
    b_low = max(0.5 - disc_radius(0.01, g), 0.1 - disc_radius(0.02, g))
    a_high = max(0.004, 0.002) + disc_radius(0.01, g)
    assert low == pytest.approx(b_low / a_high, rel=1e-6)
    assert high == math.inf  # 'after' is consistent with zero


def test_intervals_need_three_runs_per_direction():
    res = analyze([(0.1, 0.0), (0.2, 0.0)], plus_runs((0.1, 0.0), 0.01))
    assert res.e_max_interval() is None
    assert res.as_dict()["e_max_syst_interval"] is None
    assert reduction_interval(res, res) is None


def test_interval_of_noise_free_runs_is_the_point():
    res = analyze([(0.3, 0.4)] * 5, [(0.1, 0.0)] * 5)
    low, high = res.e_max_interval()
    assert low == pytest.approx(0.5, rel=1e-12) and high == pytest.approx(0.5, rel=1e-12)


def gaussian_runs(rng, mean, cov, n):
    return rng.multivariate_normal(mean, cov, size=n)


COV_CW = np.array([[1.2e-4, 0.5e-4], [0.5e-4, 0.8e-4]])  # about 10 mm scatter, correlated
COV_CCW = np.array([[0.6e-4, -0.2e-4], [-0.2e-4, 1.5e-4]])


@pytest.mark.parametrize(
    "mu_cw, mu_ccw",
    [
        ((0.40, -0.50), (0.35, -0.28)),  # far from zero (before calibration)
        ((0.003, 0.001), (-0.002, 0.002)),  # inside the scatter (after calibration)
    ],
)
def test_e_max_interval_covers_the_true_value_at_least_at_its_level(mu_cw, mu_ccw):
    rng = np.random.default_rng(20240501)
    truth = max(math.hypot(*mu_cw), math.hypot(*mu_ccw))
    trials, hits, widths = 1000, 0, []
    for _ in range(trials):
        res = analyze(gaussian_runs(rng, mu_cw, COV_CW, 5), gaussian_runs(rng, mu_ccw, COV_CCW, 5))
        low, high = res.e_max_interval(LEVEL)
        hits += low <= truth <= high
        widths.append(high - low)
    # conservative by construction: at least the level, less three binomial standard deviations
    assert hits / trials >= LEVEL - 3 * math.sqrt(LEVEL * (1 - LEVEL) / trials), hits
    assert np.median(widths) < 0.08  # and not vacuous: a few centimetres


def test_reduction_interval_covers_the_true_factor():
    rng = np.random.default_rng(7)
    mu_b, mu_a = ((0.40, -0.50), (0.35, -0.28)), ((0.006, 0.002), (-0.004, 0.003))
    truth = max(math.hypot(*m) for m in mu_b) / max(math.hypot(*m) for m in mu_a)
    trials, hits = 600, 0
    for _ in range(trials):
        before = analyze(gaussian_runs(rng, mu_b[0], COV_CW, 5), gaussian_runs(rng, mu_b[1], COV_CCW, 5))
        after = analyze(gaussian_runs(rng, mu_a[0], COV_CW, 5), gaussian_runs(rng, mu_a[1], COV_CCW, 5))
        low, high = reduction_interval(before, after, LEVEL)
        hits += low <= truth <= high
    assert hits / trials >= LEVEL - 3 * math.sqrt(LEVEL * (1 - LEVEL) / trials), hits


# --- the noise floor -----------------------------------------------------------------------------------
def test_a_perfect_robot_is_at_the_noise_floor_in_about_95_percent_of_procedures():
    """The floor is the E_max,syst distribution of a perfectly calibrated robot; its 95th
    percentile is the limit, so independent procedures of a perfect robot fall at or below it
    in 95 % of cases (binomial bounds for 300 procedures)."""
    import omnikin

    robot = load_robot("diff-drive")
    report = omnikin.run_umbmark(robot, true_robot=robot, calibrate=False, trials=300, rate=20.0, seed=3)
    at_floor = np.mean([report.at_noise_floor(r) for r in report.before])
    assert 0.95 - 3 * math.sqrt(0.95 * 0.05 / 300) <= at_floor <= 1.0
    assert report.floor.limit > 0.001  # typical noise: millimetres, not zero


def test_a_badly_built_robot_is_not_at_the_noise_floor():
    import omnikin

    report = omnikin.run_umbmark("diff-drive", calibrate=False, rate=20.0, seed=1)
    assert report.before[0].e_max_syst > 5 * report.floor.limit
    assert report.as_dict()["before"]["at_noise_floor"] is False
