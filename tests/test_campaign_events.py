"""A campaign says what its estimators did over the runs (``altfusion mc``, ``report`` and
``evaluate``): each notable health event in how many runs and at what median time, every
event of every run in a CSV."""

import csv

import numpy as np
from test_mc_report import TIME, manifest

from altfusion.cli import main
from altfusion.cosim.results import Results
from altfusion.estimators.health import Status, status_bits
from altfusion.montecarlo.campaign_events import campaign_health, records_health
from altfusion.montecarlo.report import write_report
from altfusion.montecarlo.storage import RunRecord, write_manifest, write_run

ISOLATED_FROM = {1: 5.0, 3: 12.5}
"""Run -> time from which its estimator has the GNSS isolated (to the end)."""
INVALID_IN = {2: (8.0, 10.0)}
"""Run -> the span in which its estimator's h_valid is false."""


def write_campaign(folder, runs: int = 4, with_status: bool = True):
    """Runs of one estimator 'est' fusing baro and GNSS, the GNSS isolated in the runs of
    :data:`ISOLATED_FROM` and validity lost in those of :data:`INVALID_IN`."""
    write_manifest(folder, manifest("flight", runs, ["est"]))
    bits = status_bits()
    for index in range(runs):
        truth = 100.0 + TIME
        status = np.full(TIME.size, int(Status.INITIALIZED) | bits["BARO_FUSED"]
                         | bits["GPS_FUSED"])
        if index in ISOLATED_FROM:
            isolated = ISOLATED_FROM[index] <= TIME
            status[isolated] = (int(Status.INITIALIZED) | bits["BARO_FUSED"]
                                | bits["GPS_REJECTED"] | bits["GPS_ISOLATED"])
        valid = np.ones(TIME.size)
        if index in INVALID_IN:
            low, high = INVALID_IN[index]
            valid[(low <= TIME) & (high > TIME)] = 0.0
        columns = {"plant.h": truth, "est.h_est": truth + 0.1}
        if with_status:
            columns |= {"est.status": status.astype(float), "est.h_valid": valid}
        write_run(folder, RunRecord(index, {"plant.seed": index},
                                    Results(TIME, columns, {"plant.h": "m"}), 0.0))
    return folder


def test_each_notable_event_is_counted_in_runs_at_its_median_first_time(tmp_path):
    """The isolation in runs 1 and 3 (at 5 and 12.5 s: median 8.75 s), the baro carrying
    the height from then on, validity lost in run 2 at 8 s; every event of every run in the
    CSV, rejections and the start included, with its run."""
    health = campaign_health(write_campaign(tmp_path), "flight")
    assert health.said("flight") == (
        "flight: health events of 4 runs\n  est: validity lost 1/4 runs (median 8.0 s); "
        "isolated gps 2/4 runs (median 8.8 s); fallback baro 2/4 runs (median 8.8 s)")
    with open(health.events, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert {row["run"] for row in rows if row["what"] == "isolated"} == {"1", "3"}
    assert {row["run"] for row in rows if row["what"] == "initialized"} == {"0", "1", "2", "3"}
    assert any(row["what"] == "rejected" for row in rows)


def test_mc_and_report_say_them_and_the_report_page_shows_them(tmp_path, capsys):
    """``altfusion report`` prints the events under the metrics, writes the CSV beside
    summary.json and gives the page a section of them; ``altfusion mc`` prints the same
    lines after a campaign (:func:`~altfusion.montecarlo.commands._print_health`)."""
    write_campaign(tmp_path)
    report = write_report(tmp_path)
    assert report.health.events == tmp_path / "flight.events.csv"
    assert report.health.events.is_file()
    assert report.health.rows == [("est", "validity lost 1/4 runs (median 8.0 s); isolated gps "
                                     "2/4 runs (median 8.8 s); fallback baro 2/4 runs "
                                     "(median 8.8 s)")]
    page = report.html.read_text()
    assert "Health events over the runs" in page and "isolated gps 2/4 runs" in page
    assert main(["report", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "flight: health events of 4 runs\n  est: validity lost 1/4 runs" in printed
    assert "flight.events.csv" in printed


def test_runs_without_a_recorded_status_have_nothing_to_say(tmp_path, capsys):
    """Without an estimator's status in the runs (the paper systems record their papers'
    signals) there is no health section, no CSV and no line, not a claim of no events."""
    write_campaign(tmp_path, with_status=False)
    assert not records_health(tmp_path)
    report = write_report(tmp_path)
    assert report.health is None
    assert "Health events" not in report.html.read_text()
    assert main(["report", str(tmp_path)]) == 0
    assert "health events" not in capsys.readouterr().out
