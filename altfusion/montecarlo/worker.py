"""What runs inside a worker process: one cached :class:`Simulation` per system, reused for
every run through ``reset`` (pythonfmu leaks memory on every instantiation), for the
:data:`KEPT_SYSTEMS` systems used last.

The cache is module-level, so the same functions serve local worker processes (created with
the "spawn" start method; the initializer warms the cache) and Dask workers (the first task
of a campaign on a worker fills it). Nothing here forks.

A Dask worker may run several tasks at once in threads; a Simulation is not thread-safe and
every FMU runs Python code under the host's GIL, so runs in one process are serialized by a
lock (start Dask workers with one thread each and one worker process per core).
"""

import contextlib
import os
import signal
import threading
import time
from collections import OrderedDict

from altfusion.cosim.runner import Simulation
from altfusion.cosim.scratch import remove_scratch_folders
from altfusion.montecarlo.campaign import CampaignTask
from altfusion.montecarlo.source import PreparedSystem, SystemSource, load_system
from altfusion.montecarlo.storage import RunRecord, resident_memory, worker_name

KEPT_SYSTEMS = 2
"""Simulations a worker keeps, the most recently used: the campaigns of a reproduction or an
evaluation run one after the other, each on one system, and a Dask worker may serve two
campaigns at once. A system used again after more than this many others is instantiated
anew. Each one kept holds its SSP's FMUs unpacked in the temporary folder (6.2 MB for an
evaluation's system) and its instances: kept for good, an evaluation's systems grew each
worker's share of the temporary folder campaign after campaign (with
:mod:`altfusion.cosim.extraction`'s FMUs extracted anew: 4.8 GiB on two workers after 105
campaigns, ``benchmarks/scratch_space.py``)."""

_SIMULATIONS: OrderedDict[tuple, tuple[PreparedSystem, Simulation]] = OrderedDict()
_FAILURES: dict[tuple, Exception] = {}
_LOCK = threading.Lock()


def simulation_for(source: SystemSource) -> Simulation:
    """This process's simulation of ``source``, created on first use and kept.

    If creating it failed (e.g. FMUs built from another core), every later call raises the
    same error instead of instantiating the FMUs again. Beyond :data:`KEPT_SYSTEMS`, the
    simulation used longest ago is closed (its instances freed, its unpacked SSP removed).
    """
    if source.key in _FAILURES:
        raise _FAILURES[source.key].with_traceback(None)
    cached = _SIMULATIONS.get(source.key)
    if cached is None:
        try:
            prepared = load_system(source)
            cached = (prepared, Simulation(prepared.spec, prepared.fmu_paths, source.backend))
        except Exception as error:
            _FAILURES[source.key] = error
            raise
        _SIMULATIONS[source.key] = cached
        while len(_SIMULATIONS) > KEPT_SYSTEMS:
            _, (_, oldest) = _SIMULATIONS.popitem(last=False)
            oldest.close()
    _SIMULATIONS.move_to_end(source.key)
    return cached[1]


PARENT_POLL = 1.0
"""Seconds between two checks that the parent process lives."""


def _end_with_parent(parent: int) -> None:
    """Exit when the parent process is gone (killed with -9 it cannot stop its workers): it
    is gone when this process's parent id changed (re-parented to init or a subreaper). The
    extracted FMUs are removed first (``os._exit`` runs no finalizer)."""
    while os.getppid() == parent:
        time.sleep(PARENT_POLL)
    remove_scratch_folders()
    os._exit(1)


def _terminated(signum: int, _frame) -> None:
    """SIGTERM (the campaign stopping its runs in progress: interrupted, or a worker died):
    leave at once, as the default disposition would, but without leaving this process's
    extracted FMUs in the temporary folder (they were kept for good: 4.3 MB per worker and
    interrupted campaign of system_tests/test_montecarlo.py's system). A second SIGTERM
    (the pool's and the campaign's both stop a broken pool's workers) is ignored: it would
    end the removal halfway."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    remove_scratch_folders()
    os._exit(128 + signum)


READY_TIMEOUT = 60.0
"""Seconds a local worker waits, once its simulation is built, for the other workers to have
built theirs (then it starts taking runs anyway)."""


def initialize_worker(source: SystemSource, ready: threading.Barrier | None = None) -> None:
    """Initializer of local worker processes: build the simulation before the first run, then
    wait at ``ready`` (a barrier of every worker of the pool) until each has built its own:
    a worker whose start-up is slow (a busy machine) would otherwise find every run of a
    short campaign taken by the first one ready.

    Workers ignore Ctrl-C: the parent process decides what happens to an interrupted
    campaign (it keeps every finished run and stops the workers, by SIGTERM). A watchdog
    thread ends the worker within ``PARENT_POLL`` s of its parent's death. Either way the
    worker removes its scratch folders (:mod:`altfusion.cosim.scratch`) before it goes.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _terminated)
    threading.Thread(target=_end_with_parent, args=(os.getppid(),), daemon=True,
                     name="parent-watchdog").start()
    with contextlib.suppress(Exception):  # each run of this worker reports the error
        simulation_for(source)
    if ready is not None:
        with contextlib.suppress(threading.BrokenBarrierError):
            ready.wait(READY_TIMEOUT)


def execute_run(task: CampaignTask, index: int) -> RunRecord:
    """Run ``index`` of the campaign: the same numbers wherever and whenever it runs."""
    seeds = task.seeds(index)
    with _LOCK:
        simulation = simulation_for(task.source)
        start = time.perf_counter()
        results = simulation.run(stop_time=task.stop_time,
                                 parameters={**dict(task.parameters), **seeds})
        elapsed = time.perf_counter() - start
    return RunRecord(index, seeds, results, elapsed, worker_name(), resident_memory())
