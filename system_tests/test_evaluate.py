"""``altfusion evaluate`` end to end through the FMUs: a tiny evaluation (2 paper scenarios,
2 runs, 2 estimators, 20 s flights), its table, HTML page and n/a marking, and resume."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from altfusion.cosim.ssp import read_ssp
from altfusion.health_events import events_csv, health_events
from altfusion.montecarlo.storage import finished_runs, load_run

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
ESTIMATORS = "BaselineKF,XuSHAEKF"
SCENARIOS = "bao2017,xu2016_hover15"


def evaluate(out, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "altfusion.cli", "evaluate", "--runs", "2", "--estimators",
         ESTIMATORS, "--scenarios", SCENARIOS, "--stop", "20", "--backend", "fmu",
         "--workers", "2", "--models", str(MODELS), "--out", str(out), "--quiet", *extra],
        capture_output=True, text=True, timeout=600, cwd=ROOT)


@pytest.fixture(scope="module")
def evaluated(fmus, tmp_path_factory):
    out = tmp_path_factory.mktemp("evaluate")
    completed = evaluate(out)
    assert completed.returncode == 0, completed.stderr[-3000:]
    return out, completed.stdout


def table_rows(stdout: str) -> dict[tuple[str, str], str]:
    rows = {}
    for line in stdout.splitlines():
        words = line.split()
        if len(words) > 2 and words[0] in SCENARIOS.split(",") and \
                words[1] in ESTIMATORS.split(","):
            rows[(words[0], words[1])] = line
    return rows


def test_the_table_has_every_cell_and_marks_the_estimator_lacking_an_input_na(evaluated):
    _, stdout = evaluated
    rows = table_rows(stdout)
    assert set(rows) == {(s, e) for s in SCENARIOS.split(",") for e in ESTIMATORS.split(",")}
    # bao2017 has no accelerometer, which drives XuSHAEKF's process model: n/a, not run.
    assert re.search(r"\bn/a\b.*no acc", rows[("bao2017", "XuSHAEKF")])
    for cell in (("bao2017", "BaselineKF"), ("xu2016_hover15", "BaselineKF"),
                 ("xu2016_hover15", "XuSHAEKF")):
        words = rows[cell].split()
        assert words[2] == "2", rows[cell]                       # runs
        assert float(words[3]) > 0.0                             # mean RMS, finite
        assert "n/a" not in rows[cell]


def test_every_estimator_of_a_scenario_reads_the_same_sensor_outputs(evaluated):
    out, _ = evaluated
    out = out / "models"                                        # the default's campaigns
    spec = read_ssp(out / "xu2016_hover15" / "system.ssp").spec
    feeds = {}
    for connection in spec.connections:
        component, _, variable = connection.end.partition(".")
        if component in ("estimator", "BaselineKF"):
            feeds.setdefault(variable, set()).add(connection.start)
    assert feeds["baro_h"] == {"air_data.baro_h"} and feeds["gps_h"] == {"gnss.gps_h"}
    baseline = spec.component("BaselineKF").parameters
    assert baseline["R_baro"] == pytest.approx(0.5**2)          # the scenario's true noise
    assert baseline["R_gps"] == pytest.approx((2.0 * 1.5) ** 2)
    stated = json.loads((out / "xu2016_hover15" / "scenario.json").read_text())["description"]
    assert "stated sensor error models: " in stated and "terrain_h 0" in stated
    assert "XuSHAEKF" not in {c.name for c in read_ssp(out / "bao2017" / "system.ssp")
                              .spec.components}
    assert finished_runs(out / "xu2016_hover15") == [0, 1]
    results = load_run(out / "xu2016_hover15", 1).results
    assert results.time[-1] == pytest.approx(20.0)
    assert np.all(np.isfinite(results["BaselineKF.h_est"]))


def test_the_html_page_holds_the_heat_map_and_a_plot_per_cell_and_the_na(evaluated):
    out, _ = evaluated
    page = (out / "evaluation.html").read_text()
    images = re.findall(r'<img alt="([^"]*)" src="data:image/png;base64,', page)
    assert images == ["BaselineKF in bao2017", "BaselineKF in xu2016_hover15",
                      "XuSHAEKF in xu2016_hover15"]
    # the heat maps (RMS, coverage) link every run cell to its plot
    assert page.count('<a href="#cell-xu2016_hover15-XuSHAEKF">') == 2
    assert "XuSHAEKF: n/a (no acc" in page
    markdown = (out / "evaluation.md").read_text()
    xu_row = next(line for line in markdown.splitlines() if line.startswith("| XuSHAEKF |"))
    assert xu_row.split("|")[2].strip() == "n/a"                # bao2017 column
    summary = json.loads((out / "evaluation_summary.json").read_text())["models"]
    assert summary["bao2017"]["XuSHAEKF"]["not_applicable"].startswith("no acc")
    assert summary["xu2016_hover15"]["XuSHAEKF"]["rms"]["runs"] == 2


def test_resume_runs_nothing_more_and_a_new_evaluation_refuses_the_folder(evaluated):
    out, stdout = evaluated
    resumed = evaluate(out, "--resume")
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    assert "0 executed in this session" in resumed.stdout
    assert table_rows(resumed.stdout) == table_rows(stdout)
    refused = evaluate(out)
    assert refused.returncode == 2
    assert "already holds an evaluation" in refused.stderr


def test_an_unknown_estimator_or_scenario_is_refused_naming_the_known_ones(fmus, tmp_path):
    completed = subprocess.run(
        [sys.executable, "-m", "altfusion.cli", "evaluate", "--estimators", "NoSuchKF",
         "--models", str(MODELS), "--out", str(tmp_path / "x")],
        capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert completed.returncode == 2
    assert "unknown estimators NoSuchKF; known:" in completed.stderr
    assert "BaselineKF" in completed.stderr
    assert not (tmp_path / "x").exists()


def test_fault_scenarios_put_the_fault_between_sensors_and_every_estimator(fmus):
    from altfusion.evaluation.run import plan_evaluation
    from altfusion.evaluation.told import DEFAULT_TOLD

    plans, estimators, _ = plan_evaluation(MODELS, None, ["baro_step", "range_terrain"])
    by_name = {s.name: s for s in plans[DEFAULT_TOLD]}
    assert list(by_name) == ["baro_step", "range_terrain", "nominal_flight"]  # nominal added
    step = by_name["baro_step"]
    assert step.fault.faulty == ("baro",) and step.nominal == "nominal_flight"
    assert step.stop_time == pytest.approx(130.0 + 40.0 + 60.0)
    assert set(step.components) == set(estimators)
    for name in estimators:
        feeds = {c.start for c in step.spec.connections if c.end == f"{name}.baro_h"}
        assert feeds == {"fault.baro_h"}, name
    assert step.spec.component("BaselineKF").parameters["R_baro"] == pytest.approx(20.0**2)
    # range_terrain needs the laser: an estimator that does not read it is n/a.
    assert "laser" in by_name["range_terrain"].not_applicable["BaselineKF"]
    assert by_name["nominal_flight"].fault is None
    assert "fault" not in {c.name for c in by_name["nominal_flight"].spec.components}


def test_each_scenario_writes_and_summarizes_its_runs_health_events(evaluated):
    """``<scenario>/<scenario>.events.csv`` holds every event of every stored run (what
    :func:`health_events` reads off the run's recorded outputs), and the command says for
    each scenario how many runs' events it summarized."""
    out, stdout = evaluated
    for scenario in SCENARIOS.split(","):
        folder = out / "models" / scenario
        expected = []
        for index in finished_runs(folder):
            events = health_events(load_run(folder, index).results)
            expected += events_csv(events, {"run": [index] * len(events)}).splitlines()[1:]
        lines = (folder / f"{scenario}.events.csv").read_text().splitlines()
        assert lines[0] == "run,time,estimator,source,what,test_ratio,count,exact"
        assert lines[1:] == expected and any(",initialized," in line for line in expected)
        assert f"{scenario}: health events of 2 runs" in stdout
