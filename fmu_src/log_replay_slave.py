"""FMU LogReplay: maps FMI variables onto altfusion.replay.component."""

from altfusion import fmi
from altfusion.replay import component

SOURCES = {
    "baro_h": "PX4's barometric altitude baro_alt_meter: MSL by PX4's standard-atmosphere "
              "conversion with its QNH, not launch-calibrated",
    "baro_T": "Barometer temperature baro_temp_celcius (the sensor's own, not the air's)",
    "acc_z": "Vertical acceleration from sensor_combined, rotated with the logged attitude, "
             "gravity removed, positive up",
    "laser_h": "Downward rangefinder (laser, ultrasound, infrared) range x cos(tilt): height "
               "above the ground; 0 when invalid",
    "radar_h": "Downward radar rangefinder range x cos(tilt): height above the ground",
    "ekf_h": "PX4 EKF2 altitude ref_alt - z from vehicle_local_position (MSL)",
    "ekf_vz": "PX4 EKF2 vertical speed -vz from vehicle_local_position, positive up",
}


class LogReplay(fmi.CoreSlave):
    """Replays a PX4 flight log (ULog): air data, GNSS, vertical acceleration, downward
    rangefinder and PX4 EKF2's height, each stream at its recorded time stamps with its own
    count and time stamp. The two test logs are bundled under resources/flightlogs/."""

    core_class = component.LogReplay
    bundled_files = ("tests/data/flightlogs",)
    variables = tuple(fmi.contract_output(name, reads_at_step_end=(), description=SOURCES.get(name))
                      for name in component.LOG_OUTPUTS)
