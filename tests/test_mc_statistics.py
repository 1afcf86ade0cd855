"""Confidence intervals of the campaign statistics: formulas and coverage.

Coverage tests draw TRIALS independent experiments with a fixed seed; the fraction of
intervals containing the true value must be within 4 binomial standard deviations of the
nominal 95 % (sqrt(0.95 * 0.05 / 2000) = 0.49 %, so ±1.95 %).
"""

import numpy as np
import pytest
from scipy import stats

from altfusion.montecarlo.statistics import (
    mean_bounds,
    mean_interval,
    rms_chi2_bounds,
    root_interval,
)

TRIALS = 2000
TOLERANCE = 4 * np.sqrt(0.95 * 0.05 / TRIALS)


def test_mean_interval_is_the_student_t_interval():
    samples = np.array([1.0, 2.0, 4.0, 5.0])
    interval = mean_interval(samples, 0.95)
    half = stats.t.ppf(0.975, 3) * samples.std(ddof=1) / 2.0
    assert interval.low == pytest.approx(3.0 - half)
    assert interval.high == pytest.approx(3.0 + half)


def test_a_single_run_has_no_interval():
    assert mean_interval(np.array([1.0]), 0.95) is None
    assert root_interval(np.array([1.0]), 0.95) is None
    assert mean_bounds(np.zeros(3), np.zeros(3), 1, 0.95) is None


def test_root_interval_is_the_square_root_of_the_mean_square_interval_clipped_at_zero():
    mean_squares = np.array([0.01, 0.02, 9.0])
    interval = root_interval(mean_squares, 0.95)
    assert interval.low == 0.0
    assert interval.high == pytest.approx(np.sqrt(mean_interval(mean_squares, 0.95).high))


def test_rms_chi2_bounds_cover_sigma_95_percent_of_the_time():
    rng = np.random.default_rng(2024)
    sigma, runs = 2.0, 8
    errors = sigma * rng.standard_normal((TRIALS, runs))
    low, high = rms_chi2_bounds(np.mean(errors**2, axis=1), runs, 0.95)
    coverage = np.mean((low <= sigma) & (sigma <= high))
    assert abs(coverage - 0.95) < TOLERANCE


def test_mean_bounds_cover_the_mean_95_percent_of_the_time():
    rng = np.random.default_rng(7)
    runs = 6
    samples = 0.3 + 1.5 * rng.standard_normal((TRIALS, runs))
    low, high = mean_bounds(samples.mean(axis=1), samples.std(axis=1, ddof=1), runs, 0.95)
    coverage = np.mean((low <= 0.3) & (high >= 0.3))
    assert abs(coverage - 0.95) < TOLERANCE
