"""The fmpy edge of the core: the multi-rate co-simulation runner, its results, and the SSP
reader/writer of the plain-data systems of :mod:`altfusion.systems`.

Importing this package loads fmpy; describing a system (:mod:`altfusion.systems.spec`, the
catalog) does not.
"""

from altfusion.cosim.results import Results
from altfusion.cosim.runner import CosimError, Simulation, simulate
from altfusion.cosim.ssp import read_ssp, write_ssp

__all__ = ["CosimError", "Results", "Simulation", "read_ssp", "simulate", "write_ssp"]
