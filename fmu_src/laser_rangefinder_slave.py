"""FMU LaserRangefinder: maps FMI variables onto altfusion.sensors.laser."""

from altfusion import fmi
from altfusion.sensors import laser

RANGE = ("h", "terrain_h")


class LaserRangefinder(fmi.CoreSlave):
    """Laser rangefinder: height above the terrain, valid from 0.1 m to 25 m, +-5 mm at
    100 Hz; reads 0 (invalid) out of range."""

    core_class = laser.LaserRangefinder
    variables = (
        fmi.Input("h", "m", "True altitude (MSL)"),
        fmi.Input("terrain_h", "m", "Terrain height under the vehicle (MSL)"),
        fmi.Output("laser_h", "m", "Measured height above the terrain, 0 when out of range "
                   "(held frame)", reads_at_step_end=RANGE),
        fmi.Output("laser_valid", None, "True if the held frame is within range", type=bool,
                   reads_at_step_end=RANGE),
        fmi.Output("laser_count", None, "Number of frames delivered so far (valid or not)",
                   type=int, reads_at_step_end=()),
        fmi.Output("laser_time", "s", "Time at which the held frame was taken",
                   reads_at_step_end=()),
    )
