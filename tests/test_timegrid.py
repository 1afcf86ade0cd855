"""Exact time from integer ticks (altfusion.timegrid)."""

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from altfusion.errors import ParameterError, StepError
from altfusion.timegrid import TickClock


@given(n=st.integers(min_value=0, max_value=10**9),
       step=st.sampled_from([0.01, 0.001, 0.2, 0.1, 0.005, 1.0, 0.05]))
def test_time_is_the_exact_rational_rounded_once(n, step):
    clock = TickClock(step)
    assert clock.time(n) == float(n * Fraction(repr(step)))


def test_one_hour_of_centisecond_steps_lands_exactly_on_3600_s():
    clock = TickClock(0.01)
    accumulated = 0.0
    for _ in range(360_000):
        accumulated += 0.01
    assert clock.time(360_000) == 3600.0
    assert accumulated != 3600.0  # what float accumulation would have given


def test_durations_must_be_whole_multiples_of_the_step():
    clock = TickClock(0.01)
    assert clock.ticks_in(0.2, "sample_period") == 20
    assert clock.ticks_in(3600.0, "stop_time") == 360_000
    with pytest.raises(ParameterError, match="'sample_period' = 0.015"):
        clock.ticks_in(0.015, "sample_period")
    with pytest.raises(ParameterError, match="'latency' = -0.01"):
        clock.ticks_in(-0.01, "latency")
    with pytest.raises(ParameterError, match="must be > 0"):
        clock.ticks_in(0.0, "sample_period", allow_zero=False)


def test_start_time_offsets_the_grid():
    clock = TickClock(0.2, start_time=10.0)
    assert clock.time(5) == 11.0


def test_advance_rejects_a_wrong_step_or_time():
    clock = TickClock(0.01)
    clock.advance(0.0, 0.01)
    with pytest.raises(StepError, match="step_size = 0.01"):
        clock.advance(0.01, 0.02)
    with pytest.raises(StepError, match="this component is at t = 0.01"):
        clock.advance(0.5, 0.01)
    assert clock.ticks == 1


def test_step_size_must_be_positive():
    with pytest.raises(ParameterError, match="'step_size' = 0.0"):
        TickClock(0.0)


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_a_non_finite_step_or_duration_is_refused_naming_it(bad):
    with pytest.raises(ParameterError, match="'step_size' = .*must be finite"):
        TickClock(bad)
    with pytest.raises(ParameterError, match="'stop_time' = .*must be finite"):
        TickClock(0.01).ticks_in(bad, "stop_time")
