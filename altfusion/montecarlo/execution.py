"""Running a campaign: plan it, write its manifest, run the missing runs, store each as it
finishes. An interruption (Ctrl-C, a dead worker) keeps every finished run; ``resume=True``
runs the missing ones of the same campaign."""

import time
import traceback
from collections.abc import Iterator
from concurrent.futures import BrokenExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from altfusion.cosim.instances import CosimError
from altfusion.montecarlo.backends import WorkerPool, open_backend
from altfusion.montecarlo.campaign import CampaignTask, build_manifest, check_resumable, plan
from altfusion.montecarlo.progress import Progress
from altfusion.montecarlo.source import CampaignError, SystemSource
from altfusion.montecarlo.storage import (
    damaged_runs,
    failed_runs,
    finished_runs,
    has_manifest,
    read_manifest,
    write_failure,
    write_manifest,
    write_run,
)

FAIL_FAST = 3
"""Stop when this many runs failed before any succeeded: the system itself is broken."""


@dataclass(frozen=True)
class CampaignSettings:
    """What is simulated. None: the stored campaign's value when resuming, else the default
    (the SSP's stop time, master seed 0, no parameter overrides; ``runs`` is required)."""

    runs: int | None = None
    master_seed: int | None = None
    stop_time: float | None = None
    parameters: dict[str, Any] | None = None

    def resolved(self, stored: dict[str, Any] | None) -> "CampaignSettings":
        stored = stored or {}
        runs = self.runs if self.runs is not None else stored.get("runs")
        if runs is None:
            raise CampaignError("a new campaign needs its number of runs (-n N)")
        if runs < 1:
            raise CampaignError(f"-n {runs}: the number of runs must be >= 1")
        return CampaignSettings(
            runs,
            self.master_seed if self.master_seed is not None else stored.get("master_seed", 0),
            self.stop_time if self.stop_time is not None else stored.get("stop_time"),
            self.parameters if self.parameters is not None else stored.get("parameters", {}),
        )


@dataclass(frozen=True)
class Execution:
    """How runs are executed: local worker processes (default: every available core) or the
    Dask scheduler at ``scheduler``; whether to draw a progress line on stderr. With a
    ``pool`` (and no scheduler) the local workers are the pool's, kept after the campaign
    for the next one (:class:`~altfusion.montecarlo.backends.WorkerPool`)."""

    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True
    pool: WorkerPool | None = None


@contextmanager
def kept_workers(execution: Execution) -> Iterator[Execution]:
    """``execution`` with one :class:`~altfusion.montecarlo.backends.WorkerPool` of local
    workers for every campaign run with it (a reproduction's, an evaluation's), closed on
    exit."""
    pool = WorkerPool(execution.workers)
    try:
        yield replace(execution, pool=pool)
    finally:
        pool.close()


@dataclass
class CampaignOutcome:
    out: Path
    runs: int
    finished: list[int]
    failed: dict[int, str]
    executed: int
    """Runs executed (successfully or not) in this session."""
    elapsed: float
    backend: str = ""
    stopped: str | None = None
    """Why the session stopped early (None: it ran every missing run)."""
    failing: bool = False
    """It stopped because the system fails (resuming unchanged would fail again)."""
    missing: list[int] = field(default_factory=list)
    damaged: dict[int, str] = field(default_factory=dict)
    """Stored runs found damaged by ``--resume`` (re-run), with what was wrong."""

    @property
    def complete(self) -> bool:
        return len(self.finished) == self.runs


