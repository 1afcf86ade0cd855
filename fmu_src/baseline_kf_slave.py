"""FMU BaselineKF: maps FMI variables onto altfusion.estimators.baseline."""

from altfusion.estimators import baseline
from altfusion.fmi import CoreSlave, Output, estimator_variables


class BaselineKF(CoreSlave):
    """The papers' "normal Kalman filter": altitude, vertical speed and baro bias with
    constant R; baro and GPS fused at their own rates."""

    core_class = baseline.BaselineKF
    variables = estimator_variables(core_class.streams, (
        Output("bias", "m", "Estimated baro bias b"),
        Output("innovation", "m", "Innovation of the last fused sample"),
        Output("n_rejected", None, "Samples rejected by the innovation gate", type=int),
        Output("n_ignored", None, "Non-finite samples ignored", type=int),
    ))
