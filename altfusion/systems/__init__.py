"""Systems as plain data: :class:`~altfusion.systems.spec.SystemSpec` (components,
connections, timing, recording) and the catalog of every system the build writes to
``models/<name>.ssp`` (the paper systems, the fault suite's flight, the replay systems). The
runner and the SSP reader/writer (:mod:`altfusion.cosim`) read them; importing them loads no
FMI library."""

from altfusion.systems.catalog import DEFAULT_SYSTEM, SYSTEMS, build_system

__all__ = ["DEFAULT_SYSTEM", "SYSTEMS", "build_system"]
