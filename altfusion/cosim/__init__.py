"""The fmpy edge of the core: SSP systems and the multi-rate co-simulation runner.

The plain-data system description (:mod:`altfusion.cosim.system`) is imported at once; the
runner, the results and the SSP reader/writer (which load fmpy) are imported on first use, so
describing a system never imports fmpy.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

from altfusion.cosim.system import ComponentSpec, Connection, Metric, SystemSpec

if TYPE_CHECKING:
    from altfusion.cosim.results import Results
    from altfusion.cosim.runner import CosimError, Simulation, simulate
    from altfusion.cosim.ssp import read_ssp, write_ssp

_LAZY = {
    "Results": "altfusion.cosim.results",
    "CosimError": "altfusion.cosim.runner",
    "Simulation": "altfusion.cosim.runner",
    "simulate": "altfusion.cosim.runner",
    "read_ssp": "altfusion.cosim.ssp",
    "write_ssp": "altfusion.cosim.ssp",
}

__all__ = [
    "ComponentSpec", "Connection", "CosimError", "Metric", "Results", "Simulation", "SystemSpec",
    "read_ssp", "simulate", "write_ssp",
]


def __getattr__(name: str) -> Any:
    """The runner's exports, imported from their module when first asked for (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value
