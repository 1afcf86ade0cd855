"""FMU XuSHAEKF: maps FMI variables onto altfusion.estimators.xu."""

from altfusion import fmi
from altfusion.estimators import xu


class XuSHAEKF(fmi.CoreSlave):
    """Xu et al.'s improved Sage-Husa adaptive Kalman filter (xu2016): accelerometer-driven
    height with the laser below 25 m and the baro above, GPS, adaptive measurement noise,
    innovation-based sensor weights and strong tracking."""

    core_class = xu.XuSHAEKF
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("height_source", None, "Active height source (eq. 14): 0 = baro, 1 = laser",
               type=int),
        fmi.Output("weight_gps", "1", "Weight α of GPS (eq. 18)"),
        fmi.Output("weight_baro", "1", "Weight α of the baro (eq. 18)"),
        fmi.Output("weight_laser", "1", "Weight α of the laser (eq. 18)"),
        fmi.Output("R_gps_est", "m2", "Estimated GPS noise variance R̂ (eq. 22)"),
        fmi.Output("R_baro_est", "m2", "Estimated baro noise variance R̂ (eq. 22)"),
        fmi.Output("R_laser_est", "m2", "Estimated laser noise variance R̂ (eq. 22)"),
        fmi.Output("baro_bias", "m", "Baro constant error ε_b (eqs. 4, 14)"),
        fmi.Output("acc_bias", "m/s2", "Accelerometer bias estimate"),
        fmi.Output("acc_noise_est", "m/s2", "Accelerometer noise σ̂_a behind Q̂"),
        fmi.Output("strong_tracking_factor", "1", "Fading factor λ of the last strong-tracking "
                                               "step (eq. 24)"),
        fmi.Output("n_strong_tracking", None, "Strong-tracking steps taken (eq. 23 failed)",
               type=int),
    ))
