"""Where runs execute: local worker processes, or a Dask distributed cluster.

Both give the campaign loop the same three operations: submit a run, iterate over runs as
they complete, close (cancelling what has not run). The runs themselves are the same function
(:func:`altfusion.montecarlo.worker.execute_run`) with the same per-process cached simulation.
"""

import os
import uuid
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from typing import Any

from altfusion.montecarlo.campaign import CampaignTask
from altfusion.montecarlo.source import CampaignError
from altfusion.montecarlo.worker import execute_run, initialize_worker


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class LocalWorkers:
    """``workers`` processes started with "spawn" (never fork a process that may have
    embedded-Python FMUs loaded); each builds one simulation in its initializer and waits for
    the others to have built theirs (:func:`~altfusion.montecarlo.worker.initialize_worker`).
    Every run is submitted at once, so the pool starts all ``workers`` processes."""

    def __init__(self, task: CampaignTask, workers: int):
        self.description = f"{workers} local worker process{'es' if workers > 1 else ''}"
        context = get_context("spawn")
        self._executor = ProcessPoolExecutor(max_workers=workers, mp_context=context,
                                             initializer=initialize_worker,
                                             initargs=(task.source, context.Barrier(workers)))

    def submit(self, task: CampaignTask, index: int) -> Future:
        return self._executor.submit(execute_run, task, index)

    def as_completed(self, futures: Iterable[Future]) -> Iterator[Future]:
        return as_completed(list(futures))

    def close(self, cancel: bool) -> None:
        """Shut down; with ``cancel``, drop queued runs and stop the runs in progress."""
        if not cancel:
            self._executor.shutdown(wait=True)
            return
        # The pool has no public way to stop running work: terminate its processes (each
        # one was started by this pool), then shut down without waiting for them.
        processes = list(getattr(self._executor, "_processes", {}).values())
        self._executor.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join(timeout=10)


class DaskCluster:
    """The campaign on an existing Dask distributed scheduler (``tcp://host:port``).

    Every worker must run the same altfusion installation and see the SSP at the same path.
    """

    def __init__(self, address: str):
        try:
            from distributed import Client
        except ImportError:
            raise CampaignError("--scheduler needs the 'distributed' package: "
                                "pip install 'altfusion[cluster]'") from None
        try:
            self._client = Client(address, set_as_default=False, timeout="30s")
        except OSError as error:
            raise CampaignError(f"cannot reach the Dask scheduler at {address}: {error}") \
                from None
        workers = len(self._client.scheduler_info().get("workers", {}))
        self.description = f"Dask scheduler {address} ({workers} workers)"
        self._session = uuid.uuid4().hex[:8]
        self._futures: set[Any] = set()

    def submit(self, task: CampaignTask, index: int) -> Any:
        future = self._client.submit(execute_run, task, index, pure=False, retries=0,
                                     key=f"altfusion-run-{self._session}-{index:05d}")
        self._futures.add(future)
        return future

    def as_completed(self, futures: Iterable[Any]) -> Iterator[Any]:
        """The futures as they complete; each is forgotten here once handed out (the
        scheduler frees a result nobody holds)."""
        from distributed import as_completed as dask_as_completed

        for future in dask_as_completed(list(futures), loop=self._client.loop):
            self._futures.discard(future)
            yield future

    def close(self, cancel: bool) -> None:
        if cancel and self._futures:
            self._client.cancel(list(self._futures))
        self._client.close()


def local_worker_count(workers: int | None, runs: int) -> int:
    """Local worker processes for ``runs`` runs: ``workers`` (default: one per available
    core), at most one per run."""
    if workers is not None and workers < 1:
        raise CampaignError(f"--workers must be >= 1, got {workers}")
    return min(workers or available_cores(), runs)


def open_backend(task: CampaignTask, workers: int | None, scheduler: str | None, runs: int):
    """Local worker processes (default: one per available core, at most one per run), or the
    Dask cluster at ``scheduler``."""
    if scheduler:
        return DaskCluster(scheduler)
    return LocalWorkers(task, local_worker_count(workers, runs))


class WorkerPool:
    """Local worker processes kept from one campaign to the next (a reproduction's
    campaigns): started for the first campaign's runs, closed by :meth:`close`. Each worker
    keeps one simulation per system (:func:`~altfusion.montecarlo.worker.simulation_for`), so
    campaigns on the same SSP reuse its FMU instances, as the runs of one campaign do; a
    campaign whose runs were cancelled (interrupted, failing) closes the processes and the
    next campaign starts new ones."""

    def __init__(self, workers: int | None):
        self.workers = workers
        self._backend: LocalWorkers | None = None
        self._size = 0

    def backend(self, task: CampaignTask, runs: int) -> LocalWorkers:
        """The pool's workers for ``task``'s ``runs`` runs: those running, or new ones if none
        run or fewer than these runs can use (a resumed first campaign missing one run)."""
        size = local_worker_count(self.workers, runs)
        if self._backend is not None and size > self._size:
            self.close()
        if self._backend is None:
            self._backend, self._size = LocalWorkers(task, size), size
        return self._backend

    def release(self, cancel: bool) -> None:
        """End of a campaign: keep the workers, or with ``cancel`` stop them."""
        if cancel:
            self.close(cancel=True)

    def close(self, cancel: bool = False) -> None:
        if self._backend is not None:
            self._backend.close(cancel)
            self._backend = None
