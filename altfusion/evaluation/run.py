"""Running ``altfusion evaluate``: one Monte Carlo campaign per scenario, every applicable
estimator side by side in each run, then the metrics of every (estimator, scenario) cell.

Each scenario's system is written once to ``OUT/<scenario>/system.ssp`` with its description
``scenario.json``; its campaign lives in ``OUT/<scenario>/``
(:mod:`altfusion.montecarlo.execution`: seeds, workers, storage, atomic writes, resume).
Run i of every scenario uses master seed M and run index i, so every estimator of a scenario
reads the same sensor outputs. ``OUT/evaluation.json`` records the settings; ``--resume``
checks them and completes the missing runs.
"""

import dataclasses
import json
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from altfusion.atomic import write_text
from altfusion.cosim.ssp import write_ssp
from altfusion.evaluation.metrics import (
    RunMetrics,
    Series,
    Summary,
    run_metrics,
    summarize,
    summarize_rms,
)
from altfusion.evaluation.scenarios import (
    PAPER_SCENARIOS,
    EstimatorInfo,
    EvaluationError,
    Scenario,
    discover_estimators,
    paper_scenario,
)
from altfusion.montecarlo.execution import (
    CampaignOutcome,
    CampaignSettings,
    Execution,
    run_campaign,
)
from altfusion.montecarlo.source import SystemSource
from altfusion.montecarlo.storage import finished_runs, has_manifest, load_run

EVALUATION = "evaluation.json"
SCENARIO = "scenario.json"
SSP = "system.ssp"
BACKENDS = ("core", "fmu")
METRICS = ("rms", "max_abs", "coverage", "valid_fraction", "time_to_isolate",
           "time_to_recover")


@dataclass(frozen=True)
class EvaluationSettings:
    """What is evaluated: ``runs`` seeded runs per scenario from ``master_seed``, on the
    runner's ``backend``; ``stop_time`` caps every scenario's flight (None: each its own)."""

    runs: int
    master_seed: int = 0
    backend: str = "core"
    stop_time: float | None = None


def available_scenarios() -> dict[str, str]:
    """Scenario name -> kind ('paper' or 'fault'), paper scenarios first."""
    from altfusion.evaluation.faults import fault_names

    return {**dict.fromkeys(PAPER_SCENARIOS, "paper"), **dict.fromkeys(fault_names(), "fault")}


def _choose(kind: str, given: list[str] | None, known: list[str]) -> list[str]:
    if given is None:
        return list(known)
    unknown = [name for name in given if name not in known]
    if unknown:
        raise EvaluationError(f"unknown {kind} {', '.join(unknown)}; known: {', '.join(known)}")
    if len(set(given)) != len(given) or not given:
        raise EvaluationError(f"--{kind} must name each {kind[:-1]} once")
    return list(given)


def plan_evaluation(models: Path, estimators: list[str] | None = None,
                    scenarios: list[str] | None = None,
                    ) -> tuple[list[Scenario], dict[str, EstimatorInfo], dict[str, Path]]:
    """The scenarios to run (a fault scenario brings its nominal flight along), the
    estimators and the FMU files of ``models``."""
    fmu_paths = {path.stem: path.resolve() for path in sorted(Path(models).glob("*.fmu"))}
    found = discover_estimators(fmu_paths)
    if not found:
        raise EvaluationError(f"no estimator FMU in {models} (build them: python build_fmu.py)")
    chosen = _choose("estimators", estimators, list(found))
    kinds = available_scenarios()
    names = _choose("scenarios", scenarios, list(kinds))
    planned: list[Scenario] = []
    from altfusion.evaluation.faults import NOMINAL, fault_scenario, nominal_scenario

    if any(kinds[n] == "fault" and n != NOMINAL for n in names) and NOMINAL not in names:
        names.append(NOMINAL)
    for name in names:
        if kinds[name] == "paper":
            planned.append(paper_scenario(name, found, fmu_paths, chosen))
        elif name == NOMINAL:
            planned.append(nominal_scenario(found, fmu_paths, chosen))
        else:
            planned.append(fault_scenario(name, found, fmu_paths, chosen))
    return planned, {n: found[n] for n in chosen}, fmu_paths


