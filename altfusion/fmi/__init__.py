"""The pythonfmu edge of the core: one adapter base shared by every FMU slave script."""

from altfusion.fmi.slave import CoreSlave
from altfusion.fmi.variables import Input, Output

__all__ = ["CoreSlave", "Input", "Output"]
