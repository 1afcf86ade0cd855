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


TRUE_WORDS = ("1", "true", "yes")
FALSE_WORDS = ("0", "false", "no")
"""The texts of a Boolean parameter (any case): xs:boolean's and yes/no."""


def parse_boolean(text: str) -> bool:
    """A Boolean given as text (a command line's ``--set``): one of :data:`TRUE_WORDS` or
    :data:`FALSE_WORDS` in any case; any other text is refused (ValueError), never taken as
    false."""
    word = text.strip().lower()
    if word in TRUE_WORDS or word in FALSE_WORDS:
        return word in TRUE_WORDS
    raise ValueError(f"expected true or false (1 or 0, yes or no), not {text!r}")


def parse_integer(text: str) -> int:
    """An integer given as text: ``3``, or a number with no fraction (``3.0``, ``1e3``); a
    fraction is refused (ValueError), never cut off."""
    try:
        return int(text)
    except ValueError:
        value = float(text)
    if not value.is_integer():
        raise ValueError(f"expected an integer, not {text!r}")
    return int(value)


def coerce(params_class: type, name: str, value: Any) -> Any:
    """Convert a value given by a host (FMI, CLI, SSP) to the declared type of ``name``; a
    value that is not of that type (a fraction for an integer, a text other than
    :func:`parse_boolean`'s for a Boolean) is left as given, for :func:`check_params` to
    refuse naming the parameter."""
    for info in param_infos(params_class):
        if info.name == name:
            if info.type is bool:
                if isinstance(value, str):
                    try:
                        return parse_boolean(value)
                    except ValueError:
                        return value
                return bool(value)
            if info.type is int and isinstance(value, float):
                return int(value) if value.is_integer() else value
            return info.type(value)
    raise KeyError(f"{params_class.__name__} has no parameter '{name}'")
