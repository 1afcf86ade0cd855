"""Monte Carlo campaigns of a small random system through fmpy: identical numbers with any
number of workers or a Dask cluster, single runs re-run alone, interruption and resume,
reports and the estimator-swapping machinery of ``altfusion compare``."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from altfusion.cosim import write_ssp
from altfusion.montecarlo.aggregation import aggregate
from altfusion.montecarlo.execution import (
    CampaignSettings,
    Execution,
    kept_workers,
    run_campaign,
)
from altfusion.montecarlo.source import CampaignError, SystemSource
from altfusion.montecarlo.storage import finished_runs, read_manifest, read_run, run_path
from altfusion.montecarlo.tables import statistics_json
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.spec import ComponentSpec, Connection, Metric, SystemSpec

RUNS = 8
STEP = 0.02
WEATHER = {"wind_mean": 3.0, "gust_std": 1.5, "lapse_rate_std": 0.003, "lapse_rate_period": 5.0}


def gusty_system(estimator: bool = False) -> SystemSpec:
    """30 s of yang2020's climb in a gusty atmosphere whose lapse rate changes every 5 s,
    against a calm reference atmosphere: both error metrics differ from run to run. With
    ``estimator``, a third atmosphere named 'estimator' rides along (to be swapped)."""
    components = plant_components("yang2020", step=STEP, atmosphere=WEATHER) + (
        ComponentSpec("calm", "Atmosphere", STEP, {"wind_mean": 3.0}),)
    connections = plant_connections() + (Connection("plant.h", "calm.h"),)
    record = ("plant.h", "atmosphere.wind_speed", "calm.wind_speed", "atmosphere.p_static",
              "calm.p_static")
    if estimator:
        components += (ComponentSpec("estimator", "Atmosphere", STEP, WEATHER),)
        connections += (Connection("plant.h", "estimator.h"),)
        record += ("estimator.wind_speed",)
    return SystemSpec(
        name="gusty_climb", description="climb in gusts against a calm reference atmosphere",
        components=components, connections=connections, stop_time=30.0, base_step=STEP,
        output_interval=0.5, record=record,
        metrics=(Metric("gust", "atmosphere.wind_speed", "calm.wind_speed"),
                 Metric("pressure", "atmosphere.p_static", "calm.p_static")),
    )


@pytest.fixture(scope="module")
def gusty_ssp(fmus, tmp_path_factory) -> Path:
    return write_ssp(gusty_system(), fmus, tmp_path_factory.mktemp("ssp") / "gusty.ssp")


@pytest.fixture(scope="module")
def reference(gusty_ssp, tmp_path_factory) -> Path:
    """The uninterrupted campaign on one local worker process."""
    out = tmp_path_factory.mktemp("reference")
    outcome = run_campaign(SystemSource.from_path(gusty_ssp), out, CampaignSettings(RUNS),
                           Execution(workers=1, progress=False))
    assert outcome.complete and not outcome.failed
    return out


def assert_same_runs(folder: Path, reference: Path) -> None:
    assert finished_runs(folder) == list(range(RUNS))
    for index in range(RUNS):
        mine, theirs = read_run(folder, index), read_run(reference, index)
        assert mine.seeds == theirs.seeds
        assert np.array_equal(mine.results.time, theirs.results.time)
        for name, values in theirs.results.columns.items():
            assert np.array_equal(mine.results[name], values), (index, name)


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "altfusion.cli", *args]


def test_runs_differ_by_seed_and_every_seeded_component_gets_its_own(reference):
    first, second = read_run(reference, 0), read_run(reference, 1)
    assert set(first.seeds) == {"atmosphere.seed", "calm.seed"}
    assert first.seeds != second.seeds
    assert not np.array_equal(first.results["atmosphere.wind_speed"],
                              second.results["atmosphere.wind_speed"])


def test_two_workers_and_a_dask_cluster_give_the_same_numbers_as_one_worker(
        gusty_ssp, reference, tmp_path):
    from distributed import LocalCluster

    source = SystemSource.from_path(gusty_ssp)
    two = run_campaign(source, tmp_path / "two", CampaignSettings(RUNS),
                       Execution(workers=2, progress=False))
    assert len({read_run(tmp_path / "two", i).worker for i in range(RUNS)}) == 2
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        dask = run_campaign(source, tmp_path / "dask", CampaignSettings(RUNS),
                            Execution(scheduler=cluster.scheduler_address, progress=False))
    assert two.complete and dask.complete
    assert dask.backend.startswith("Dask scheduler")
    for folder in ("two", "dask"):
        assert_same_runs(tmp_path / folder, reference)
        assert statistics_json(aggregate(tmp_path / folder)) == \
            statistics_json(aggregate(reference))


def test_campaigns_on_a_kept_worker_pool_give_each_its_own_numbers(gusty_ssp, reference,
                                                                  tmp_path):
    """A reproduction's campaigns share two worker processes (WorkerPool): a campaign with
    parameter overrides, then one without, run in the same processes on the same cached
    simulations, and the second gives the reference campaign's numbers (an override of the
    first does not outlive its runs)."""
    source = SystemSource.from_path(gusty_ssp)
    with kept_workers(Execution(workers=2, progress=False)) as execution:
        calm = run_campaign(source, tmp_path / "calm", CampaignSettings(
            RUNS, parameters={"atmosphere.wind_mean": 0.0, "atmosphere.gust_std": 0.0}),
            execution)
        again = run_campaign(source, tmp_path / "again", CampaignSettings(RUNS), execution)
    assert calm.complete and again.complete
    workers = {read_run(tmp_path / folder, i).worker for folder in ("calm", "again")
               for i in range(RUNS)}
    assert len(workers) == 2
    assert not np.any(read_run(tmp_path / "calm", 0).results["atmosphere.wind_speed"])
    assert_same_runs(tmp_path / "again", reference)


def test_a_single_run_re_run_alone_gives_the_same_numbers(gusty_ssp, reference):
    completed = subprocess.run(cli("mc", str(gusty_ssp), "--out", str(reference), "--run", "5"),
                               capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert f"identical to run 5 of the campaign in {reference}" in completed.stdout


def wait_for_runs(folder: Path, count: int, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 120
    while len(finished_runs(folder)) < count:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "campaign too slow"
        time.sleep(0.02)


def gone(pid: int, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def default_sigint() -> None:
    """In the child before it starts: Ctrl-C's default disposition. A shell without job
    control starts a background command with SIGINT ignored (``pytest ... &`` in a script),
    its children inherit that, and Python then installs no KeyboardInterrupt handler: the
    campaign would not see the interrupt this test sends, as it should not see one sent to a
    background job."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def private_tmp(tmp_path: Path) -> tuple[Path, dict[str, str]]:
    """A temporary folder of the test's own and the environment that makes a campaign's
    processes (and their workers) put their scratch folders there."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    return folder, {**os.environ, "TMPDIR": str(folder)}


def extracted_fmus(folder: Path) -> list[Path]:
    """The folders of FMUs extracted by the simulations' processes left in ``folder``."""
    return sorted(folder.glob("altfusion_fmus_*"))


