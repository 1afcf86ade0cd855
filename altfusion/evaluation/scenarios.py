"""The scenarios of ``altfusion evaluate``: each a system flying every applicable estimator side
by side on the same sensor outputs, and the estimators that cannot take part (n/a, and why).

Estimators: every FMU whose core class (named in its modelDescription) is an
:class:`~altfusion.estimators.base.Estimator`, so a new estimator FMU joins by being built.

A paper scenario is the catalog's paper system: its own estimator (component ``estimator``)
keeps its place and its paper's parameters (in a closed-loop system the aircraft flies on
it); the other estimators are added as observers, each a component named after its FMU,
stepped with the paper's estimator and connected by contract names to the sensors the system
has (:func:`altfusion.systems.wiring.estimator_connections`). Comparators the paper system
carries (BaselineKF, a non-adaptive XuSHAEKF) give way to those observers. A fault scenario is
the generic fault flight of :mod:`altfusion.systems.faults` with the fault inserted.

n/a rules (never run on defaults):

* the scenario has no height sensor the estimator reads;
* the scenario lacks a source the estimator's algorithm cannot do without
  (:func:`required_sources`: XuSHAEKF's process model is driven by the accelerometer);
* a fault scenario whose faulty sensors the estimator does not read tells nothing about it.

An estimator reading a source the scenario lacks (YangFusionKF without a radio altimeter) runs
on what it reads: a stream that never delivers a sample is never fused.

Each estimator can be told the scenario's true sensor noise (:func:`sensor_noise`, the
contract names ``baro_noise``... of ``docs/signals.md``) through the parameters it has: the
contract name itself, else the variance ``R_<source>`` (σ²) or ``<source>_noise_std`` (σ). In
a paper scenario it can also be told the sensors' error models beyond white noise that the
paper system states (:data:`altfusion.systems.error_models.SENSOR_ERRORS`: a calibrated
barometer, its drift, flat terrain, an accelerometer's turn-on bias...) through every
parameter it has of the stated name or of the same quantity under its own name
(:func:`error_parameters`: the random walk of the baro height's error is BaselineKF's
``bias_psd``). What it is told, the noise, the models too (the default), nothing or a
misstated noise, is the evaluation's ``--told`` mode (:mod:`altfusion.evaluation.told`). The
paper's own estimator keeps its paper's parameters.
"""

import importlib
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from altfusion.cosim.instances import fmu_info
from altfusion.estimators.base import HEIGHT_SOURCES, Estimator
from altfusion.evaluation.metrics import Fault
from altfusion.evaluation.told import DEFAULT_TOLD, NOISE_NAMES, NOISE_REFERENCES, Told
from altfusion.montecarlo.source import CampaignError
from altfusion.systems.catalog import build_system
from altfusion.systems.error_models import SENSOR_ERRORS
from altfusion.systems.sensors import SENSORS
from altfusion.systems.spec import ComponentSpec, Metric, SystemSpec
from altfusion.systems.wiring import EXTRA_SOURCES, SENSOR_OF_PREFIX, estimator_connections

PAPER_ESTIMATOR = "estimator"
"""The component of a paper system that runs the paper's estimator."""

PAPER_SCENARIOS = ("whang2008", "bao2017", "hajiyev", "hajiyev_drift", "yang2020",
                   "xu2016_hover15")
"""The paper systems evaluated (docs/montecarlo.md says why these)."""

SHORTENED: dict[str, tuple[float, str]] = {
    "bao2017": (1800.0, "Flown for the first 1800 s of the hour: the nominal, poor (Fig. 8's "
                        "left ellipse) and medium GPS phases; the hour with the good phase is "
                        "`altfusion reproduce bao2017`'s."),
}
"""Paper scenarios flown shorter than the paper (stop time, s; why) to fit the budget."""

RECORDED = ("h_est", "h_std", "h_valid", "status")
"""What is recorded of every estimator."""

SOURCE_OF_SENSOR = {sensor: prefix for prefix, sensor in SENSOR_OF_PREFIX.items()}
"""Signal prefix (source) of each sensor component."""


class EvaluationError(CampaignError):
    """A scenario or estimator that cannot be evaluated; the message says why."""


@dataclass(frozen=True)
class EstimatorInfo:
    """An estimator FMU: its model name, file, core class and FMI parameters."""

    name: str
    path: Path
    core: type[Estimator]
    parameters: frozenset[str]

    @property
    def sources(self) -> tuple[str, ...]:
        return self.core.sources()

    @property
    def height_sources(self) -> tuple[str, ...]:
        return tuple(s for s in self.sources if s in HEIGHT_SOURCES)


def core_class(path: Path) -> type | None:
    """The core class an FMU names in its modelDescription (None if it names none)."""
    named = fmu_info(path).core_class
    if not named:
        return None
    module, _, qualname = named.partition(":")
    try:
        found = importlib.import_module(module)
        for part in qualname.split("."):
            found = getattr(found, part)
    except (ImportError, AttributeError):
        return None
    return found if isinstance(found, type) else None


