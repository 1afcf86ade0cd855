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


class UsageError(ValueError):
    """A user's mistake in a command line or an input file; the message names the file,
    component or parameter. The command line reports it in one line, exit status 2."""
