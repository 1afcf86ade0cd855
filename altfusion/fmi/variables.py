"""Declarations of an FMU's inputs and outputs (its parameters come from the core's Params)."""

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Input:
    """An FMI input mapped onto the core attribute of the same name."""

    name: str
    unit: str | None
    description: str
    type: type = float
    start: Any = 0.0
    min: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class Output:
    """An FMI output read from the core attribute of the same name.

    ``depends_on`` lists the inputs whose value at the end of a step enters the output at that
    instant (direct feedthrough); ``None`` means every input, ``()`` none (a state output).
    """

    name: str
    unit: str | None
    description: str
    type: type = float
    depends_on: tuple[str, ...] | None = None
    min: float | None = None
    max: float | None = None
