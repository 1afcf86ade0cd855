"""The fmpy edge of the core: SSP systems and the multi-rate co-simulation runner."""

from altfusion.cosim.results import Results
from altfusion.cosim.runner import CosimError, Simulation, simulate
from altfusion.cosim.ssp import read_ssp, write_ssp
from altfusion.cosim.system import ComponentSpec, Connection, Metric, SystemSpec

__all__ = [
    "ComponentSpec", "Connection", "CosimError", "Metric", "Results", "Simulation", "SystemSpec",
    "read_ssp", "simulate", "write_ssp",
]
