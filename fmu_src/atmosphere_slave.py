"""FMU Atmosphere: maps FMI variables onto altfusion.physics.atmosphere."""

from altfusion import fmi
from altfusion.physics import atmosphere


class Atmosphere(fmi.CoreSlave):
    """Lapse-rate atmosphere with drifting sea-level pressure, temperature and lapse rate,
    gusty wind and terrain height, evaluated at the vehicle's true altitude."""

    core_class = atmosphere.Atmosphere
    variables = (
        fmi.Input("h", "m", "True altitude of the vehicle (MSL)"),
        fmi.Output("p_static", "Pa", "True static pressure at h", reads_at_step_end=("h",),
                   initial_depends_on=("h",)),
        fmi.Output("T_air", "K", "True air temperature at h", reads_at_step_end=("h",),
                   initial_depends_on=("h",)),
        fmi.Output("rho_air", "kg/m3", "Air density at h", reads_at_step_end=("h",),
                   initial_depends_on=("h",)),
        fmi.Output("wind_speed", "m/s", "Wind speed at the vehicle", reads_at_step_end=()),
        fmi.Output("terrain_h", "m", "Terrain height under the vehicle (MSL)",
                   reads_at_step_end=()),
        fmi.Output("p0_actual", "Pa", "Current sea-level pressure", reads_at_step_end=()),
        fmi.Output("T0_actual", "K", "Current sea-level temperature", reads_at_step_end=()),
        fmi.Output("lapse_rate_actual", "K/m", "Current lapse rate dT/dh", reads_at_step_end=()),
    )
