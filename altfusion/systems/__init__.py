"""Python descriptions of every system the build writes to ``models/<name>.ssp``."""

from altfusion.systems.catalog import DEFAULT_SYSTEM, SYSTEMS, build_system

__all__ = ["DEFAULT_SYSTEM", "SYSTEMS", "build_system"]