def prepare_campaign(source: SystemSource, out: Path, settings: CampaignSettings,
                     resume: bool = False) -> tuple[CampaignTask, dict[str, Any]]:
    """Plan the campaign and write its manifest (checked against the stored one on resume)."""
    out = Path(out)
    stored = read_manifest(out) if has_manifest(out) else None
    if stored is not None and not resume:
        raise CampaignError(f"{out} already holds a campaign: --resume completes it, or "
                            f"choose another --out")
    if stored is None and resume:
        raise CampaignError(f"no campaign to resume in {out} (no manifest.json)")
    settings = settings.resolved(stored)
    task, prepared = plan(source, settings.master_seed, settings.stop_time, settings.parameters)
    manifest = build_manifest(task, prepared, settings.runs)
    if stored is not None:
        check_resumable(stored, manifest)
        manifest = {**manifest, "created": stored["created"], "versions": stored["versions"],
                    "sessions": stored["sessions"] + manifest["sessions"]}
    write_manifest(out, manifest)
    return task, manifest


def run_campaign(source: SystemSource, out: Path, settings: CampaignSettings,
                 execution: Execution | None = None, resume: bool = False,
                 ) -> CampaignOutcome:
    """Run (or, with ``resume``, complete) the campaign of ``source`` in folder ``out``."""
    out = Path(out)
    execution = execution or Execution()
    task, manifest = prepare_campaign(source, out, settings, resume)
    runs = manifest["runs"]
    damaged = damaged_runs(out) if resume else {}
    done = set(finished_runs(out)) - set(damaged)
    todo = [index for index in range(runs) if index not in done]
    start = time.monotonic()
    outcome = CampaignOutcome(out, runs, sorted(done), {}, 0, 0.0, damaged=damaged)
    if todo:
        outcome = _execute(task, out, todo, outcome, execution)
    outcome.finished = finished_runs(out)
    outcome.failed = {i: m for i, m in failed_runs(out).items() if i < runs}
    outcome.missing = [i for i in range(runs) if i not in set(outcome.finished)]
    outcome.elapsed = time.monotonic() - start
    return outcome


def _describe(error: BaseException) -> str:
    """The error message; for errors other than CosimError (which carry the FMU's message and
    traceback already) its type and message in one line, then the traceback, the worker's one
    included (the first line is what the command line shows)."""
    if isinstance(error, CosimError):
        return str(error)
    message = " ".join(str(error).split()) or repr(error)
    return (f"{type(error).__name__}: {message}\n\n"
            + "".join(traceback.format_exception(error)).strip())


def _execute(task: CampaignTask, out: Path, todo: list[int], outcome: CampaignOutcome,
             execution: Execution) -> CampaignOutcome:
    pool = execution.pool if execution.scheduler is None else None
    backend = pool.backend(task, len(todo)) if pool is not None else \
        open_backend(task, execution.workers, execution.scheduler, len(todo))
    progress = Progress(outcome.runs, outcome.runs - len(todo), enabled=execution.progress)
    stopped, executed, succeeded, failures, clean = None, 0, 0, 0, False
    try:
        futures = {}
        for index in todo:
            future = backend.submit(task, index)
            futures[id(future)] = (future, index)
        for future in backend.as_completed(f for f, _ in futures.values()):
            # Keep no reference to a finished run's future: its result (every recorded
            # signal) is freed once written, so memory does not grow with the runs.
            index = futures.pop(id(future))[1]
            try:
                record = future.result()
            except BrokenExecutor:
                stopped = f"a worker process died while running run {index} or another run"
                break
            except Exception as error:
                executed += 1
                failures += 1
                write_failure(out, index, _describe(error))
                progress.advance(failed=True)
                if not succeeded and failures >= FAIL_FAST:
                    stopped = (f"the first {failures} runs failed: "
                               f"{_describe(error).splitlines()[0]}")
                    outcome = replace(outcome, failing=True)
                    break
                continue
            write_run(out, record)
            executed += 1
            succeeded += 1
            progress.advance()
        clean = stopped is None
    except KeyboardInterrupt:
        stopped = "interrupted"
    finally:
        progress.close()
        if pool is not None:
            pool.release(cancel=not clean)
        else:
            backend.close(cancel=not clean)
    return replace(outcome, executed=executed, stopped=stopped, backend=backend.description)
