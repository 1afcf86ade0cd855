"""FMU BaselineKF: maps FMI variables onto altfusion.estimators.baseline."""

from altfusion import fmi
from altfusion.estimators import baseline


class BaselineKF(fmi.CoreSlave):
    """The papers' "normal Kalman filter": altitude, vertical speed and baro bias with
    constant R; baro and GPS fused at their own rates."""

    core_class = baseline.BaselineKF
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("bias", "m", "Estimated baro bias b"),
        fmi.Output("innovation", "m", "Innovation of the last fused sample"),
    ))
