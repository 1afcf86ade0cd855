"""The fault scenarios of ``altfusion evaluate``: the fault suite's generic flight
(:func:`altfusion.systems.faults.fault_flight`) without a fault (``nominal_flight``, the
nominal RMS of each estimator) and with each fault of :data:`~altfusion.systems.faults.FAULTS`.

The flight is closed on the true altitude, so every estimator is an observer: each is a
component named after its FMU, connected by contract names to the five sensors, told what
the ``--told`` mode tells (:mod:`~altfusion.evaluation.told`) of the flight's true sensor
noise (the flight's own choices for the estimators it knows, then
:func:`~.scenarios.noise_parameters`) and of its error models (the rest of the fault suite's
settings: the flat terrain, AltitudeEKF's range height reference, the baro and GNSS-offset
walks). An estimator reading none of the sensors a fault needs (``FaultScenario.needs``) is
n/a for that fault: the fault tells nothing about it.

Rate: the flight's own (:func:`~altfusion.systems.faults.fault_flight`: plant, fast
sensors, fault component and estimators at 20 Hz, GNSS 10 Hz, radio altimeter 5 Hz); every
estimator is stepped at the flight's base step. Each estimator's cost is per step and per fused
sample: at 100 Hz the suite would not let ``altfusion evaluate --runs 20`` finish within 30
minutes on two cores (``benchmarks/RESULTS.md``). 20 Hz is the rate PX4 logs its barometer
at (the replayed flights), the faults act over seconds, and the noise per sample is unchanged.

Length: a fault that starts in flight (``start`` > 0) is flown until :data:`AFTER_TRANSIENT`
after its transient (isolation and recovery are assessed within the transient, 10 s + 30 s
in the suite; the minute after gives the coverage once the fault is handled); a fault from
the start (ground effect, prop wash, weather, sample stamps, acc_bias with its clipping
episode at 150 s) flies the whole flight, as does the nominal flight.
"""

from dataclasses import replace
from pathlib import Path

from altfusion.evaluation.metrics import Fault
from altfusion.evaluation.scenarios import (
    EstimatorInfo,
    Scenario,
    noise_parameters,
    not_applicable,
    record_estimators,
    sensor_inputs,
    sensor_noise,
    sensor_sources,
)
from altfusion.evaluation.told import DEFAULT_TOLD, Told, split_noise
from altfusion.systems.faults import (
    FAULTS,
    TRUE_NOISE,
    fault_flight,
    with_fault,
)
from altfusion.systems.spec import ComponentSpec

AFTER_TRANSIENT = 60.0
"""Seconds flown after the transient of a fault that starts in flight."""

NOMINAL = "nominal_flight"
"""The fault flight without a fault."""

TRUTH = "plant.h"


def fault_names() -> list[str]:
    """The fault scenarios: the nominal flight, then the suite's faults in its order."""
    return [NOMINAL, *FAULTS]


def _flight(estimators: dict[str, EstimatorInfo], fmu_paths: dict[str, Path],
            selected: list[str], told: Told, needs: tuple[str, ...] = ()) -> Scenario:
    spec = fault_flight(estimators=())
    sources = sensor_sources(spec)
    noise = sensor_noise(spec, fmu_paths)
    components, missing, added, connections = {}, {}, [], []
    for estimator in (estimators[name] for name in selected):
        reason = not_applicable(estimator, set(sources), needs)
        if reason:
            missing[estimator.name] = reason
            continue
        components[estimator.name] = estimator.name
        stated, models = split_noise(TRUE_NOISE.get(estimator.name, {}))
        added.append(ComponentSpec(estimator.name, estimator.name, spec.base_step,
                                   told.tell({**stated, **noise_parameters(estimator, noise)},
                                             models)))
        connections.extend(sensor_inputs(estimator, estimator.name, sources))
    record, metrics = record_estimators(components, TRUTH)
    spec = replace(spec, name="evaluate_fault_flight",
                   components=spec.components + tuple(added),
                   connections=spec.connections + tuple(connections),
                   record=record, metrics=metrics)
    return Scenario(NOMINAL, "The fault suite's flight without a fault: " + spec.description,
                    spec, TRUTH, components, missing)


def nominal_scenario(estimators: dict[str, EstimatorInfo], fmu_paths: dict[str, Path],
                     selected: list[str], told: Told = DEFAULT_TOLD) -> Scenario:
    """The fault flight without a fault, its estimators told what ``told`` tells."""
    return _flight(estimators, fmu_paths, selected, told)


def fault_scenario(name: str, estimators: dict[str, EstimatorInfo],
                   fmu_paths: dict[str, Path], selected: list[str],
                   told: Told = DEFAULT_TOLD) -> Scenario:
    """The fault flight with fault ``name``, its estimators told what ``told`` tells; its
    nominal RMS comes from :data:`NOMINAL` (of the same mode)."""
    fault = FAULTS[name]
    flight = _flight(estimators, fmu_paths, selected, told, fault.needs)
    spec = replace(with_fault(flight.spec, name), name=f"evaluate_{name}",
                   record=flight.spec.record)
    stop = None
    if fault.start > 0.0 and fault.start + fault.transient + AFTER_TRANSIENT < spec.stop_time:
        stop = fault.start + fault.transient + AFTER_TRANSIENT
    return replace(flight, name=name, description=f"{fault.description} ({fault.origin})",
                   spec=spec, fault=Fault(fault.start, fault.faulty, fault.transient),
                   nominal=NOMINAL, stop_time=stop,
                   note=f"Flown to {stop:g} s, {AFTER_TRANSIENT:g} s after the fault's "
                        f"transient." if stop else "")
