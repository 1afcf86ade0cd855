"""``altfusion mc`` and ``altfusion evaluate`` on a real Dask cluster, started the way a user
starts one (docs/montecarlo.md): a ``dask scheduler`` process and two ``dask worker``
processes, one thread each, all on 127.0.0.1. They give the same numbers as local worker
processes: every recorded array of every run, and the evaluation's table and summary."""

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")

from dask_cluster import dask_cluster  # noqa: E402

from altfusion.montecarlo.storage import finished_runs, read_run  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
WORKERS = 2


def cli(*args: str) -> subprocess.CompletedProcess:
    completed = subprocess.run([sys.executable, "-m", "altfusion.cli", *args],
                               capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert completed.returncode == 0, completed.stderr[-3000:]
    return completed


@pytest.fixture(scope="module")
def cluster(fmus, tmp_path_factory) -> Iterator[str]:
    """A scheduler and two workers on 127.0.0.1 (:func:`dask_cluster.dask_cluster`)."""
    with dask_cluster(tmp_path_factory.mktemp("dask"), WORKERS) as address:
        assert address.startswith("tcp://127.0.0.1:")
        yield address


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
    assert_same_runs(tmp_path / "dask" / "models" / "bao2017",
                     tmp_path / "local" / "models" / "bao2017", 2)
