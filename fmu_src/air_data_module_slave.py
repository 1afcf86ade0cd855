"""FMU AirDataModule: maps FMI variables onto altfusion.sensors.air_data."""

from altfusion import fmi
from altfusion.sensors import air_data

AIR = ("p_static", "T_air", "wind_speed")


class AirDataModule(fmi.CoreSlave):
    """Barometer and thermometer sampled on their own schedule: static pressure with wind
    disturbance, bias, drift, noise and quantization, and the baro-height of the launch
    calibration."""

    core_class = air_data.AirDataModule
    variables = (
        fmi.Input("p_static", "Pa", "True static pressure at the vehicle"),
        fmi.Input("T_air", "K", "True air temperature at the vehicle"),
        fmi.Input("wind_speed", "m/s", "Wind speed at the vehicle (dynamic-pressure disturbance)"),
        fmi.Output("baro_p", "Pa", "Measured static pressure (held sample)", reads_at_step_end=AIR),
        fmi.Output("baro_T", "K", "Measured air temperature (held sample)",
                   reads_at_step_end=("T_air",)),
        fmi.Output("baro_h", "m", "Baro-height from the launch calibration (held sample, MSL)",
                   reads_at_step_end=AIR),
        fmi.Output("baro_drift", "m", "Drift contained in the held sample (diagnostic truth)",
                   reads_at_step_end=()),
        fmi.Output("baro_count", None, "Number of samples delivered so far", type=int,
                   reads_at_step_end=()),
        fmi.Output("baro_time", "s", "Time at which the held sample was taken",
                   reads_at_step_end=()),
    )
