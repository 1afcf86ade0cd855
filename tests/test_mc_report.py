"""The campaign report (``altfusion report``) decides at a glance: RMS on a log axis,
intervals of non-negative quantities that stay non-negative (with a warning below 3 runs), a
histogram shown at its own size, no empty header row, a re-run command that runs, and the
same RMS as ``altfusion evaluate``."""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from altfusion.cosim.results import Results
from altfusion.estimators.health import Status
from altfusion.evaluation.metrics import Series, run_metrics
from altfusion.evaluation.run import Cell
from altfusion.montecarlo import plots
from altfusion.montecarlo.aggregation import aggregate
from altfusion.montecarlo.report import write_report
from altfusion.montecarlo.storage import RunRecord, write_manifest, write_run
from altfusion.scores import RMS_DEFINITION

TIME = np.arange(0.0, 20.5, 0.5)
ESTIMATORS = ("A", "B", "C", "D", "E", "F", "G")


def manifest(name: str, runs: int, estimators) -> dict:
    metrics = [{"name": f"{e} error", "estimate": f"{e}.h_est", "truth": "plant.h"}
               for e in estimators]
    return {"runs": runs, "master_seed": 7, "stop_time": 20.0, "ssp": "/m/fault_flight.ssp",
            "ssp_sha256": "0" * 64, "parameters": {}, "seeded_components": ["plant"],
            "created": "2026-01-01T00:00:00+00:00", "versions": {"numpy": "x"},
            "format": 1, "recorded": ["plant.h"], "sessions": [], "metrics": metrics,
            "system": {"name": name, "description": "synthetic", "components": [],
                       "connections": [], "metrics": metrics, "record": [],
                       "base_step": 0.5, "output_interval": None, "start_time": 0.0}}


def write_campaign(folder: Path, errors: dict[str, np.ndarray], name: str = "flight",
                   initialized_from: float = 0.0) -> Path:
    """Runs whose estimator e has error errors[e][run] (a constant), initialized (status
    bit) from ``initialized_from`` s; before that its estimate is a 1000 m placeholder."""
    runs = len(next(iter(errors.values())))
    write_manifest(folder, manifest(name, runs, list(errors)))
    status = np.where(initialized_from <= TIME, int(Status.INITIALIZED), 0).astype(float)
    for index in range(runs):
        truth = 100.0 + TIME
        columns, units = {"plant.h": truth}, {"plant.h": "m"}
        for estimator, values in errors.items():
            estimate = np.where(status > 0, truth + values[index], 1000.0)
            columns |= {f"{estimator}.h_est": estimate, f"{estimator}.status": status}
            units[f"{estimator}.h_est"] = "m"
        write_run(folder, RunRecord(index, {"plant.seed": index}, Results(TIME, columns,
                                                                           units), 0.0))
    return folder


def spread(values_a: float, values_b: float) -> dict[str, np.ndarray]:
    """Seven estimators, two runs each, RMS from 0.4 m to 500 m."""
    return {e: np.array([values_a, values_b]) * 10.0 ** (k / 2.0)
            for k, e in enumerate(ESTIMATORS)}


def test_the_rms_versus_time_uses_a_log_axis_so_small_bands_stay_visible(tmp_path,
                                                                           monkeypatch):
    write_campaign(tmp_path, spread(0.4, 0.5))
    figures = []
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or path)
    plots.plot_rms_versus_time(aggregate(tmp_path), tmp_path / "rms.png")
    assert [ax.get_yscale() for ax in figures[0].axes] == ["log"]


def test_intervals_of_non_negative_quantities_stay_non_negative_with_a_warning(tmp_path):
    """Two runs whose maxima are 1 m and 30 m: the t interval of the mean per-run max
    (t = 12.7 at one degree of freedom) would reach about -170 m."""
    write_campaign(tmp_path, {"A": np.array([1.0, 30.0])})
    report = write_report(tmp_path)
    a = report.statistics.metrics[0]
    for interval in (a.rms_ci, a.std_ci, a.run_max_ci):
        assert interval.low >= 0.0
    page = report.html.read_text()
    assert "WARNING: fewer than 3 runs" in page


def test_the_histogram_fits_the_page_so_it_is_shown_at_its_own_size(tmp_path):
    write_campaign(tmp_path, spread(0.4, 0.5))
    write_report(tmp_path)
    width, height = Image.open(tmp_path / "run_rms_histogram.png").size
    assert width <= 1100 and height <= 700                       # the page is 1100 px wide


def test_the_report_has_no_empty_header_row_and_a_rerun_command_that_names_the_campaign(
        tmp_path):
    write_campaign(tmp_path, spread(0.4, 0.5), name="fault_flight+baro_step")
    page = write_report(tmp_path).html.read_text()
    assert not re.search(r"<tr>(<th></th>)+</tr>", page)
    assert "SYSTEM.ssp" not in page
    assert f"altfusion mc /m/fault_flight.ssp --out {tmp_path} --fault baro_step --run 1" \
        in page


def test_the_report_and_the_evaluation_compute_one_rms(tmp_path):
    """Placeholder rows before initialization count in neither; the runs' mean squares
    (1 and 3844, RMS 1 m and 62 m) pool to sqrt(1922.5) = 43.8 m on both pages."""
    errors = np.array([1.0, 62.0])
    write_campaign(tmp_path, {"A": errors}, initialized_from=2.0)
    report = write_report(tmp_path)
    status = np.where(TIME >= 2.0, int(Status.INITIALIZED), 0)
    runs = [Series(TIME, np.where(status > 0, e, 900.0), np.ones_like(TIME),
                   np.ones_like(TIME), status) for e in errors]
    cell = Cell("A", "flight", runs=[run_metrics(r) for r in runs])
    assert report.statistics.metrics[0].rms == pytest.approx(math.sqrt(1922.5))
    assert cell.rms == pytest.approx(report.statistics.metrics[0].rms)
    assert RMS_DEFINITION in report.html.read_text().replace("&#x27;", "'")


def test_each_mean_error_gets_its_own_axis_fitted_to_it(tmp_path, monkeypatch):
    """Seven estimators from 0.4 m to 500 m: seven panels, the first within a metre."""
    write_campaign(tmp_path, spread(0.4, 0.5))
    figures = []
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or path)
    plots.plot_mean_error_versus_time(aggregate(tmp_path), tmp_path / "mean.png")
    shown = [ax for ax in figures[0].axes if ax.get_visible()]
    assert [ax.get_title() for ax in shown] == [f"{e} error" for e in ESTIMATORS]
    assert shown[0].get_ylim()[1] < 1.0 < 100.0 < shown[-1].get_ylim()[1]
