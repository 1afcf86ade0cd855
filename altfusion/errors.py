"""Exceptions shared by the core, the FMU adapters and the runner."""

from typing import Any


class ParameterError(ValueError):
    """An invalid parameter value; the message names the parameter and the value."""

    def __init__(self, name: str, value: Any, reason: str):
        self.name = name
        self.value = value
        self.reason = reason
        super().__init__(f"parameter '{name}' = {value!r}: {reason}")


class StepError(RuntimeError):
    """A step request the component cannot honour (wrong time or step size)."""
