"""Running ``altfusion evaluate``: one Monte Carlo campaign per scenario and ``--told``
variant (:mod:`altfusion.evaluation.told`), every applicable estimator side by side in each
run, then the metrics of every (estimator, scenario) cell of every variant.

Each scenario's system is written once to ``OUT/<variant>/<scenario>/system.ssp`` with its
description ``scenario.json``; its campaign lives in ``OUT/<variant>/<scenario>/``
(:mod:`altfusion.montecarlo.execution`: seeds, workers, storage, atomic writes, resume).
Run i of every scenario uses master seed M and run index i, so every estimator of a scenario
reads the same sensor outputs, in every variant. ``OUT/evaluation.json`` records the settings
and the told modes; ``--resume`` checks them and completes the missing runs of every variant.
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
from altfusion.evaluation.told import DEFAULT_TOLD, TOLD_MODES, Told, told_variants
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


def _choose(option: str, noun: str, given: list[str] | None, known: list[str]) -> list[str]:
    """The names ``given`` to ``--option`` (None: every ``known`` one); an unknown or
    repeated name, or none, is the user's mistake."""
    if given is None:
        return list(known)
    unknown = [name for name in given if name not in known]
    if unknown:
        raise EvaluationError(f"unknown {noun}s {', '.join(unknown)}; known: "
                              f"{', '.join(known)}")
    if not given:
        raise EvaluationError(f"--{option} names no {noun}")
    if len(set(given)) != len(given):
        raise EvaluationError(f"--{option} must name each {noun} once")
    return list(given)


def choose_told(modes: list[str]) -> list[Told]:
    """The variants of the ``--told`` modes (each known, once)."""
    return told_variants(_choose("told", "told mode", modes, list(TOLD_MODES)))


Plans = dict[Told, list[Scenario]]
"""Each ``--told`` variant's scenarios."""


def plan_evaluation(models: Path, estimators: list[str] | None = None,
                    scenarios: list[str] | None = None, told: tuple[Told, ...] = (DEFAULT_TOLD,),
                    ) -> tuple[Plans, dict[str, EstimatorInfo], dict[str, Path]]:
    """The scenarios to run in each variant of ``told`` (a fault scenario brings its nominal
    flight along), the estimators and the FMU files of ``models``."""
    fmu_paths = {path.stem: path.resolve() for path in sorted(Path(models).glob("*.fmu"))}
    found = discover_estimators(fmu_paths)
    if not found:
        raise EvaluationError(f"no estimator FMU in {models} (build them: python build_fmu.py)")
    chosen = _choose("estimators", "estimator", estimators, list(found))
    kinds = available_scenarios()
    names = _choose("scenarios", "scenario", scenarios, list(kinds))
    from altfusion.evaluation.faults import NOMINAL, fault_scenario, nominal_scenario

    if any(kinds[n] == "fault" and n != NOMINAL for n in names) and NOMINAL not in names:
        names.append(NOMINAL)
    plans: Plans = {}
    for variant in told:
        plans[variant] = [
            paper_scenario(name, found, fmu_paths, chosen, variant) if kinds[name] == "paper"
            else nominal_scenario(found, fmu_paths, chosen, variant) if name == NOMINAL
            else fault_scenario(name, found, fmu_paths, chosen, variant) for name in names]
    return plans, {n: found[n] for n in chosen}, fmu_paths


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


def told_modes(plans: Plans) -> list[str]:
    """The ``--told`` modes of the planned variants."""
    return list(dict.fromkeys(told.mode for told in plans))


def _settings_json(settings: EvaluationSettings, plans: Plans,
                   estimators: list[str]) -> dict[str, Any]:
    scenarios = next(iter(plans.values()))
    return {"format": 2, "runs": settings.runs, "master_seed": settings.master_seed,
            "backend": settings.backend, "stop_time": settings.stop_time,
            "scenarios": [s.name for s in scenarios], "estimators": estimators,
            "told": told_modes(plans)}


def check_evaluation(out: Path, settings: EvaluationSettings, plans: Plans,
                     estimators: list[str], resume: bool) -> None:
    """Write ``OUT/evaluation.json``; refuse to overwrite an evaluation unless resuming the
    same one (same scenarios, estimators, told modes, seed, backend, stop time; runs may
    grow)."""
    path = Path(out) / EVALUATION
    new = _settings_json(settings, plans, estimators)
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


def stored_settings(out: Path) -> dict[str, Any]:
    """The settings of the evaluation in ``out`` (empty if there is none)."""
    path = Path(out) / EVALUATION
    return json.loads(path.read_text()) if path.is_file() else {}


def variant_folder(out: Path, told: Told) -> Path:
    """The folder of a variant's campaigns, one per scenario."""
    return Path(out) / told.name


Outcome = tuple[Told, Scenario, CampaignOutcome | None]
"""A campaign's variant, scenario and outcome (None: no estimator applies, nothing run)."""


def run_evaluation(out: Path, plans: Plans, estimators: list[str],
                   fmu_paths: dict[str, Path], settings: EvaluationSettings,
                   execution: Execution, resume: bool = False) -> list[Outcome]:
    """Every variant's scenarios' campaigns in turn; stops at the first interrupted one."""
    if settings.backend not in BACKENDS:
        raise EvaluationError(f"--backend must be one of {', '.join(BACKENDS)}")
    check_evaluation(out, settings, plans, estimators, resume)
    outcomes: list[Outcome] = []
    for told, scenarios in plans.items():
        for scenario in scenarios:
            if not scenario.components:
                outcomes.append((told, scenario, None))
                continue
            if execution.progress:
                print(f"{told.name}/{scenario.name}:", file=sys.stderr, flush=True)
            folder = variant_folder(out, told)
            source = prepare_scenario(scenario, fmu_paths, folder, settings.backend)
            stops = [s for s in (scenario.stop_time, settings.stop_time) if s is not None]
            outcome = run_campaign(
                source, folder / scenario.name,
                CampaignSettings(settings.runs, settings.master_seed,
                                 min(stops) if stops else None),
                execution, resume=has_manifest(folder / scenario.name))
            outcomes.append((told, scenario, outcome))
            if outcome.stopped:
                return outcomes
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


def estimator_cell(column: list[Cell], estimator: str) -> Cell:
    """The cell of ``estimator`` in a scenario's ``column``."""
    return next(c for c in column if c.estimator == estimator)


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


Cells = dict[str, list[Cell]]
"""Scenario name -> its cells, one per estimator."""


def evaluation_cells(out: Path, plans: Plans, estimators: dict[str, EstimatorInfo],
                     ) -> dict[Told, Cells]:
    """Each variant's cells from its campaigns."""
    return {told: scenarios_cells(variant_folder(out, told), scenarios, estimators)
            for told, scenarios in plans.items()}


def scenarios_cells(out: Path, scenarios: list[Scenario],
                    estimators: dict[str, EstimatorInfo]) -> Cells:
    """Scenario name -> its cells (one per estimator) from the campaigns in ``out``, nominal
    scenarios first so that the fault scenarios can compare with their nominal RMS."""
    cells: dict[str, list[Cell]] = {}
    ordered = sorted(scenarios, key=lambda s: s.nominal is not None)
    for scenario in ordered:
        nominal = None
        if scenario.nominal is not None:
            nominal = {c.estimator: c.rms for c in cells.get(scenario.nominal, [])}
        cells[scenario.name] = scenario_cells(out, scenario, estimators, nominal)
    return {s.name: cells[s.name] for s in scenarios}
