"""Parameter declarations: one dataclass field per parameter, carrying its SI unit,
description and bounds. The FMU adapter exposes these fields as FMI parameters, and
:func:`check_params` rejects bad values at initialization with a message naming them."""

import dataclasses
import math
from typing import Any

from altfusion.errors import ParameterError


def param(
    default: Any,
    unit: str | None,
    description: str,
    *,
    min: float | None = None,
    max: float | None = None,
    positive: bool = False,
) -> Any:
    """A parameter field: ``min``/``max`` are inclusive bounds, ``positive`` means > 0."""
    metadata = {
        "unit": unit,
        "description": description,
        "min": min,
        "max": max,
        "positive": positive,
    }
    return dataclasses.field(default=default, metadata=metadata)


@dataclasses.dataclass(frozen=True)
class ParamInfo:
    """What a parameter field declares."""

    name: str
    type: type
    default: Any
    unit: str | None
    description: str
    min: float | None
    max: float | None
    positive: bool


def param_infos(params_class: type) -> list[ParamInfo]:
    """The declared parameters of a parameter dataclass, in declaration order."""
    infos = []
    for f in dataclasses.fields(params_class):
        if "description" not in f.metadata:
            raise TypeError(f"{params_class.__name__}.{f.name} is not declared with param()")
        infos.append(
            ParamInfo(
                name=f.name,
                type=type(f.default),
                default=f.default,
                unit=f.metadata["unit"],
                description=f.metadata["description"],
                min=f.metadata["min"],
                max=f.metadata["max"],
                positive=f.metadata["positive"],
            )
        )
    return infos


def check_params(params: Any) -> None:
    """Check types, finiteness and declared bounds of every field; raise ParameterError."""
    for info in param_infos(type(params)):
        value = getattr(params, info.name)
        if info.type is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ParameterError(info.name, value, "must be a real number")
            if not math.isfinite(value):
                raise ParameterError(info.name, value, "must be finite")
        elif info.type is int and (isinstance(value, bool) or not isinstance(value, int)):
            raise ParameterError(info.name, value, "must be an integer")
        elif info.type is bool and not isinstance(value, bool):
            raise ParameterError(info.name, value, "must be a Boolean")
        elif info.type is str and not isinstance(value, str):
            raise ParameterError(info.name, value, "must be a string")
        if info.positive and not value > 0:
            raise ParameterError(info.name, value, "must be > 0")
        if info.min is not None and value < info.min:
            raise ParameterError(info.name, value, f"must be >= {info.min}")
        if info.max is not None and value > info.max:
            raise ParameterError(info.name, value, f"must be <= {info.max}")


def coerce(params_class: type, name: str, value: Any) -> Any:
    """Convert a value given by a host (FMI, CLI, SSP) to the declared type of ``name``."""
    for info in param_infos(params_class):
        if info.name == name:
            if info.type is bool:
                if isinstance(value, str):
                    return value.strip().lower() in ("1", "true", "yes")
                return bool(value)
            if info.type is int and isinstance(value, float) and value.is_integer():
                return int(value)
            return info.type(value)
    raise KeyError(f"{params_class.__name__} has no parameter '{name}'")