def discover_estimators(fmu_paths: dict[str, Path]) -> dict[str, EstimatorInfo]:
    """Every FMU of ``fmu_paths`` (model name -> file) whose core class is an Estimator."""
    found = {}
    for name, path in sorted(fmu_paths.items()):
        core = core_class(path)
        if core is not None and issubclass(core, Estimator):
            parameters = frozenset(v.name for v in fmu_info(path).variables.values()
                                   if v.causality == "parameter")
            found[name] = EstimatorInfo(name, path, core, parameters)
    return found


def required_sources(estimator: EstimatorInfo) -> dict[str, str]:
    """Sources the estimator cannot do without -> why (its core's
    :attr:`~altfusion.estimators.base.Estimator.required_sources`)."""
    return dict(estimator.core.required_sources)


def sensor_sources(spec: SystemSpec) -> dict[str, str]:
    """Source prefix -> sensor component of the system (by the sensor block's names)."""
    return {SOURCE_OF_SENSOR[c.name]: c.name for c in spec.components
            if c.name in SOURCE_OF_SENSOR and SENSORS[c.name].fmu == c.fmu}


def not_applicable(estimator: EstimatorInfo, sources: set[str], fault_needs: tuple[str, ...] = (),
                   ) -> str | None:
    """Why ``estimator`` cannot be evaluated with the sources ``sources`` (None: it can)."""
    if not set(estimator.height_sources) & sources:
        return f"no height sensor it reads ({', '.join(estimator.height_sources)})"
    missing = {s: why for s, why in required_sources(estimator).items() if s not in sources}
    if missing:
        return "; ".join(f"no {source}: {why}" for source, why in missing.items())
    if fault_needs and not set(fault_needs) & set(estimator.sources):
        return f"reads none of the faulty sensors ({', '.join(fault_needs)})"
    return None


def sensor_params(spec: SystemSpec, component: str, fmu_paths: dict[str, Path]) -> Any:
    """The sensor core's parameters of ``component`` (its defaults with the bound values)."""
    spec_component = spec.component(component)
    params_class = core_class(fmu_paths[spec_component.fmu]).Params
    known = {k: v for k, v in spec_component.parameters.items()
             if k in params_class.__dataclass_fields__}
    return replace(params_class(), **known)


def sensor_noise(spec: SystemSpec, fmu_paths: dict[str, Path]) -> dict[str, float]:
    """The true noise (1σ) of the system's sensors under their contract names.

    GPS height: σ = user range error x VDOP x √max(1, nsat_reference / nsat) at the
    receiver's nominal (initial) VDOP and satellites, plus its Gauss-Markov error in
    quadrature, with that VDOP as ``gps_vdop_ref`` (``told.NOISE_REFERENCES``: a noise
    stated at a VDOP is one statement with it); baro: the height noise; the others: their
    white noise."""
    sensors = sensor_sources(spec)
    noise: dict[str, float] = {}
    if "baro" in sensors:
        noise["baro_noise"] = sensor_params(spec, sensors["baro"], fmu_paths).height_noise_std
    if "gps" in sensors:
        p = sensor_params(spec, sensors["gps"], fmu_paths)
        white = p.user_range_error * p.vdop * math.sqrt(max(1.0, p.nsat_reference
                                                            / max(p.nsat, 1)))
        noise["gps_noise"] = math.hypot(white, p.gm_std)
        noise["gps_vdop_ref"] = p.vdop
        noise["gps_vz_noise"] = p.velocity_noise_std
    for source, name in (("acc", "acc_noise"), ("radar", "radar_noise"),
                         ("laser", "laser_noise")):
        if source in sensors:
            noise[name] = sensor_params(spec, sensors[source], fmu_paths).noise_std
    return noise


def noise_parameters(estimator: EstimatorInfo, noise: dict[str, float]) -> dict[str, float]:
    """The estimator's parameters that take the sensor noises ``noise``: the contract name,
    else ``R_<source>`` (variance), else ``<source>_noise_std``; a zero noise is floored at
    1 mm (a variance must be positive). The conditions a noise holds at
    (``told.NOISE_REFERENCES``) go to the estimators that have them, under their names."""
    values = {}
    for name, sigma in noise.items():
        if name in NOISE_REFERENCES:
            if name in estimator.parameters:
                values[name] = sigma
            continue
        source = name.removesuffix("_noise")
        sigma = max(sigma, 1e-3)
        if name in estimator.parameters:
            values[name] = sigma
        elif f"R_{source}" in estimator.parameters:
            values[f"R_{source}"] = sigma**2
        elif f"{source}_noise_std" in estimator.parameters:
            values[f"{source}_noise_std"] = sigma
    return values


