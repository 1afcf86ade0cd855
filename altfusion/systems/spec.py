"""A co-simulated system described in Python: components, connections, timing, recording.

This is what the SSP writer serialises and the SSP reader returns; systems are never written
as XML by hand.
"""

from dataclasses import dataclass, field, replace
from typing import Any


@dataclass(frozen=True)
class ComponentSpec:
    """One FMU instance: its FMU model name, its own step and its parameter values."""

    name: str
    fmu: str
    step_size: float
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Connection:
    """Output ``start`` ('component.variable') drives input ``end``."""

    start: str
    end: str


@dataclass(frozen=True)
class Metric:
    """An error signal reported after a run: ``estimate`` minus ``truth`` (both recorded)."""

    name: str
    estimate: str
    truth: str


@dataclass(frozen=True)
class SystemSpec:
    """A system: components stepped on multiples of ``base_step`` from start to stop time."""

    name: str
    description: str
    components: tuple[ComponentSpec, ...]
    connections: tuple[Connection, ...]
    stop_time: float
    base_step: float = 0.01
    start_time: float = 0.0
    output_interval: float | None = None
    record: tuple[str, ...] = ()
    metrics: tuple[Metric, ...] = ()

    def component(self, name: str) -> ComponentSpec:
        for component in self.components:
            if component.name == name:
                return component
        raise KeyError(f"system {self.name} has no component '{name}'")

    def with_parameters(self, overrides: dict[str, Any]) -> "SystemSpec":
        """A copy with 'component.parameter' values overridden."""
        components = []
        for component in self.components:
            mine = {key.split(".", 1)[1]: value for key, value in overrides.items()
                    if key.split(".", 1)[0] == component.name}
            if mine:
                component = replace(component, parameters={**component.parameters, **mine})
            components.append(component)
        unknown = {key.split(".", 1)[0] for key in overrides} - {c.name for c in components}
        if unknown:
            raise KeyError(f"system {self.name} has no component(s) {sorted(unknown)}")
        return replace(self, components=tuple(components))
