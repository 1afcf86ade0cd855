"""Nothing left in the temporary folder: every ``altfusion`` command removes the SSP archives
it unpacked and the FMUs it extracted when it exits, in its Monte Carlo worker processes too
(which leave by ``os._exit``, skipping :mod:`atexit`), after success and after a user's
mistake. Before, each run of the yang2020 system left eight extracted FMUs (about 1 MiB each)
in ``/tmp`` and each worker its own: a day of test suites had filled 19 GB."""

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from altfusion.cosim import extraction, instances
from altfusion.montecarlo import worker
from altfusion.montecarlo.source import SystemSource


def altfusion(args: list[str], tmp_path) -> tuple[subprocess.CompletedProcess, list[str]]:
    """Run ``altfusion ARGS`` with its own empty temporary folder; what is left in it after."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    completed = subprocess.run([sys.executable, "-m", "altfusion.cli", *args],
                               env={**os.environ, "TMPDIR": str(scratch)},
                               capture_output=True, text=True, timeout=600)
    return completed, sorted(p.name for p in scratch.iterdir())


@pytest.mark.parametrize("command", [
    ["run", "{yang2020}", "--stop", "5", "--out", "{out}"],
    ["mc", "{yang2020}", "-n", "3", "--stop", "2", "--workers", "2", "--quiet", "--out",
     "{out}"],
    ["run", "{fault_flight}", "--fault", "baro_step", "--stop", "2", "--out", "{out}"],
    ["run", "{yang2020}", "--stop", "5", "--set", "plant.mass=-1", "--out", "{out}"],
], ids=["run", "mc-two-workers", "fault", "refused-parameter"])
def test_no_temporary_folder_outlives_a_command(ssp_files, tmp_path, command):
    args = [a.format(**ssp_files, out=tmp_path / "out") for a in command]
    completed, left = altfusion(args, tmp_path)
    assert completed.returncode == (2 if "plant.mass=-1" in args else 0), completed.stderr
    assert left == []


def test_a_kept_worker_extracts_each_fmu_once_and_keeps_few_systems(ssp_files, tmp_path):
    """A worker running campaign after campaign (the kept workers of ``evaluate`` and
    ``reproduce``, a Dask worker): each campaign of an evaluation reads its own SSP archive
    holding the same FMUs. Those were extracted anew for every campaign (keyed by path) and
    every system was kept with its unpacked archive: an evaluation's worker grew its share of
    the temporary folder by about 22 MB per campaign until it ended (benchmarks/RESULTS.md),
    and its memory by the FMUs' descriptions, cached by path (0.22 MB per campaign). Now an
    FMU of the same bytes is extracted and described once per process, and beyond
    ``KEPT_SYSTEMS`` the system used longest ago is closed and its unpacked archive removed;
    used again, it is rebuilt and runs the same."""
    sources = []
    for k in range(worker.KEPT_SYSTEMS + 2):
        campaign = tmp_path / f"campaign{k}"
        campaign.mkdir()
        shutil.copy(ssp_files["plant_yang2020"], campaign / "system.ssp")
        sources.append(SystemSource.from_path(campaign / "system.ssp"))
    first = worker.simulation_for(sources[0]).run(stop_time=2.0)
    unpacked = [worker._SIMULATIONS[sources[0].key][0].loaded.folder.path]
    extracted = sorted(extraction._FMU_FOLDER.path.iterdir())
    described = len(instances._INFO_CACHE)
    for source in sources[1:]:
        worker.simulation_for(source)
        unpacked.append(worker._SIMULATIONS[source.key][0].loaded.folder.path)
    assert sorted(extraction._FMU_FOLDER.path.iterdir()) == extracted
    assert len(instances._INFO_CACHE) == described
    assert list(worker._SIMULATIONS)[-worker.KEPT_SYSTEMS:] == [
        s.key for s in sources[-worker.KEPT_SYSTEMS:]]
    assert [folder.exists() for folder in unpacked] == [False] * 2 + [True] * worker.KEPT_SYSTEMS
    again = worker.simulation_for(sources[0]).run(stop_time=2.0)
    assert list(again.columns) == list(first.columns)
    assert all(np.array_equal(again[name], first[name]) for name in first.columns)