def test_an_interrupted_campaign_keeps_its_runs_and_resumes_to_the_same_result(
        gusty_ssp, reference, tmp_path):
    """... and leaves no scratch folder behind: its worker, stopped by SIGTERM, removes the
    FMUs it extracted (it left them, 4.3 MB here, before it handled SIGTERM)."""
    out = tmp_path / "interrupted"
    scratch, environment = private_tmp(tmp_path)
    process = subprocess.Popen(cli("mc", str(gusty_ssp), "-n", str(RUNS), "--workers", "1",
                                   "--out", str(out)),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=default_sigint, env=environment)
    wait_for_runs(out, 2, process)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "stopped: interrupted. Finished runs are kept" in stderr
    kept = finished_runs(out)
    assert 2 <= len(kept) < RUNS
    assert not [p for p in (out / "runs").iterdir() if p.suffix == ".tmp"]
    worker = int(read_run(out, kept[0]).worker.split("@")[0])
    assert gone(worker), "the worker process outlived the interrupted campaign"
    assert not list(scratch.iterdir())

    completed = subprocess.run(cli("mc", str(gusty_ssp), "--out", str(out), "--resume"),
                               capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert f"{RUNS}/{RUNS} runs finished" in completed.stdout
    assert f"({RUNS - len(kept)} executed in this session" in completed.stdout
    assert_same_runs(out, reference)
    assert len(read_manifest(out)["sessions"]) == 2


def test_a_killed_worker_keeps_the_finished_runs_for_resume(gusty_ssp, reference, tmp_path):
    """The other worker, stopped by SIGTERM, removes its extracted FMUs; only the killed
    one's stay (SIGKILL runs nothing)."""
    out = tmp_path / "killed"
    scratch, environment = private_tmp(tmp_path)
    process = subprocess.Popen(cli("mc", str(gusty_ssp), "-n", str(RUNS), "--workers", "2",
                                   "--out", str(out), "--quiet"),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=environment)
    wait_for_runs(out, 1, process)
    worker = int(read_run(out, finished_runs(out)[0]).worker.split("@")[0])
    os.kill(worker, signal.SIGKILL)  # a worker process this test's campaign started
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 1, stderr
    assert "a worker process died" in stderr
    assert 1 <= len(finished_runs(out)) < RUNS
    assert len(extracted_fmus(scratch)) == 1
    outcome = run_campaign(SystemSource.from_path(gusty_ssp), out, CampaignSettings(),
                           Execution(workers=2, progress=False), resume=True)
    assert outcome.complete
    assert_same_runs(out, reference)


def test_workers_end_within_10_s_of_their_parents_death(gusty_ssp, tmp_path):
    """kill -9 of `altfusion mc` cannot stop its workers: their watchdog (polling every
    PARENT_POLL = 1 s) must, within the 10 s the issue allows, and remove the FMUs they
    extracted as they go."""
    out = tmp_path / "orphaned"
    scratch, environment = private_tmp(tmp_path)
    process = subprocess.Popen(cli("mc", str(gusty_ssp), "-n", str(RUNS), "--workers", "2",
                                   "--out", str(out), "--quiet"),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=environment)
    wait_for_runs(out, 1, process)
    workers = {int(read_run(out, i).worker.split("@")[0]) for i in finished_runs(out)}
    process.kill()       # SIGKILL of the campaign this test started
    process.communicate(timeout=60)
    assert all(gone(worker, timeout=10.0) for worker in workers)
    assert not extracted_fmus(scratch)


def damage(path: Path, how: str) -> None:
    """Truncate a run file to half, or flip one byte in the middle of its data."""
    data = bytearray(path.read_bytes())
    if how == "truncated":
        path.write_bytes(data[:len(data) // 2])
    else:
        data[len(data) // 3] ^= 0xFF
        path.write_bytes(bytes(data))


def test_report_skips_damaged_runs_and_resume_re_runs_them(gusty_ssp, reference, tmp_path):
    out = tmp_path / "damaged"
    shutil.copytree(reference, out)
    damage(run_path(out, 2), "truncated")
    damage(run_path(out, 5), "flipped")
    completed = subprocess.run(cli("report", str(out)), capture_output=True, text=True,
                               timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert "skipped run 2: run_00002.npz" in completed.stdout
    assert "skipped run 5: run_00005.npz" in completed.stdout
    outcome = run_campaign(SystemSource.from_path(gusty_ssp), out, CampaignSettings(),
                           Execution(workers=1, progress=False), resume=True)
    assert sorted(outcome.damaged) == [2, 5] and outcome.executed == 2
    assert_same_runs(out, reference)


def test_resume_refuses_another_seed_and_a_new_campaign_refuses_an_occupied_folder(
        gusty_ssp, reference):
    source = SystemSource.from_path(gusty_ssp)
    with pytest.raises(CampaignError, match="(?s)cannot resume: .*master_seed: campaign has 0, "
                                            "now 1"):
        run_campaign(source, reference, CampaignSettings(master_seed=1), resume=True)
    with pytest.raises(CampaignError, match="already holds a campaign: --resume completes it"):
        run_campaign(source, reference, CampaignSettings(RUNS))
    with pytest.raises(CampaignError, match="seeds are derived per run"):
        run_campaign(source, reference, CampaignSettings(parameters={"calm.seed": 3}),
                     resume=True)


def test_a_system_that_fails_every_run_stops_after_three_with_the_fmu_message(gusty_ssp,
                                                                              tmp_path):
    outcome = run_campaign(SystemSource.from_path(gusty_ssp), tmp_path,
                           CampaignSettings(RUNS, parameters={"plant.mass": -1.0}),
                           Execution(workers=1, progress=False))
    assert outcome.failing and not outcome.finished
    assert sorted(outcome.failed) == [0, 1, 2]
    assert "component 'plant'" in outcome.failed[0]
    assert "parameter 'mass' = -1.0: must be > 0" in outcome.stopped


def colored_fraction(png: Path) -> float:
    """Fraction of pixels that are neither white nor grey (plotted data, not axes)."""
    pixels = matplotlib.image.imread(png)[..., :3]
    spread = pixels.max(axis=-1) - pixels.min(axis=-1)
    return float(np.mean(spread > 0.15))


def test_report_writes_the_html_and_non_empty_plots(reference):
    completed = subprocess.run(cli("report", str(reference)), capture_output=True, text=True,
                               timeout=120)
    assert completed.returncode == 0, completed.stderr
    pngs = ["rms_vs_time.png", "mean_error_vs_time.png", "run_rms_histogram.png",
            "signals.png"]
    for name in pngs:
        assert colored_fraction(reference / name) > 0.005, name
    page = (reference / "report.html").read_text()
    assert page.count("src=\"data:image/png;base64,") == len(pngs)
    assert "<script" not in page and "http" not in page  # self-contained
    for text in ("gust", "pressure", "95 % confidence", "Atmosphere", "FlightController",
                 "lapse_rate_std = 0.003", "seed derived per run", "numpy", "pythonfmu"):
        assert text in page, text
    summary = json.loads((reference / "summary.json").read_text())
    gust = summary["metrics"][0]
    assert gust["name"] == "gust" and len(summary["per_run"]) == RUNS
    assert gust["rms_ci"][0] <= gust["rms"] <= gust["rms_ci"][1]
    header = (reference / "rms_vs_time.csv").read_text().splitlines()[0]
    assert header.startswith("time [s],gust RMS [m/s],gust RMS low [m/s]")


def test_compare_swaps_the_estimator_and_feeds_each_the_same_noise(fmus, tmp_path):
    """Mechanism only (no estimator FMU exists yet): the component 'estimator' runs an
    Atmosphere, then the SSP's VerticalDynamics, which declares none of its inputs or
    parameters. The sensor-side atmospheres must see identical noise in both campaigns."""
    ssp = write_ssp(gusty_system(estimator=True), fmus, tmp_path / "gusty_estimator.ssp")
    out = tmp_path / "compare"
    completed = subprocess.run(
        cli("compare", str(ssp), "--estimators", "Atmosphere,VerticalDynamics", "-n", "4",
            "--workers", "2", "--out", str(out), "--quiet"),
        capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    rows = [line for line in completed.stdout.splitlines() if line.startswith("gust ")]
    assert [row.split()[1] for row in rows] == ["Atmosphere", "VerticalDynamics"]
    swapped = read_manifest(out / "VerticalDynamics")
    assert swapped["swap_effect"]["dropped_connections"] == ["plant.h -> estimator.h"]
    assert swapped["swap_effect"]["dropped_recordings"] == ["estimator.wind_speed"]
    assert "gust_std" in swapped["swap_effect"]["dropped_parameters"]
    assert swapped["seeded_components"] == ["atmosphere", "calm"]
    for index in range(4):
        a = read_run(out / "Atmosphere", index)
        b = read_run(out / "VerticalDynamics", index)
        assert a.seeds["atmosphere.seed"] == b.seeds["atmosphere.seed"]
        assert np.array_equal(a.results["atmosphere.wind_speed"],
                              b.results["atmosphere.wind_speed"])
        assert "estimator.wind_speed" in a.results.columns
        assert "estimator.wind_speed" not in b.results.columns
    page = (out / "compare.html").read_text()
    assert "VerticalDynamics/report.html" in page and "data:image/png;base64," in page


def test_compare_refuses_an_estimator_lacking_an_output_a_metric_needs(fmus, tmp_path):
    system = gusty_system(estimator=True)
    system = SystemSpec(**{**system.__dict__, "metrics": system.metrics + (
        Metric("estimated wind", "estimator.wind_speed", "calm.wind_speed"),)})
    ssp = write_ssp(system, fmus, tmp_path / "needs_wind.ssp")
    completed = subprocess.run(
        cli("compare", str(ssp), "--estimators", "VerticalDynamics", "-n", "2", "--out",
            str(tmp_path / "out")), capture_output=True, text=True, timeout=120)
    assert completed.returncode == 2
    assert ("VerticalDynamics has no output 'wind_speed', which error metric 'estimated "
            "wind' needs") in completed.stderr


def test_a_fault_campaign_says_what_each_estimator_did_over_its_runs(ssp_files, tmp_path):
    """``altfusion mc`` on the fault flight with a fault applied (its estimators' health
    outputs recorded): after the metrics, in how many runs each estimator isolated the
    GNSS that stepped by +6 m at 80 s and +100 m at 140 s, and every event in a CSV."""
    out = tmp_path / "mc"
    completed = subprocess.run(
        cli("mc", str(ssp_files["fault_flight"]), "--fault", "gnss_step", "-n", "2",
            "--stop", "160", "--workers", "1", "--quiet", "--out", str(out)),
        capture_output=True, text=True, timeout=600)
    assert completed.returncode == 0, completed.stderr
    said = completed.stdout
    assert "fault_flight+gnss_step: health events of 2 runs" in said
    assert "  AltitudeEKF: " in said and "isolated gps 2/2 runs" in said
    assert (out / "fault_flight+gnss_step.events.csv").is_file()


def test_compare_says_what_each_estimator_did_over_the_same_runs(ssp_files, tmp_path):
    """``altfusion compare`` on the fault demonstration (its estimator's status recorded):
    after the side-by-side metrics, each estimator's health events over the same seeded
    runs, headed by its name; each estimator's folder holds the CSV of every event."""
    out = tmp_path / "compare"
    completed = subprocess.run(
        cli("compare", str(ssp_files["fault_demo_altitude_ekf"]), "--estimators",
            "AltitudeEKF,YangFusionKF", "-n", "2", "--stop", "40", "--workers", "1",
            "--quiet", "--out", str(out)),
        capture_output=True, text=True, timeout=600)
    assert completed.returncode == 0, completed.stderr
    said = completed.stdout
    assert "AltitudeEKF: health events of 2 runs" in said
    assert "YangFusionKF: health events of 2 runs" in said
    assert list((out / "AltitudeEKF").glob("*.events.csv"))
