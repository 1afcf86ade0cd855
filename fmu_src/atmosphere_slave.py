"""FMU Atmosphere: maps FMI variables onto altfusion.physics.atmosphere."""

from altfusion.fmi import CoreSlave, Input, Output
from altfusion.physics import atmosphere


class Atmosphere(CoreSlave):
    """Lapse-rate atmosphere with drifting sea-level pressure, temperature and lapse rate,
    gusty wind and terrain height, evaluated at the vehicle's true altitude."""

    core_class = atmosphere.Atmosphere
    variables = (
        Input("h", "m", "True altitude of the vehicle (MSL)"),
        Output("p_static", "Pa", "True static pressure at h", depends_on=("h",)),
        Output("T_air", "K", "True air temperature at h", depends_on=("h",)),
        Output("rho_air", "kg/m3", "Air density at h", depends_on=("h",)),
        Output("wind_speed", "m/s", "Wind speed at the vehicle", depends_on=()),
        Output("terrain_h", "m", "Terrain height under the vehicle (MSL)", depends_on=()),
        Output("p0_actual", "Pa", "Current sea-level pressure", depends_on=()),
        Output("T0_actual", "K", "Current sea-level temperature", depends_on=()),
        Output("lapse_rate_actual", "K/m", "Current lapse rate dT/dh", depends_on=()),
    )
