"""WindowSum: the same bits as math.fsum over the window, at every value pushed."""

import math
from collections import deque

import numpy as np
import pytest

from altfusion.estimators.window_sum import WindowSum


def _pushed(values, length):
    """(WindowSum.total(), math.fsum(window)) after each value pushed."""
    summed, window = WindowSum(length), deque(maxlen=length)
    pairs = []
    for value in values:
        summed.push(value)
        window.append(value)
        assert len(summed) == len(window)
        pairs.append((summed.total(), math.fsum(window)))
    return pairs


@pytest.mark.parametrize("length", [1, 2, 20, 100])
def test_the_sum_is_math_fsum_of_the_window_bit_for_bit(length):
    """Squares of differences spanning 24 decades (the accelerometer's noise estimate),
    signed values summing near 0 (every subtraction cancels), and their mixture: a plain
    running sum differs from fsum in its last bits within a few hundred values."""
    rng = np.random.default_rng(2026)
    squares = (rng.normal(size=3000) * 10.0 ** rng.uniform(-12, 12, 3000)) ** 2
    cancelling = rng.normal(size=3000) * 10.0 ** rng.uniform(-8, 8, 3000)
    for values in (squares, cancelling, np.concatenate([squares, cancelling])):
        for total, reference in _pushed(values.tolist(), length):
            assert total == reference or (math.isnan(total) and math.isnan(reference))
    if length > 2:                      # what the test tells apart: a running sum drifts
        running, window = 0.0, deque(maxlen=length)
        drifted = 0
        for value in cancelling.tolist():
            if len(window) == length:
                running -= window[0]
            window.append(value)
            running += value
            drifted += running != math.fsum(window)
        assert drifted > 0


def test_a_value_that_is_not_finite_is_summed_as_fsum_sums_it_until_it_leaves():
    values = [1.0, 0.1, math.inf, 0.2, 0.3, 1e-17, math.nan, 0.4, 0.5, 0.6, 0.7, 0.8]
    pairs = _pushed(values, 4)
    assert pairs[2][0] == math.inf and math.isnan(pairs[6][0])
    for total, reference in pairs:
        assert total == reference or (math.isnan(total) and math.isnan(reference))
    assert pairs[-1][0] == math.fsum([0.5, 0.6, 0.7, 0.8])


def test_a_sum_that_overflows_falls_back_to_fsum_and_is_exact_again_once_it_is_gone():
    summed = WindowSum(3)
    for value in (1e308, 1e308):
        summed.push(value)
    assert not summed.exact
    with pytest.raises(OverflowError):
        summed.total()                     # as math.fsum of the window raises
    for value in (0.1, 0.2, 0.3):
        summed.push(value)
    assert summed.exact and summed.total() == math.fsum([0.1, 0.2, 0.3])


def test_cleared_the_window_is_empty_and_sums_to_zero():
    summed = WindowSum(5)
    for value in (0.1, math.inf, 0.3):
        summed.push(value)
    summed.clear()
    assert len(summed) == 0 and summed.total() == 0.0
    summed.push(0.7)
    assert summed.total() == 0.7
