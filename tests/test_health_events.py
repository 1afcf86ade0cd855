"""Health events in words, read off an estimator's recorded health outputs (status bits,
h_valid, n_height_resets, test ratios): the same from any host's results."""

import math

import numpy as np
import pytest

from altfusion.cosim.results import Results
from altfusion.estimators.health import SourceBit, Status, source_bit
from altfusion.health_events import (
    BAD_ACC,
    FALLBACK,
    GOOD_ACC,
    HEIGHT_RESET,
    INITIALIZED,
    INVALID,
    ISOLATED,
    NOISE_OK,
    NOISE_UP,
    RAISED_MOTION,
    RANGE_AID_OFF,
    RANGE_AID_ON,
    READMITTED,
    REJECTED,
    STATED_MOTION,
    VALID,
    HealthEvent,
    events_csv,
    format_events,
    health_events,
    status_names,
)

DT = 0.1
ON = int(Status.INITIALIZED)
BARO_FUSED, BARO_REJECTED, BARO_ISOLATED = (source_bit("baro", b) for b in (
    SourceBit.FUSED, SourceBit.REJECTED, SourceBit.ISOLATED))
GPS_FUSED, GPS_REJECTED = source_bit("gps", SourceBit.FUSED), source_bit("gps", SourceBit.REJECTED)


def history(rows: list[tuple[int, float, float, float, int]]) -> Results:
    """An estimator 'est' recorded at 10 Hz: per row (status, baro ratio, gps ratio, h_valid,
    n_height_resets)."""
    status, baro, gps, valid, resets = (np.array(c, dtype=float) for c in zip(*rows,
                                                                              strict=True))
    time = np.arange(len(rows)) * DT
    return Results(time, {"est.h_est": np.zeros(len(rows)), "est.status": status,
                          "est.baro_test_ratio": baro, "est.gps_test_ratio": gps,
                          "est.h_valid": valid, "est.n_height_resets": resets}, {})


def rows_of_a_baro_fault() -> list[tuple[int, float, float, float, int]]:
    fused = ON | BARO_FUSED | GPS_FUSED
    rows = [(0, 0.0, 0.0, 0, 0)]                                  # 0.0 s: not started
    rows += [(fused, 0.1, 0.2, 1, 0)] * 3                         # 0.1 s: initialized
    rows += [(ON | BARO_REJECTED | GPS_FUSED, 4.0 + i, 0.2, 1, 0) for i in range(12)]
    rows += [(ON | BARO_REJECTED | BARO_ISOLATED | GPS_FUSED, 9.0, 0.3, 1, 0)]   # 1.6 s
    rows += [(ON | BARO_REJECTED | BARO_ISOLATED | GPS_FUSED, 9.5, 0.3, 1, 0)]
    rows += [(fused, 0.5, 0.3, 1, 0)]                             # 1.8 s: re-admitted
    rows += [(ON | GPS_REJECTED | Status.DEAD_RECKONING, 0.5, 30.0, 0, 1)]  # 1.9 s
    rows += [(fused, 0.5, 0.4, 1, 1)]                             # 2.0 s
    return rows


def test_a_baro_fault_reads_as_rejections_isolation_fallback_readmission_reset_validity():
    events = health_events(history(rows_of_a_baro_fault()))
    said = [(round(e.time, 1), e.source, e.what, e.count) for e in events]
    assert said == [
        (0.1, "", INITIALIZED, 1),
        *[(round(0.4 + 0.1 * i, 1), "baro", REJECTED, 1) for i in range(13)],
        (1.6, "baro", ISOLATED, 1), (1.6, "gps", FALLBACK, 1),
        (1.7, "baro", REJECTED, 1),                               # a new ratio: a new sample
        (1.8, "baro", READMITTED, 1),
        (1.9, "gps", REJECTED, 1), (1.9, "gps", HEIGHT_RESET, 1), (1.9, "", INVALID, 1),
        (2.0, "", VALID, 1),
    ]
    isolated = next(e for e in events if e.what == ISOLATED)
    assert isolated.test_ratio == 9.0 and isolated.estimator == "est"
    assert math.isnan(next(e for e in events if e.what == FALLBACK).test_ratio)


def test_repeated_events_are_grouped_into_one_line():
    text = format_events(health_events(history(rows_of_a_baro_fault())), "x.events.csv")
    assert text.splitlines() == [
        "health events (all in x.events.csv):",
        "  est",
        "       0.10 s  initialized",
        "       0.40 s  rejected baro in 13 recorded rows between 0.4 and 1.6 s (test ratio "
        "up to 15)",
        "       1.60 s  isolated baro (test ratio 9)",
        "       1.60 s  height carried by gps",
        "       1.70 s  rejected baro (test ratio 9.5)",
        "       1.80 s  re-admitted baro (test ratio 0.5)",
        "       1.90 s  validity lost",
        "       1.90 s  rejected gps (test ratio 30)",
        "       1.90 s  height reset onto gps (test ratio 30)",
        "       2.00 s  validity regained",
    ]


