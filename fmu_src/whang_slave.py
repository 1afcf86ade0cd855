"""FMU WhangGAEstimator: maps FMI variables onto altfusion.estimators.whang."""

from altfusion.estimators import whang
from altfusion.fmi import CoreSlave, Output, estimator_variables


class WhangGAEstimator(CoreSlave):
    """Whang & Ra's altitude estimator (seed 000): GA filter for baro scale factor and bias
    from GPS and ADM temperature, baro compensation and an alpha-beta Kalman filter."""

    core_class = whang.WhangGAEstimator
    variables = estimator_variables(core_class.streams, (
        Output("h_prior", "m", "A priori height estimate of the alpha-beta filter"),
        Output("h_comp", "m", "Compensated baro height h^c (eq. 32)"),
        Output("scale_factor", "1", "Estimated baro scale factor a"),
        Output("bias", "m", "Estimated baro bias b"),
        Output("scale_factor_var", "1", "Variance P^a of the scale factor"),
        Output("bias_var", "m2", "Variance P^b of the bias"),
        Output("lambda_meas", "1", "Temperature pseudo-measurement λ (eq. 6)"),
        Output("n_rejected", None, "GPS samples rejected by the innovation gate", type=int),
        Output("n_ignored", None, "Non-finite samples ignored", type=int),
    ))
