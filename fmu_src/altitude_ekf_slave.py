"""FMU AltitudeEKF: maps FMI variables onto altfusion.estimators.altitude_ekf."""

from altfusion import fmi
from altfusion.estimators import altitude_ekf


class AltitudeEKF(fmi.CoreSlave):
    """One Kalman filter on height, vertical speed, accelerometer bias, baro offset and scale
    factor, terrain height and GNSS offset, fusing any subset of baro, GNSS (height, vertical speed,
    VDOP, satellites), accelerometer, radio altimeter and laser, each sample at its own time
    stamp, after PX4 EKF2's height fusion."""

    core_class = altitude_ekf.AltitudeEKF
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("vz_std", "m/s", "1σ of vz_est"),
        fmi.Output("acc_bias", "m/s2", "Accelerometer-bias estimate b_a"),
        fmi.Output("baro_bias", "m", "Baro offset d: baro_h = h + d + k·(h - h_c) (0 with "
                                     "height_ref baro)"),
        fmi.Output("gps_bias", "m", "GNSS offset g: gps_h = h + g (0 with height_ref gps)"),
        fmi.Output("baro_scale", "1", "Baro scale factor k: baro error k·(h - h_c)"),
        fmi.Output("terrain_est", "m", "Terrain-height estimate under the rangefinders"),
        fmi.Output("terrain_std", "m", "1σ of terrain_est"),
        fmi.Output("n_terrain_resets", "1", "Terrain resets after a range inconsistency",
                   type=int),
    ))
