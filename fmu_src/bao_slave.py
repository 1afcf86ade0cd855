"""FMU BaoDriftEstimator: maps FMI variables onto altfusion.estimators.bao."""

from altfusion import fmi
from altfusion.estimators import bao


class BaoDriftEstimator(fmi.CoreSlave):
    """Bao et al.'s barometer error correction (bao2017): principle-error and wind
    corrections, and a drift Kalman filter whose R adapts to the GPS VDOP and satellite count;
    no vertical-speed estimate (vz_est = 0)."""

    core_class = bao.BaoDriftEstimator
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("drift", "m", "Drift error estimate ε_d, true minus baro height (eqs. 12-13)"),
        fmi.Output("drift_std", "m", "Standard deviation of the drift estimate"),
        fmi.Output("eta", "1",
                   "Factor η of eq. (14) from the last GPS sample's VDOP and satellites"),
        fmi.Output("R", "m2", "Measurement noise R_k of the last GPS update (eq. 14)"),
        fmi.Output("gps_std", "m", "GPS height standard deviation √R_k of the last GPS update"),
        fmi.Output("principle_error", "m", "Principle-error correction ε_p (eq. 5)"),
        fmi.Output("wind_error", "m", "Wind-disturbance correction ε_e (eq. 11)"),
        fmi.Output("h_baro_corrected", "m", "Baro height corrected for ε_p and ε_e",
                   initial_depends_on=("baro_h",)),
        fmi.Output("innovation", "m", "Innovation of the last fused GPS sample"),
    ), core_class.extra_inputs, initial_depends_on={"h_est": ("baro_h",)})
