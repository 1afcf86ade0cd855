"""The pythonfmu edge of the core: one adapter base shared by every FMU slave script."""

from altfusion.fmi.slave import CoreSlave
from altfusion.fmi.variables import (
    Input,
    Output,
    contract_input,
    contract_output,
    estimator_variables,
)

__all__ = [
    "CoreSlave", "Input", "Output", "contract_input", "contract_output", "estimator_variables",
]
