"""The GUID of an FMU: a digest of its whole interface.

Tools cache FMUs by GUID, so the GUID changes whenever the interface could: it is a UUID
(version 5) of the canonical JSON of every model variable (value reference, name, FMI type,
causality, variability, unit, bounds, start value, description), the SHA-256 of the slave
script that declares them and the core version (whose digest covers the core's sources,
among them the ``Params`` dataclasses that define the parameters). Rebuilding unchanged
sources gives the same GUID; swapping two outputs' value references gives another.
"""

import hashlib
import json
import uuid
from collections.abc import Iterable
from pathlib import Path
from typing import Any

GUID_NAMESPACE = uuid.uuid5(uuid.NAMESPACE_URL, "https://altfusion/fmu-interface")


def _source_digest(script: Path | None) -> str:
    """SHA-256 of the slave script's file ('' for a class defined without one)."""
    return hashlib.sha256(script.read_bytes()).hexdigest() if script else ""


def _variable_row(var: Any, units: dict[str, tuple[str | None, Any, Any]]) -> list[Any]:
    start = var.getter() if var.getter is not None else None
    unit, low, high = units.get(var.name, (None, None, None))
    return [var.value_reference, var.name, type(var).__name__, var.causality.name,
            var.variability.name, unit, repr(low), repr(high), repr(start), var.description]


def interface_guid(model_name: str, variables: Iterable[Any],
                   units: dict[str, tuple[str | None, Any, Any]],
                   slave_script: Path | None, core_version: str) -> str:
    """The GUID of the FMU ``model_name`` with these pythonfmu ``variables`` (their declared
    ``units`` and bounds by name), declared by ``slave_script``, on ``core_version``."""
    interface = {
        "model": model_name,
        "variables": [_variable_row(v, units) for v in variables],
        "slave_script_sha256": _source_digest(slave_script),
        "core_version": core_version,
    }
    canonical = json.dumps(interface, sort_keys=True, separators=(",", ":"))
    return str(uuid.uuid5(GUID_NAMESPACE, canonical))
