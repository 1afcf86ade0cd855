"""Parameter overrides given as ``component.parameter=value`` strings (``--set``)."""

from typing import Any

from altfusion.cosim.instances import PY_TYPES, fmu_info
from altfusion.cosim.ssp import LoadedSystem
from altfusion.errors import UsageError
from altfusion.params import parse_boolean, parse_integer


def parse_settings(loaded: LoadedSystem, settings: list[str]) -> dict[str, Any]:
    """'comp.var=value' strings converted to each parameter's FMI type."""
    values: dict[str, Any] = {}
    for setting in settings:
        path, sep, text = setting.partition("=")
        component, _, name = path.partition(".")
        if not sep or not name:
            raise UsageError(f"--set {setting!r}: expected component.parameter=value")
        try:
            spec = loaded.spec.component(component)
        except KeyError as error:
            raise UsageError(f"--set {setting!r}: {error.args[0]}") from error
        if name == "step_size":
            raise UsageError(f"--set {setting!r}: a component's step_size is the system's "
                             f"(its SSP step size hint), not a --set parameter")
        var = fmu_info(loaded.fmu_paths[spec.fmu]).variables.get(name)
        if var is None or var.causality != "parameter":
            raise UsageError(f"--set {setting!r}: {spec.fmu} has no parameter '{name}'")
        kind = PY_TYPES[var.type]
        parse = {bool: parse_boolean, int: parse_integer}.get(kind, kind)
        try:
            values[path] = parse(text)
        except ValueError as error:
            raise UsageError(f"--set {setting!r}: parameter '{path}' expects "
                             f"{var.type}, not {text!r}") from error
    return values
