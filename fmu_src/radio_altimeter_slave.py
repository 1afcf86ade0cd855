"""FMU RadioAltimeter: maps FMI variables onto altfusion.sensors.radio_altimeter."""

from altfusion import fmi
from altfusion.sensors import radio_altimeter

RANGE = ("h", "terrain_h")


class RadioAltimeter(fmi.CoreSlave):
    """Radio altimeter: height above the terrain with white noise, up to a maximum range."""

    core_class = radio_altimeter.RadioAltimeter
    variables = (
        fmi.Input("h", "m", "True altitude (MSL)"),
        fmi.Input("terrain_h", "m", "Terrain height under the vehicle (MSL)"),
        fmi.Output("radar_h", "m", "Measured height above the terrain (held valid sample)",
                   reads_at_step_end=RANGE),
        fmi.Output("radar_valid", None, "True while the held sample is current (within range)",
                   type=bool, reads_at_step_end=RANGE),
        fmi.Output("radar_count", None, "Number of valid samples delivered so far", type=int,
                   reads_at_step_end=RANGE),
        fmi.Output("radar_time", "s", "Time at which the held sample was taken",
                   reads_at_step_end=RANGE),
    )
