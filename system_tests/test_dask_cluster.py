"""``altfusion mc`` and ``altfusion evaluate`` on a real Dask cluster, started the way a user
starts one (docs/montecarlo.md): a ``dask scheduler`` process and two ``dask worker``
processes, one thread each, all on 127.0.0.1. They give the same numbers as local worker
processes: every recorded array of every run, and the evaluation's table and summary."""

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")

from altfusion.montecarlo.storage import finished_runs, read_run  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
DASK = Path(sys.executable).with_name("dask")
WORKERS = 2
START_TIMEOUT = 120.0
"""Seconds the scheduler and the workers get to start (spawned processes importing numpy and
altfusion on a busy machine)."""


def cli(*args: str) -> subprocess.CompletedProcess:
    completed = subprocess.run([sys.executable, "-m", "altfusion.cli", *args],
                               capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert completed.returncode == 0, completed.stderr[-3000:]
    return completed


def scheduler_address(scheduler_file: Path, scheduler: subprocess.Popen) -> str:
    """The address the scheduler writes to its scheduler file once it listens."""
    deadline = time.monotonic() + START_TIMEOUT
    while True:
        assert scheduler.poll() is None, "dask scheduler exited"
        if scheduler_file.exists():
            try:
                return json.loads(scheduler_file.read_text())["address"]
            except (ValueError, KeyError):
                pass                                    # being written
        assert time.monotonic() < deadline, "dask scheduler did not start"
        time.sleep(0.2)


@pytest.fixture(scope="module")
def cluster(fmus, tmp_path_factory) -> Iterator[str]:
    """``dask scheduler --host 127.0.0.1 --port 0`` and two ``dask worker`` processes; the
    scheduler's address once both workers have joined. Stops the processes it started."""
    from distributed import Client

    folder = tmp_path_factory.mktemp("dask")
    scheduler_file = folder / "scheduler.json"
    with open(folder / "cluster.log", "w") as log:
        started = [subprocess.Popen(
            [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(scheduler_file)], stdout=log, stderr=subprocess.STDOUT)]
        try:
            address = scheduler_address(scheduler_file, started[0])
            assert address.startswith("tcp://127.0.0.1:")
            for index in range(WORKERS):
                started.append(subprocess.Popen(
                    [str(DASK), "worker", address, "--host", "127.0.0.1", "--nworkers", "1",
                     "--nthreads", "1", "--no-dashboard", "--name", f"worker-{index}"],
                    stdout=log, stderr=subprocess.STDOUT, cwd=folder))
            with Client(address, timeout="30s") as client:
                client.wait_for_workers(WORKERS, timeout=START_TIMEOUT)
            yield address
        finally:
            for process in reversed(started):
                process.terminate()
            for process in reversed(started):
                try:
                    process.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()


def assert_same_runs(folder: Path, reference: Path, runs: int) -> None:
    assert finished_runs(folder) == finished_runs(reference) == list(range(runs))
    for index in range(runs):
        mine, theirs = read_run(folder, index), read_run(reference, index)
        assert mine.seeds == theirs.seeds
        assert np.array_equal(mine.results.time, theirs.results.time)
        assert list(mine.results.columns) == list(theirs.results.columns)
        for name, values in theirs.results.columns.items():
            assert np.array_equal(mine.results[name], values), (index, name)


def test_mc_on_the_cluster_gives_the_local_workers_numbers(cluster, tmp_path):
    runs = 4
    common = ("mc", str(MODELS / "yang2020.ssp"), "-n", str(runs), "--stop", "5", "--quiet")
    cli(*common, "--workers", "2", "--out", str(tmp_path / "local"))
    on_cluster = cli(*common, "--scheduler", cluster, "--out", str(tmp_path / "dask"))
    assert f"Dask scheduler {cluster} ({WORKERS} workers)" in on_cluster.stdout
    assert_same_runs(tmp_path / "dask", tmp_path / "local", runs)
    workers = {read_run(tmp_path / "dask", index).worker for index in range(runs)}
    assert len(workers) == WORKERS                  # both workers ran some of the runs


def table_rows(stdout: str) -> list[str]:
    """The lines of the evaluation's table (scenario bao2017, one per estimator)."""
    return [line for line in stdout.splitlines() if line.split()[:1] == ["bao2017"]]


def test_evaluate_on_the_cluster_gives_the_local_workers_table(cluster, tmp_path):
    common = ("evaluate", "--runs", "2", "--estimators", "BaselineKF,BaoDriftEstimator",
              "--scenarios", "bao2017", "--stop", "10", "--models", str(MODELS), "--quiet")
    local = cli(*common, "--workers", "2", "--out", str(tmp_path / "local"))
    on_cluster = cli(*common, "--scheduler", cluster, "--out", str(tmp_path / "dask"))
    rows = [table_rows(completed.stdout) for completed in (local, on_cluster)]
    assert len(rows[0]) == 2 and rows[0] == rows[1]
    summaries = [json.loads((tmp_path / out / "evaluation_summary.json").read_text())
                 for out in ("local", "dask")]
    assert summaries[0] == summaries[1]
    assert_same_runs(tmp_path / "dask" / "bao2017", tmp_path / "local" / "bao2017", 2)
