"""``altfusion replay`` saves its comparison beside its plot: ``<system>_summary.csv`` (full
precision) and ``<system>_summary.md`` (the table of docs/replay.md)."""

import csv
import math

import numpy as np

from altfusion.replay.compare import (
    EKF2,
    SUMMARY_COLUMNS,
    EstimatorReport,
    Stats,
    format_markdown,
    write_summary,
)


def report(name: str, offset: float, rejected: int | None) -> EstimatorReport:
    differences = Stats.of(offset + np.array([-0.5, 0.5]))
    return EstimatorReport(name, differences, Stats.of(np.array([0.25, -0.25])), 0.8,
                           Stats.of(np.array([-155.0, -155.5])), Stats.of(np.array([])),
                           rejected, 1.0, "")


def test_the_summary_is_saved_as_csv_and_markdown(tmp_path):
    reports = [report(EKF2, 0.0, None), report("AltitudeEKF", -2.0, 0)]
    files = write_summary(reports, tmp_path / "replay_log")
    assert [f.name for f in files] == ["replay_log_summary.csv", "replay_log_summary.md"]
    rows = list(csv.reader(files[0].open()))
    assert tuple(rows[0]) == SUMMARY_COLUMNS
    ekf2, ours = (dict(zip(rows[0], row, strict=True)) for row in rows[1:])
    assert ekf2["vs EKF2: RMS [m]"] == "" and ekf2["rejected"] == ""   # itself; no count
    assert float(ours["vs EKF2: RMS [m]"]) == math.sqrt(2.5**2 / 2 + 1.5**2 / 2)
    assert ours["h - range: std [m]"] == "" and ours["diverged"] == "no"
    markdown = files[1].read_text()
    assert markdown == format_markdown(reports)
    assert "| AltitudeEKF | 2.062 | -2.000 | 0.500 | 2.500 | 0.000 | 0.250 | 0.80 |" \
        in markdown
    assert markdown.splitlines()[2].startswith(f"| {EKF2} | - | - | - | - |")
