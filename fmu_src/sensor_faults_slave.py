"""FMU SensorFaults: maps FMI variables onto altfusion.sensors.faults."""

from altfusion import fmi
from altfusion.sensors import faults
from altfusion.signals import SIGNALS


def _raw_input(name: str) -> fmi.Input:
    kind, unit, meaning = SIGNALS[name]
    return fmi.Input(f"raw_{name}", unit, f"From the sensor: {meaning}", type=kind)


def _stream_variables(prefix: str) -> tuple:
    """The raw inputs of stream ``prefix`` and the outputs they drive (read at the end of the
    step from the stream's own inputs, and in Initialization Mode each from its raw input; the
    truth inputs enter with one step's delay)."""
    signals = faults.stream_signals(prefix)
    own = tuple(f"raw_{name}" for name in signals)
    return (*(_raw_input(name) for name in signals),
            *(fmi.contract_output(name, reads_at_step_end=own,
                                  initial_depends_on=(f"raw_{name}",)) for name in signals))


class SensorFaults(fmi.CoreSlave):
    """The sensor streams passed through with one named fault scenario of the fault suite
    applied (docs/faults.md): failed, drifting, stopping, wild or mis-stamped sensors."""

    core_class = faults.SensorFaults
    variables = (
        *(variable for prefix in faults.STREAMS for variable in _stream_variables(prefix)),
        fmi.Input("h", "m", "True altitude (MSL): ground effect"),
        fmi.Input("thrust", "N", "Thrust: prop wash"),
        fmi.Output("fault_active", None, "True from the scenario's fault_start on (scenario "
                   "not 'none')", type=bool, reads_at_step_end=()),
    )
