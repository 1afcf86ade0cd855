"""A system's sensor streams: which component samples what, on which declared schedule, and
which estimators consume each stream's count.

A stream is a component with a ``sample_period`` parameter and a pair of outputs
``<prefix>_count`` and ``<prefix>_time`` (``docs/signals.md``); its schedule is the
component's ``sample_period``, ``sample_offset`` and ``latency``, from the SSP's parameter
values or else the FMU's defaults. A consumer is a component whose input is connected to the
stream's count; a component that passes the count on under the same output name (the
SensorFaults FMU: ``raw_gps_count`` in, ``gps_count`` out) is a relay, followed to the
consumers behind it.
"""

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from fmpy import read_model_description

from altfusion.errors import UsageError
from altfusion.systems.spec import SystemSpec
from altfusion.timegrid import exact

SCHEDULE_PARAMETERS = ("sample_period", "sample_offset", "latency")


@dataclass(frozen=True)
class Consumer:
    """An input connected to a stream's count, possibly through relays."""

    component: str
    variable: str
    handover: float
    """The longest time, s, a host may take to hand a new count over: the consumer's step
    plus the step of every relay on the way (a Jacobi master exchanges once per step)."""
    relays: tuple[str, ...] = ()

    @property
    def column(self) -> str:
        return f"{self.component}.{self.variable}"


@dataclass(frozen=True)
class Stream:
    """One sensor stream and its declared schedule (exact decimals, as the FMU counts them)."""

    component: str
    fmu: str
    prefix: str
    period: Fraction
    offset: Fraction
    latency: Fraction
    step: float
    """The component's communication step in the system, s (its SSP step size hint)."""
    consumers: tuple[Consumer, ...] = ()
    valid: str | None = None
    """The output saying whether the measurement is valid (``<prefix>_valid``, ``gps_fix``);
    None for a sensor that takes every sample (barometer, accelerometer)."""

    @property
    def name(self) -> str:
        return f"{self.component}.{self.prefix}"

    @property
    def count_column(self) -> str:
        return f"{self.component}.{self.prefix}_count"

    @property
    def time_column(self) -> str:
        return f"{self.component}.{self.prefix}_time"

    @property
    def valid_column(self) -> str | None:
        return f"{self.component}.{self.valid}" if self.valid else None

    def columns(self) -> tuple[str, ...]:
        """Every signal the check reads: count, stamp, validity and each consumer's count."""
        valid = (self.valid_column,) if self.valid_column else ()
        return (self.count_column, self.time_column, *valid,
                *(c.column for c in self.consumers))


@dataclass(frozen=True)
class _Model:
    """The variables of one FMU: causality and start value by name."""

    outputs: frozenset[str]
    starts: dict[str, str | None]


def _models(system: SystemSpec, fmu_paths: dict[str, Path]) -> dict[str, _Model]:
    models = {}
    for fmu in {c.fmu for c in system.components}:
        md = read_model_description(str(fmu_paths[fmu]))
        models[fmu] = _Model(
            frozenset(v.name for v in md.modelVariables if v.causality == "output"),
            {v.name: v.start for v in md.modelVariables if v.causality == "parameter"})
    return models


def sensor_streams(system: SystemSpec, fmu_paths: dict[str, Path]) -> tuple[Stream, ...]:
    """Every sensor stream of ``system``, with its consumers; a UsageError if there is none."""
    models = _models(system, fmu_paths)
    streams = []
    for component in system.components:
        model = models[component.fmu]
        if "sample_period" not in model.starts:
            continue
        schedule = {name: exact(float(component.parameters.get(name, model.starts.get(name))
                                      or 0.0))
                    for name in SCHEDULE_PARAMETERS}
        for output in sorted(model.outputs):
            prefix = output.removesuffix("_count")
            if prefix == output or f"{prefix}_time" not in model.outputs:
                continue
            valid = next((name for name in (f"{prefix}_valid", f"{prefix}_fix")
                          if name in model.outputs), None)
            streams.append(Stream(
                component.name, component.fmu, prefix, schedule["sample_period"],
                schedule["sample_offset"], schedule["latency"], component.step_size,
                _consumers(system, models, f"{component.name}.{output}", output), valid))
    if not streams:
        raise UsageError(f"system {system.name} has no sensor stream (no component with a "
                         f"sample_period parameter and <prefix>_count/<prefix>_time outputs)")
    return tuple(streams)


def _consumers(system: SystemSpec, models: dict[str, _Model], source: str, count: str,
               relays: tuple[str, ...] = (), delay: float = 0.0) -> tuple[Consumer, ...]:
    """The inputs fed by output ``source`` (a stream's ``count``), relays followed."""
    found: list[Consumer] = []
    for connection in system.connections:
        if connection.start != source:
            continue
        name, _, variable = connection.end.partition(".")
        component = system.component(name)
        if count in models[component.fmu].outputs and name not in relays:
            found += _consumers(system, models, f"{name}.{count}", count, (*relays, name),
                                delay + component.step_size)
        else:
            found.append(Consumer(name, variable, delay + component.step_size, relays))
    return tuple(found)


def timing_signals(streams: tuple[Stream, ...]) -> tuple[str, ...]:
    """The signals to record for a timing check, each once, in stream order."""
    return tuple(dict.fromkeys(column for stream in streams for column in stream.columns()))