def scenario_json(scenario: Scenario) -> dict[str, Any]:
    """A scenario's description as stored in ``scenario.json`` (JSON-ready)."""
    data = dataclasses.asdict(scenario)
    return json.loads(json.dumps(data))


def prepare_scenario(scenario: Scenario, fmu_paths: dict[str, Path], out: Path,
                     backend: str) -> SystemSource:
    """Write the scenario's SSP and description into ``out/<name>/`` (kept if identical: a
    resumed campaign needs the very same archive), return its campaign source."""
    folder = Path(out) / scenario.name
    description = json.dumps(scenario_json(scenario), indent=2, sort_keys=True) + "\n"
    ssp = folder / SSP
    stored = folder / SCENARIO
    if stored.is_file() and ssp.is_file():
        if stored.read_text() != description:
            raise EvaluationError(f"{folder} holds another version of scenario "
                                  f"{scenario.name} (the system or the estimators changed): "
                                  f"evaluate into a new --out")
    else:
        _write_ssp(scenario, fmu_paths, ssp)
        write_text(stored, description)
    return SystemSource.from_path(ssp, backend=backend)


def _write_ssp(scenario: Scenario, fmu_paths: dict[str, Path], path: Path) -> None:
    """Write the SSP under a temporary name in its folder, then rename it into place."""
    temporary = path.with_name(f".{path.name}.tmp")
    try:
        write_ssp(scenario.spec, fmu_paths, temporary)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def _settings_json(settings: EvaluationSettings, scenarios: list[Scenario],
                   estimators: list[str]) -> dict[str, Any]:
    return {"format": 1, "runs": settings.runs, "master_seed": settings.master_seed,
            "backend": settings.backend, "stop_time": settings.stop_time,
            "scenarios": [s.name for s in scenarios], "estimators": estimators}


def check_evaluation(out: Path, settings: EvaluationSettings, scenarios: list[Scenario],
                     estimators: list[str], resume: bool) -> None:
    """Write ``OUT/evaluation.json``; refuse to overwrite an evaluation unless resuming the
    same one (same scenarios, estimators, seed, backend, stop time; runs may grow)."""
    path = Path(out) / EVALUATION
    new = _settings_json(settings, scenarios, estimators)
    if path.is_file():
        if not resume:
            raise EvaluationError(f"{out} already holds an evaluation: --resume completes it, "
                                  f"or choose another --out")
        stored = json.loads(path.read_text())
        differences = [f"{key}: {stored.get(key)!r} then, {new[key]!r} now" for key in new
                       if key != "runs" and stored.get(key) != new[key]]
        if differences or new["runs"] < stored["runs"]:
            raise EvaluationError("cannot resume another evaluation:\n  " + "\n  ".join(
                differences or [f"runs: {stored['runs']} then, {new['runs']} now"]))
    elif resume:
        raise EvaluationError(f"no evaluation to resume in {out} (no {EVALUATION})")
    write_text(path, json.dumps(new, indent=2) + "\n")


def stored_runs(out: Path) -> int | None:
    """The number of runs of the evaluation in ``out`` (None if there is none)."""
    path = Path(out) / EVALUATION
    return json.loads(path.read_text())["runs"] if path.is_file() else None


