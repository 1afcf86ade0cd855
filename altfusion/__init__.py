"""altfusion: barometer/GPS altitude estimation components for co-simulation.

The core (physics, sensors, estimators) is plain Python + numpy. FMI lives at two edges:
``altfusion.fmi`` (the pythonfmu adapter base) and ``altfusion.cosim`` (the fmpy runner).
"""

from altfusion.version import CORE_VERSION, __version__

__all__ = ["CORE_VERSION", "__version__"]
