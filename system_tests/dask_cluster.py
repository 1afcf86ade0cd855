"""A Dask cluster started the way a user starts one (docs/montecarlo.md): a ``dask scheduler``
process and ``dask worker`` processes of one thread each, all listening on 127.0.0.1 only.
Used by ``test_dask_cluster.py`` and ``benchmarks/dask_scaling.py``."""

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

DASK = Path(sys.executable).with_name("dask")
START_TIMEOUT = 120.0
"""Seconds the scheduler and the workers get to start (spawned processes importing numpy and
altfusion on a busy machine)."""


def scheduler_address(scheduler_file: Path, scheduler: subprocess.Popen) -> str:
    """The address the scheduler writes to its scheduler file once it listens."""
    deadline = time.monotonic() + START_TIMEOUT
    while True:
        if scheduler.poll() is not None:
            raise RuntimeError("dask scheduler exited")
        if scheduler_file.exists():
            try:
                return json.loads(scheduler_file.read_text())["address"]
            except (ValueError, KeyError):
                pass                                    # being written
        if time.monotonic() > deadline:
            raise RuntimeError("dask scheduler did not start")
        time.sleep(0.2)


@contextmanager
def dask_cluster(folder: Path, workers: int) -> Iterator[str]:
    """``dask scheduler --host 127.0.0.1 --port 0`` and ``workers`` ``dask worker``
    processes (``--nthreads 1``), logging to ``folder/cluster.log``; yields the scheduler's
    address once every worker has joined, and stops the processes it started."""
    from distributed import Client

    scheduler_file = folder / "scheduler.json"
    with open(folder / "cluster.log", "w") as log:
        started = [subprocess.Popen(
            [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(scheduler_file)], stdout=log, stderr=subprocess.STDOUT)]
        try:
            address = scheduler_address(scheduler_file, started[0])
            for index in range(workers):
                started.append(subprocess.Popen(
                    [str(DASK), "worker", address, "--host", "127.0.0.1", "--nworkers", "1",
                     "--nthreads", "1", "--no-dashboard", "--name", f"worker-{index}"],
                    stdout=log, stderr=subprocess.STDOUT, cwd=folder))
            with Client(address, timeout="30s") as client:
                client.wait_for_workers(workers, timeout=START_TIMEOUT)
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