def test_a_rejection_count_output_counts_every_rejected_sample():
    """Where ``<source>_rejected`` is recorded its increments are the counts (a source
    sampled faster than the rows are recorded rejects several samples per row)."""
    results = history(rows_of_a_baro_fault())
    counts = np.zeros(len(results.time))
    counts[5:] = 10
    counts[9:] = 37
    results.columns["est.baro_rejected"] = counts
    rejected = [(round(e.time, 1), e.count, e.exact) for e in health_events(results)
                if e.what == REJECTED and e.source == "baro"]
    assert rejected == [(0.5, 10, True), (0.9, 27, True)]
    assert "0.50 s  37 x rejected baro between 0.5 and 0.9 s" in format_events(
        health_events(results))


def test_the_events_of_a_csv_written_elsewhere_are_the_same(tmp_path):
    results = history(rows_of_a_baro_fault())
    again = Results.from_csv(results.to_csv(tmp_path / "run.csv"))
    assert health_events(again) == health_events(results)


def test_status_bits_are_named_and_the_csv_lists_every_event():
    assert status_names(ON | BARO_ISOLATED | GPS_FUSED) == ["INITIALIZED", "BARO_ISOLATED",
                                                            "GPS_FUSED"]
    events = [HealthEvent(1.5, "est", "baro", ISOLATED, 9.0), HealthEvent(2.0, "est", "", VALID)]
    assert events_csv(events, {"run": [3, 3]}).splitlines() == [
        "run,time,estimator,source,what,test_ratio,count,exact",
        "3,1.5,est,baro,isolated,9,1,1", "3,2,est,,validity regained,nan,1,1"]


@pytest.mark.parametrize(("bit", "on", "off"), [
    (Status.BAD_ACC_VERTICAL, BAD_ACC, GOOD_ACC),
    (Status.PROCESS_NOISE_ADAPTED, RAISED_MOTION, STATED_MOTION),
], ids=["bad-accelerometer", "motion-noise"])
def test_an_estimator_flag_reads_as_set_then_cleared(bit, on, off):
    fused = ON | BARO_FUSED | GPS_FUSED
    flagged = fused | bit
    rows = [(fused, 0.1, 0.1, 1, 0)] * 2 + [(flagged, 0.1, 0.1, 1, 0)] * 3 \
        + [(fused, 0.1, 0.1, 1, 0)]
    said = [(round(e.time, 1), e.source, e.what)
            for e in health_events(history(rows)) if e.what in (on, off)]
    assert said == [(0.2, "", on), (0.5, "", off)]


def test_a_noise_flag_and_the_range_aid_are_said_when_set_and_cleared():
    fused = ON | BARO_FUSED | GPS_FUSED
    inflated = fused | source_bit("baro", SourceBit.NOISE_INFLATED)
    aided = fused | Status.RANGE_AID
    rows = [(fused, 0.1, 0.1, 1, 0), (inflated, 0.1, 0.1, 1, 0), (inflated, 0.1, 0.1, 1, 0),
            (aided, 0.1, 0.1, 1, 0), (fused, 0.1, 0.1, 1, 0)]
    said = [(round(e.time, 1), e.source, e.what) for e in health_events(history(rows))
            if e.what in (NOISE_UP, NOISE_OK, RANGE_AID_ON, RANGE_AID_OFF)]
    assert said == [(0.1, "baro", NOISE_UP), (0.3, "baro", NOISE_OK), (0.3, "", RANGE_AID_ON),
                    (0.4, "", RANGE_AID_OFF)]


def test_an_isolated_speed_is_said_without_a_height_fallback():
    """AltitudeEKF isolates a stuck GNSS speed (estimators/stuck.py): said as isolated and
    re-admitted, with no height source said to carry the height for it."""
    fused = ON | BARO_FUSED | GPS_FUSED
    stuck = fused | source_bit("gps_vz", SourceBit.ISOLATED)
    rows = [(fused, 0.1, 0.1, 1, 0), (stuck, 0.1, 0.1, 1, 0), (stuck, 0.1, 0.1, 1, 0),
            (fused, 0.1, 0.1, 1, 0)]
    said = [(round(e.time, 1), e.source, e.what) for e in health_events(history(rows))
            if e.source == "gps_vz" or e.what == FALLBACK]
    assert said == [(0.1, "gps_vz", ISOLATED), (0.3, "gps_vz", READMITTED)]
