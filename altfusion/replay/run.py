"""``altfusion replay``: build a LogReplay + estimators system for a log, run it, compare.

This is co-simulation-level code (it steps FMUs through fmpy); the FMUs themselves never
import it. Each estimator gets the inputs its FMU declares (read from its modelDescription),
each connected to the LogReplay output of the same name, and the replay tuning of
:mod:`altfusion.systems.replay` unless ``paper_tuning``.
"""

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from altfusion.cosim.instances import CosimError, fmu_info
from altfusion.cosim.results import Results
from altfusion.cosim.runner import Simulation
from altfusion.errors import UsageError
from altfusion.replay.calibration import launch_calibration
from altfusion.replay.compare import EstimatorReport, compare_all, settle_time, write_summary
from altfusion.replay.extract import ATTITUDE, EKF_PREFIX, LOCAL_POSITION, FlightLog
from altfusion.replay.plot import plot_replay
from altfusion.replay.ulog import LogReadError, read_ulog
from altfusion.systems.replay import BASE_STEP, EstimatorEntry, replay_system, replay_tuning
from altfusion.systems.spec import SystemSpec

DAMAGE = ("missing topic", "non-finite", "bad time stamp", "non-monotonic", "duplicate")
"""Findings about a sensor topic that say its data are damaged (named when none is left)."""


@dataclass
class ReplayRun:
    """What a replay produced."""

    log: FlightLog
    spec: SystemSpec
    results: Results
    reports: list[EstimatorReport]
    settle_time: float
    unconnected: dict[str, list[str]] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)


def stop_time_for(log: FlightLog, time_offset: float = 0.0) -> float:
    """The log's duration (after ``time_offset``) rounded up to a whole base step."""
    steps = math.ceil(round((log.duration - time_offset) / BASE_STEP, 9))
    return float(f"{steps * BASE_STEP:.10g}")


def declared_inputs(fmu: Path) -> tuple[str, ...]:
    """The input variables an FMU declares, in modelDescription order."""
    return tuple(v.name for v in fmu_info(fmu).variables.values() if v.causality == "input")


def estimator_entries(names: list[str], fmu_paths: dict[str, Path], log: FlightLog,
                      paper_tuning: bool) -> list[EstimatorEntry]:
    missing = [n for n in ["LogReplay", *names] if n not in fmu_paths]
    if missing:
        raise CosimError(f"no FMU for {', '.join(missing)} (known: {', '.join(sorted(fmu_paths))}"
                         f"); build them with python build_fmu.py")
    calibration = launch_calibration(log)
    return [EstimatorEntry(name, declared_inputs(fmu_paths[name]),
                           {} if paper_tuning else replay_tuning(name, calibration))
            for name in names]


@dataclass
class ReplayPlan:
    """A log read and its replay system built, ready to run."""

    log_file: Path
    log: FlightLog
    spec: SystemSpec
    estimators: list[str]
    unconnected: dict[str, list[str]]


def plan_replay(log_file: Path, estimators: list[str], fmu_paths: dict[str, Path],
                paper_tuning: bool = False, time_offset: float = 0.0) -> ReplayPlan:
    """Read ``log_file`` and build its system with ``estimators`` (FMU model names)."""
    log_file = Path(log_file).resolve()
    log = read_ulog(log_file)
    if log.duration < BASE_STEP:
        sensors = [p for s in log.streams.values() if s.prefix != EKF_PREFIX for p in s.problems]
        found = "; ".join(list(dict.fromkeys(
            f"{p.topic}: {p.kind}" for p in [*log.problems, *sensors]
            if p.topic not in (LOCAL_POSITION, ATTITUDE) and p.kind in DAMAGE))[:4])
        counts = ", ".join(f"{s.topic} {len(s)}" for s in log.streams.values()
                           if s.prefix != EKF_PREFIX) or "none"
        reader = next((f"; {p.message}" for p in log.problems if p.kind == "damaged"), "")
        raise LogReadError(f"{log_file}: the sensor data span {log.duration:g} s, less than "
                           f"one replay step ({BASE_STEP:g} s): the sensor section is missing or "
                           f"damaged (samples: {counts}{'; ' + found if found else ''}{reader})")
    if time_offset >= log.duration:
        raise UsageError(f"time offset {time_offset:g} s: at or beyond the end of the log's "
                         f"sensor data ({log.duration:g} s)")
    entries = estimator_entries(estimators, fmu_paths, log, paper_tuning)
    spec, unconnected = replay_system(f"replay_{log_file.stem}", str(log_file),
                                      stop_time_for(log, time_offset), entries,
                                      f"LogReplay of {log_file.name}", time_offset=time_offset)
    return ReplayPlan(log_file, log, spec, list(estimators), unconnected)


def run_replay(plan: ReplayPlan, fmu_paths: dict[str, Path], out: Path,
               parameters: dict[str, Any] | None = None) -> ReplayRun:
    """Run the plan to the end of the log, compare, write ``<system>.csv``, ``.png`` and the
    comparison beside them (``<system>_summary.csv`` and ``_summary.md``)."""
    with Simulation(plan.spec, fmu_paths) as simulation:
        results = simulation.run(parameters=parameters or {})
    start = settle_time(results)
    reports = compare_all(results, plan.estimators, start)
    out = Path(out)
    csv_path = results.to_csv(out / f"{plan.spec.name}.csv")
    png_path = plot_replay(results, plan.estimators, out / f"{plan.spec.name}.png",
                           f"{plan.log_file.name}: estimators vs PX4 EKF2, raw sensors and "
                           f"rangefinder", start)
    summary = write_summary(reports, out / plan.spec.name)
    return ReplayRun(plan.log, plan.spec, results, reports, start, plan.unconnected,
                     [csv_path, png_path, *summary])