def error_parameters(estimator: EstimatorInfo, errors: dict[str, float]) -> dict[str, float]:
    """The parameters that tell the estimator the stated sensor error models ``errors``
    (stated name -> value; :meth:`Estimator.stated_parameters`: its parameter of that name or
    of the same quantity under its own name); the noises among them are left to
    :func:`noise_parameters`."""
    stated = {name: value for name, value in errors.items() if name not in NOISE_NAMES}
    return {name: value for name, value in estimator.core.stated_parameters(stated).items()
            if name in estimator.parameters}


def describe_errors(errors: dict[str, float]) -> str:
    return ", ".join(f"{name} {value:.3g}" for name, value in errors.items())


@dataclass(frozen=True)
class Scenario:
    """One column of the evaluation: the system to run and how to read its results."""

    name: str
    description: str
    spec: SystemSpec
    truth: str
    """Recorded truth signal the estimates are compared with."""
    components: dict[str, str]
    """Estimator model name -> its component in ``spec``."""
    not_applicable: dict[str, str] = field(default_factory=dict)
    """Estimator model name -> why it is not evaluated here."""
    fault: Fault | None = None
    nominal: str | None = None
    """The scenario whose RMS is each estimator's nominal RMS (fault scenarios)."""
    stop_time: float | None = None
    """A shorter stop time than the system's (None: the system's)."""
    note: str = ""
    """Why the flight is shortened, or other choices."""


def record_estimators(components: dict[str, str], truth: str,
                      ) -> tuple[tuple[str, ...], tuple[Metric, ...]]:
    """The truth and each estimator's recorded outputs; one error metric per estimator."""
    record = (truth,) + tuple(f"{c}.{name}" for c in components.values() for name in RECORDED)
    metrics = tuple(Metric(f"{name} error", f"{c}.h_est", truth)
                    for name, c in components.items())
    return record, metrics


def sensor_inputs(estimator: EstimatorInfo, component: str, sources: dict[str, str]):
    """The estimator's inputs from the sensors the system has (the others stay unconnected:
    their streams never deliver a sample)."""
    present = set(sources.values())
    return tuple(c for c in estimator_connections(estimator.core, component)
                 if c.start.partition(".")[0] in present
                 or c.start in EXTRA_SOURCES.values())


def paper_scenario(name: str, estimators: dict[str, EstimatorInfo],
                   fmu_paths: dict[str, Path], selected: list[str] | None = None,
                   told: Told = DEFAULT_TOLD) -> Scenario:
    """The paper system ``name`` with every applicable estimator of ``selected`` (default:
    all of ``estimators``) beside its own, each told what ``told`` tells (the paper's own
    too, as an observer, when ``told.observes_own``)."""
    spec = build_system(name)
    own = spec.component(PAPER_ESTIMATOR)
    truth = next((m.truth for m in spec.metrics if m.estimate == f"{PAPER_ESTIMATOR}.h_est"),
                 None)
    if own.fmu not in estimators or truth is None:
        raise EvaluationError(f"{name}: no estimator component '{PAPER_ESTIMATOR}' with an "
                              f"error metric of its h_est")
    dropped = {c.name for c in spec.components
               if c.fmu in estimators and c.name != PAPER_ESTIMATOR}
    sources = sensor_sources(spec)
    errors = SENSOR_ERRORS.get(name, {})
    noise = {**sensor_noise(spec, fmu_paths),
             **{k: v for k, v in errors.items() if k in NOISE_NAMES}}
    chosen = list(estimators) if selected is None else selected
    components, missing, added, connections = {}, {}, [], []
    for estimator in (estimators[e] for e in chosen):
        if estimator.name == own.fmu and not told.observes_own:
            components[estimator.name] = PAPER_ESTIMATOR
            continue
        reason = not_applicable(estimator, set(sources))
        if reason:
            missing[estimator.name] = reason
            continue
        components[estimator.name] = estimator.name
        added.append(ComponentSpec(estimator.name, estimator.name, own.step_size,
                                   told.tell(noise_parameters(estimator, noise),
                                             error_parameters(estimator, errors))))
        connections.extend(sensor_inputs(estimator, estimator.name, sources))
    record, metrics = record_estimators(components, truth)
    kept = tuple(c for c in spec.components if c.name not in dropped)
    spec = replace(
        spec, name=f"evaluate_{name}",
        components=kept + tuple(added),
        connections=tuple(c for c in spec.connections
                          if c.start.partition(".")[0] not in dropped
                          and c.end.partition(".")[0] not in dropped) + tuple(connections),
        record=record, metrics=metrics)
    stop, note = SHORTENED.get(name, (None, ""))
    description = spec.description + (f" (stated sensor error models: "
                                      f"{describe_errors(errors)})" if errors else "")
    return Scenario(name, description, spec, truth, components, missing, stop_time=stop,
                    note=note)


def describe_noise(noise: dict[str, float]) -> str:
    return ", ".join(f"{name} {value:g}" for name, value in noise.items())
