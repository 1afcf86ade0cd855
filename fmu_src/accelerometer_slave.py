"""FMU Accelerometer: maps FMI variables onto altfusion.sensors.accelerometer."""

from altfusion.fmi import CoreSlave, Input, Output
from altfusion.sensors import accelerometer


class Accelerometer(CoreSlave):
    """Vertical accelerometer: specific force with bias and noise, gravity removed."""

    core_class = accelerometer.Accelerometer
    variables = (
        Input("az", "m/s2", "True vertical acceleration, positive up"),
        Output("acc_z", "m/s2", "Measured vertical acceleration, gravity removed (held sample)",
               depends_on=("az",)),
        Output("acc_count", None, "Number of samples delivered so far", type=int,
               depends_on=()),
        Output("acc_time", "s", "Time at which the held sample was taken", depends_on=()),
    )