def run_evaluation(out: Path, scenarios: list[Scenario], estimators: list[str],
                   fmu_paths: dict[str, Path], settings: EvaluationSettings,
                   execution: Execution, resume: bool = False,
                   ) -> list[tuple[Scenario, CampaignOutcome | None]]:
    """Every scenario's campaign in turn (None: no estimator applies, nothing to run); stops
    at the first interrupted one."""
    if settings.backend not in BACKENDS:
        raise EvaluationError(f"--backend must be one of {', '.join(BACKENDS)}")
    check_evaluation(out, settings, scenarios, estimators, resume)
    outcomes: list[tuple[Scenario, CampaignOutcome | None]] = []
    for scenario in scenarios:
        if not scenario.components:
            outcomes.append((scenario, None))
            continue
        if execution.progress:
            print(f"{scenario.name}:", file=sys.stderr, flush=True)
        source = prepare_scenario(scenario, fmu_paths, out, settings.backend)
        folder = Path(out) / scenario.name
        stops = [s for s in (scenario.stop_time, settings.stop_time) if s is not None]
        outcome = run_campaign(
            source, folder,
            CampaignSettings(settings.runs, settings.master_seed, min(stops) if stops else None),
            execution, resume=has_manifest(folder))
        outcomes.append((scenario, outcome))
        if outcome.stopped:
            break
    return outcomes


@dataclass
class Cell:
    """One estimator in one scenario: n/a (with the reason), or the metrics of its runs."""

    estimator: str
    scenario: str
    not_applicable: str = ""
    runs: list[RunMetrics] = field(default_factory=list)
    time: np.ndarray | None = None
    errors: np.ndarray | None = None
    """Error of each run (rows) versus time (columns)."""
    h_std: np.ndarray | None = None
    startup_end: float = math.inf
    """When the start-up ends, s (the earliest over the runs)."""

    def summary(self, metric: str) -> Summary | None:
        values = [getattr(run, metric) for run in self.runs]
        return summarize_rms(values) if metric == "rms" else summarize(values)

    @property
    def rms(self) -> float:
        """The RMS over runs (:data:`altfusion.scores.RMS_DEFINITION`; nan when n/a or no
        run)."""
        summary = self.summary("rms") if self.runs else None
        return summary.mean if summary is not None else math.nan


def _series(results, component: str, truth: str) -> Series:
    return Series(results.time, results[f"{component}.h_est"] - results[truth],
                  results[f"{component}.h_std"], results[f"{component}.h_valid"],
                  results[f"{component}.status"])


def scenario_cells(out: Path, scenario: Scenario, estimators: dict[str, EstimatorInfo],
                   nominal: dict[str, float] | None = None) -> list[Cell]:
    """The cells of ``scenario`` from its stored runs; ``nominal``: each estimator's nominal
    RMS (fault scenarios)."""
    folder = Path(out) / scenario.name
    cells = {name: Cell(name, scenario.name, scenario.not_applicable.get(name, ""))
             for name in estimators}
    runs = finished_runs(folder) if scenario.components else []
    series: dict[str, list[Series]] = {name: [] for name in scenario.components}
    for index in runs:
        results = load_run(folder, index).results
        for name, component in scenario.components.items():
            if name not in cells:
                continue
            run = _series(results, component, scenario.truth)
            series[name].append(run)
            cells[name].runs.append(run_metrics(
                run, scenario.fault, estimators[name].sources,
                (nominal or {}).get(name, math.nan)))
    for name, runs_ in series.items():
        if runs_ and name in cells:
            length = min(r.time.size for r in runs_)
            cells[name].time = runs_[0].time[:length]
            cells[name].errors = np.vstack([r.error[:length] for r in runs_])
            cells[name].h_std = np.vstack([r.h_std[:length] for r in runs_])
            cells[name].startup_end = min(r.startup_end for r in runs_)
    return list(cells.values())


def evaluation_cells(out: Path, scenarios: list[Scenario],
                     estimators: dict[str, EstimatorInfo]) -> dict[str, list[Cell]]:
    """Scenario name -> its cells (one per estimator), nominal scenarios first so that the
    fault scenarios can compare with their nominal RMS."""
    cells: dict[str, list[Cell]] = {}
    ordered = sorted(scenarios, key=lambda s: s.nominal is not None)
    for scenario in ordered:
        nominal = None
        if scenario.nominal is not None:
            nominal = {c.estimator: c.rms for c in cells.get(scenario.nominal, [])}
        cells[scenario.name] = scenario_cells(out, scenario, estimators, nominal)
    return {s.name: cells[s.name] for s in scenarios}
