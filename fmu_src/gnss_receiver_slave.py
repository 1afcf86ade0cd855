"""FMU GnssReceiver: maps FMI variables onto altfusion.sensors.gnss."""

from altfusion import fmi
from altfusion.sensors import gnss


class GnssReceiver(fmi.CoreSlave):
    """GNSS height and vertical velocity with VDOP-scaled noise, an optional Gauss-Markov
    error, satellite geometry (constant, scheduled or random) and outages."""

    core_class = gnss.GnssReceiver
    variables = (
        fmi.Input("h", "m", "True altitude (MSL)"),
        fmi.Input("vz", "m/s", "True vertical speed, positive up"),
        fmi.Output("gps_h", "m", "Measured height (held sample, MSL)", reads_at_step_end=("h",)),
        fmi.Output("gps_vz", "m/s", "Measured vertical speed (held sample)",
                   reads_at_step_end=("vz",)),
        fmi.Output("gps_vdop", "1", "Vertical dilution of precision of the held fix",
                   reads_at_step_end=()),
        fmi.Output("gps_nsat", None, "Satellites used in the held fix", type=int,
                   reads_at_step_end=()),
        fmi.Output("gps_fix", None, "True while the receiver has a fix", type=bool,
                   reads_at_step_end=()),
        fmi.Output("gps_count", None, "Number of fixes delivered so far", type=int,
                   reads_at_step_end=()),
        fmi.Output("gps_time", "s", "Time at which the held fix was taken", reads_at_step_end=()),
    )
