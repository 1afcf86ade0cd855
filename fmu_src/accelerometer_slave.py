"""FMU Accelerometer: maps FMI variables onto altfusion.sensors.accelerometer."""

from altfusion import fmi
from altfusion.sensors import accelerometer


class Accelerometer(fmi.CoreSlave):
    """Vertical accelerometer: specific force with bias and noise, gravity removed."""

    core_class = accelerometer.Accelerometer
    variables = (
        fmi.Input("az", "m/s2", "True vertical acceleration, positive up"),
        fmi.Output("acc_z", "m/s2", "Measured vertical acceleration, gravity removed (held sample)",
                   reads_at_step_end=("az",)),
        fmi.Output("acc_count", None, "Number of samples delivered so far", type=int,
                   reads_at_step_end=()),
        fmi.Output("acc_time", "s", "Time at which the held sample was taken",
                   reads_at_step_end=()),
    )
