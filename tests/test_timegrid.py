"""Exact time from integer ticks (altfusion.timegrid)."""

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from altfusion.errors import ParameterError, StepError
from altfusion.timegrid import MAX_TICKS_PER_STEP, TickClock


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


def run(clock: TickClock, current_time: float, step_size: float) -> int:
    """Run one doStep request on ``clock``: the ticks it runs."""
    due = clock.due(current_time, step_size)
    for _ in range(due):
        clock.tick()
    return due


def test_a_step_of_one_tick_runs_one_tick():
    clock = TickClock(0.01)
    assert [run(clock, n * 0.01, 0.01) for n in range(5)] == [1] * 5
    assert clock.now == 0.05


def test_any_step_runs_the_ticks_that_fall_within_it():
    """Ticks of 0.01 s under steps of 0.025 s: 2, 3, 2, 3 ticks (ends 0.025, 0.05, ...)."""
    clock = TickClock(0.01)
    assert [run(clock, n * 0.025, 0.025) for n in range(4)] == [2, 3, 2, 3]
    assert clock.ticks == 10


def test_a_host_adding_floats_reaches_its_stop_time_and_its_remainder_step_runs_nothing():
    """OMSimulator's way: 1000 steps of 0.01 s added up end at 9.999999999999831 s; its
    remainder step (about 1e-13 s) ends at 10 s, where the last tick already ran."""
    clock = TickClock(0.01)
    time, steps = 0.0, []
    while time < 10.0 - 1e-12:
        steps.append(run(clock, time, 0.01))
        time += 0.01
    assert steps == [1] * 1000 and time != 10.0
    assert run(clock, time, 10.0 - time) == 0
    assert clock.ticks == 1000 and clock.now == 10.0


def test_steps_shorter_than_a_tick_run_it_once_its_time_is_reached():
    clock = TickClock(0.01)
    assert [run(clock, n * 0.001, 0.001) for n in range(20)] == ([0] * 9 + [1]) * 2
    assert clock.now == 0.02


def test_a_request_not_at_the_end_of_the_last_or_not_positive_is_refused():
    clock = TickClock(0.01)
    run(clock, 0.0, 0.01)
    with pytest.raises(StepError, match="this component is at t = 0.01"):
        clock.due(0.5, 0.01)
    for bad in (0.0, -0.01, float("nan"), float("inf")):
        with pytest.raises(StepError, match="must be positive and finite"):
            clock.due(0.01, bad)
    for bad in (float("nan"), float("inf")):
        with pytest.raises(StepError, match=f"doStep at t = {bad!r} s, but this component"):
            clock.due(bad, 0.01)
    assert clock.ticks == 1


def test_a_request_running_more_ticks_than_the_limit_is_refused_and_changes_nothing():
    clock = TickClock(0.01)
    largest = MAX_TICKS_PER_STEP * 0.01
    assert clock.due(0.0, largest) == MAX_TICKS_PER_STEP          # the limit itself runs
    clock = TickClock(0.01)
    run(clock, 0.0, 0.005)                                         # off the grid
    with pytest.raises(StepError, match=f"would run {MAX_TICKS_PER_STEP + 1} ticks of 0.01 s"):
        clock.due(0.005, largest + 0.01)
    assert (clock.ticks, clock.host_time) == (0, 0.005)
    assert run(clock, 0.005, 0.005) == 1


def test_step_size_must_be_positive():
    with pytest.raises(ParameterError, match="'step_size' = 0.0"):
        TickClock(0.0)


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_a_non_finite_step_or_duration_is_refused_naming_it(bad):
    with pytest.raises(ParameterError, match="'step_size' = .*must be finite"):
        TickClock(bad)
    with pytest.raises(ParameterError, match="'stop_time' = .*must be finite"):
        TickClock(0.01).ticks_in(bad, "stop_time")
