"""Confidence intervals used by the aggregation (confidence level given as e.g. 0.95)."""

from dataclasses import dataclass

import numpy as np
from scipy import stats


@dataclass(frozen=True)
class Interval:
    """A two-sided confidence interval."""

    low: float
    high: float


FEW_RUNS = 3
"""Below this many runs a t interval is very wide (two runs: 12.7 standard errors at 95 %)
and the lower end of a non-negative quantity's interval is often clipped at 0."""


def mean_interval(samples: np.ndarray, confidence: float,
                  nonnegative: bool = False) -> Interval | None:
    """Student-t interval for the mean of i.i.d. ``samples`` (None for fewer than 2); the
    lower end clipped at 0 when the samples cannot be negative (``nonnegative``)."""
    samples = np.asarray(samples, dtype=float)
    n = samples.size
    if n < 2:
        return None
    half = stats.t.ppf(0.5 + confidence / 2, n - 1) * samples.std(ddof=1) / np.sqrt(n)
    center = samples.mean()
    low = max(center - half, 0.0) if nonnegative else center - half
    return Interval(float(low), float(center + half))


def root_interval(mean_squares: np.ndarray, confidence: float) -> Interval | None:
    """Interval for sqrt(E[x]) from i.i.d. non-negative ``mean_squares`` x: the square root of
    their t interval (lower end clipped at 0)."""
    interval = mean_interval(mean_squares, confidence)
    if interval is None:
        return None
    return Interval(float(np.sqrt(max(interval.low, 0.0))), float(np.sqrt(interval.high)))


def rms_chi2_bounds(mean_square: np.ndarray, n: int, confidence: float,
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Interval for the RMS σ of zero-mean Gaussian errors from the mean square of ``n``
    independent samples: n·ms/σ² is χ²(n), so σ lies in
    [sqrt(n·ms/χ²_{(1+c)/2}(n)), sqrt(n·ms/χ²_{(1-c)/2}(n))]."""
    upper_quantile = stats.chi2.ppf(0.5 + confidence / 2, n)
    lower_quantile = stats.chi2.ppf(0.5 - confidence / 2, n)
    scaled = n * np.asarray(mean_square, dtype=float)
    return np.sqrt(scaled / upper_quantile), np.sqrt(scaled / lower_quantile)


def mean_bounds(mean: np.ndarray, std: np.ndarray, n: int, confidence: float,
                ) -> tuple[np.ndarray, np.ndarray] | None:
    """Elementwise Student-t interval of means of ``n`` samples with sample std ``std``."""
    if n < 2:
        return None
    half = stats.t.ppf(0.5 + confidence / 2, n - 1) * np.asarray(std) / np.sqrt(n)
    return mean - half, mean + half
