"""FMU YangFusionKF: maps FMI variables onto altfusion.estimators.yang."""

from altfusion import fmi
from altfusion.estimators import yang


class YangFusionKF(fmi.CoreSlave):
    """Yang et al.'s altitude measurement (yang2020): time-unified, optimally weighted GPS,
    baro and radio-altimeter heights, then a Kalman filter on height, vertical speed and
    acceleration with the GPS vertical speed and the IMU acceleration."""

    core_class = yang.YangFusionKF
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("h_fused", "m", "Weighted-fusion height y of the last fusion (eq. 7)"),
        fmi.Output("fused_std", "m", "Its standard deviation σ_Y = (Σ 1/σ_i²)^(-1/2)"),
        fmi.Output("az_est", "m/s2", "Vertical-acceleration estimate"),
        fmi.Output("acc_bias", "m/s2", "Accelerometer-bias estimate (0 without "
                                       "fault_detection: the paper's filter has none)"),
        fmi.Output("baro_bias", "m", "Baro-offset estimate d (0 without fault_detection)"),
        fmi.Output("gps_bias", "m", "GPS height-offset estimate (0 unless gps_bias_psd > 0, "
                                    "with fault_detection)"),
        fmi.Output("weight_gps", "1", "Weight ω of GPS in the last fusion (0: not live)"),
        fmi.Output("weight_baro", "1", "Weight ω of the baro in the last fusion"),
        fmi.Output("weight_radar", "1", "Weight ω of the radio altimeter in the last fusion"),
    ))
