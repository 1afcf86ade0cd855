"""The timing checks of ``altfusion timing`` on synthetic result tables: a stream recorded as
the convention of docs/signals.md says passes; each way of breaking it is reported as what it
is, and nothing else is."""

from fractions import Fraction

import numpy as np
import pytest

from altfusion.timing.check import TIME_TOLERANCE, Schedule, check_stream
from altfusion.timing.report import format_report
from altfusion.timing.streams import Consumer, Stream

ROWS_PER_SECOND = 100
"""Rows every 0.01 s (times n/100, as our runner computes them)."""


def stream(period="0.1", offset="0", latency="0", step=0.1, handover=0.01,
           valid=None) -> Stream:
    return Stream("gnss", "GnssReceiver", "gps", Fraction(period), Fraction(offset),
                  Fraction(latency), step, (Consumer("estimator", "gps_count", handover),),
                  valid)


def recorded(s: Stream, stop: float = 2.0, rows_per_second: int = ROWS_PER_SECOND,
             seen_after_rows: int = 0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Rows of a sensor keeping its schedule exactly, and a consumer whose count follows the
    sensor's ``seen_after_rows`` rows later."""
    time = np.arange(round(stop * rows_per_second) + 1) / rows_per_second
    k = np.arange(0, round(stop / float(s.period)) + 1)
    instants = np.array([float(s.offset + i * s.period) for i in k])
    instants = instants[instants > 0]
    due = instants + float(s.latency)
    count = np.searchsorted(due, time + TIME_TOLERANCE, side="right")
    stamp = np.where(count > 0, instants[np.maximum(count - 1, 0)], 0.0)
    seen = np.r_[np.zeros(seen_after_rows), count[:count.size - seen_after_rows]]
    return time, {s.count_column: count.astype(float), s.time_column: stamp,
                  "estimator.gps_count": seen}


def kinds(result) -> set[str]:
    return {violation.kind for violation in result.violations}


def test_a_stream_on_its_schedule_passes_with_every_sample_counted():
    s = stream()
    result = check_stream(s, *recorded(s))
    assert result.ok, result.violations
    assert (result.expected, result.seen, result.gaps) == (20, 20, 0)
    assert result.stamp_error == 0.0 and result.jitter == 0.0
    assert (result.delay.low, result.delay.high) == (0.0, 0.0)
    assert result.consumers[0].seen == 20
    assert result.consumers[0].latency.high == 0.0


def test_a_run_of_no_duration_has_nothing_due_and_nothing_wrong():
    """One row (``altfusion timing SYSTEM.ssp --stop 0``: the run's initial values) failed
    with "zip() argument 2 is shorter than argument 1"; no sample is due, none is seen."""
    s = stream()
    zero = np.zeros(1)
    result = check_stream(s, zero, {s.count_column: zero, s.time_column: zero,
                                    "estimator.gps_count": zero})
    assert result.ok, result.violations
    assert (result.expected, result.seen, result.gaps) == (0, 0, 0)


def test_a_consumer_one_step_behind_passes_with_that_latency_and_two_steps_fail():
    s = stream()
    one = check_stream(s, *recorded(s, seen_after_rows=1))
    assert one.ok, one.violations
    assert one.consumers[0].latency.low == pytest.approx(0.01)
    assert one.consumers[0].pending == 1        # shown in the last row, seen after it
    two = check_stream(s, *recorded(s, seen_after_rows=2))
    assert kinds(two) == {"samples estimator.gps_count saw late (hand-over over 0.01 s)"}
    assert two.violations[0].count == 19        # the 20th is shown too late to be judged


def test_a_count_change_removed_from_a_row_is_a_late_or_lost_sample():
    s = stream()
    time, columns = recorded(s)
    row = 50                                    # the sample of 0.5 s
    columns[s.count_column][row] -= 1
    columns[s.time_column][row] = 0.4
    result = check_stream(s, time, columns)
    assert "samples late or lost" in kinds(result)
    late = next(v for v in result.violations if v.kind == "samples late or lost")
    assert late.count == 1 and "instant 0.5 s shown at 0.51 s" in late.examples[0]
    assert result.seen == 20                   # the count still rose by 20


def test_an_altered_stamp_is_off_the_schedule():
    s = stream()
    time, columns = recorded(s)
    columns[s.time_column][70:80] = 0.705        # the sample of 0.7 s, 5 ms off
    result = check_stream(s, time, columns)
    assert kinds(result) == {"stamps off the schedule"}
    assert result.stamp_error == pytest.approx(0.005)
    assert result.jitter == pytest.approx(0.005)


def test_a_count_that_rises_without_a_new_stamp_counts_a_sample_twice():
    s = stream()
    time, columns = recorded(s)
    columns[s.count_column][55:] += 1            # +1 at 0.55 s, stamp still 0.5 s
    result = check_stream(s, time, columns)
    assert "samples counted twice (the count rose by more than the instants since the " \
           "previous stamp)" in kinds(result)
    assert result.duplicated == 1


def outage(s: Stream, fix: bool | None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Rows in which the samples of 0.6 .. 1.0 s are not taken, ``gnss.gps_fix`` recorded
    ``fix`` meanwhile (None: not recorded)."""
    time, columns = recorded(s)
    count, stamp = columns[s.count_column], columns[s.time_column]
    hold = (time >= 0.6) & (time < 1.1)
    count[hold] = count[time == 0.5][0]
    stamp[hold] = 0.5
    count[time >= 1.1] -= 5
    columns["estimator.gps_count"] = count.copy()
    if fix is not None:
        columns["gnss.gps_fix"] = np.where(hold, float(fix), 1.0)
    return time, columns


def test_an_outage_skips_instants_while_the_fix_is_lost():
    s = stream(valid="gps_fix")
    result = check_stream(s, *outage(s, fix=False))
    assert result.ok, result.violations
    assert (result.expected, result.seen, result.gaps) == (20, 15, 5)


def test_instants_skipped_with_a_valid_fix_are_missing_samples():
    s = stream(valid="gps_fix")
    result = check_stream(s, *outage(s, fix=True))
    assert kinds(result) == {"samples missing while gps_fix was true"}
    assert result.violations[0].count == 5


def test_a_sensor_without_a_validity_output_must_take_every_sample():
    s = stream()
    assert kinds(check_stream(s, *outage(s, fix=None))) == {
        "samples missing (GnssReceiver takes every sample: it has no validity output)"}
    unjudged = check_stream(stream(valid="gps_fix"), *outage(s, fix=None))
    assert unjudged.ok and "record gnss.gps_fix" in unjudged.notes[0]


def test_a_count_that_stops_before_the_last_row_is_missing_samples():
    """A host that failed after its first steps and wrote a last row at the stop time."""
    s = stream()
    time, columns = recorded(s)
    rows = np.r_[0:11, time.size - 1]
    stopped = {name: np.r_[values[:11], values[10]] for name, values in columns.items()}
    result = check_stream(s, time[rows], stopped)
    assert result.violations[0].kind.startswith("samples missing")
    assert result.violations[0].count == 19


def test_several_samples_in_one_coarse_row_are_counted_not_lost():
    s = stream(period="0.1", step=0.1)
    time, columns = recorded(s, rows_per_second=2)          # rows every 0.5 s
    result = check_stream(s, time, columns)
    assert result.ok, result.violations
    assert result.seen == 20
    assert result.notes and "rows every 0.5 s" in result.notes[0]


def test_a_jump_of_two_samples_in_a_fine_row_is_a_late_sample():
    s = stream()
    time, columns = recorded(s)
    columns[s.count_column][(time >= 0.3) & (time < 0.4)] -= 1   # 0.3 s shows at 0.4 s
    columns[s.time_column][(time >= 0.3) & (time < 0.4)] = 0.2
    result = check_stream(s, time, columns)
    assert "samples late or lost" in kinds(result)


def test_a_sample_shown_before_its_instant_is_early():
    """ECOS shows a slow sensor's end-of-step sample from the start of its step."""
    s = stream()
    time, columns = recorded(s)
    for name in (s.count_column, s.time_column, "estimator.gps_count"):
        columns[name] = np.r_[columns[name][9:], np.repeat(columns[name][-1], 9)]
    result = check_stream(s, time, columns)
    assert kinds(result) == {"samples shown before they were due (instant + latency)",
                             "samples estimator.gps_count saw before they were due"}
    assert result.delay.low == pytest.approx(-0.09)
    assert result.early == result.consumers[0].early == 20


def test_latency_and_offset_move_the_due_rows():
    s = stream(offset="0.05", latency="0.02", step=0.01)
    result = check_stream(s, *recorded(s))
    assert result.ok, result.violations
    assert result.expected == 20                  # 0.05 .. 1.95 s, due by 1.97 s
    assert result.delay.low == pytest.approx(0.02) and result.delay.high == pytest.approx(0.02)
    time, columns = recorded(stream(offset="0.05", step=0.01))   # delivered at once
    early = check_stream(s, time, columns)
    assert "samples shown before they were due (instant + latency)" in kinds(early)


def test_a_consumer_that_never_sees_the_samples_is_reported():
    s = stream()
    time, columns = recorded(s)
    columns["estimator.gps_count"][time > 1.0] = columns["estimator.gps_count"][time == 1.0][0]
    result = check_stream(s, time, columns)
    assert kinds(result) == {"samples estimator.gps_count never saw"}
    assert result.violations[0].count == 9      # 1.1 .. 1.9 s; 2.0 s is shown in the last row
    assert result.consumers[0].pending == 1


def test_unrecorded_columns_are_said_not_failed():
    s = stream()
    time, columns = recorded(s)
    del columns["estimator.gps_count"]
    result = check_stream(s, time, columns)
    assert result.ok and not result.consumers[0].recorded
    assert "not recorded" in format_report([result])
    missing = check_stream(s, time, {})
    assert not missing.recorded and missing.ok


def test_the_report_lists_each_violation_and_counts_the_failing_streams():
    s = stream()
    time, columns = recorded(s)
    columns[s.time_column][70:80] = 0.705
    text = format_report([check_stream(s, time, columns)])
    assert "1 violation(s) in 1 of 1 streams:" in text
    assert "gnss.gps: 1 stamps off the schedule: 0.705 s at 0.7 s" in text
    assert "FAIL" in text


def test_instants_are_exact_and_start_strictly_after_the_start_time():
    schedule = Schedule(Fraction("0.1"), Fraction("0.05"), Fraction(0), 0.1, start=0.05)
    assert schedule.first_index() == 1
    assert schedule.instant(np.array([3]))[0] == 0.35
    assert schedule.last_due_index(1.0) == 9
    on_grid, inside = schedule.delivered_by(np.array([0.15, 0.2]))   # steps from 0.05 s
    assert on_grid == pytest.approx(0.15) and inside == pytest.approx(0.25)


def test_one_host_step_for_every_component_sets_the_delivery_and_hand_over_allowed():
    s = stream(step=0.01, handover=0.01)
    time, columns = recorded(s, seen_after_rows=5)                # 0.05 s later
    assert "samples estimator.gps_count saw late (hand-over over 0.01 s)" in kinds(
        check_stream(s, time, columns))
    result = check_stream(s, time, columns, step=0.05)
    assert result.ok, result.violations
    assert result.consumers[0].allowed == pytest.approx(0.05)
