"""FMU WhangGAEstimator: maps FMI variables onto altfusion.estimators.whang."""

from altfusion import fmi
from altfusion.estimators import whang


class WhangGAEstimator(fmi.CoreSlave):
    """Whang & Ra's altitude estimator (whang2008): GA filter for baro scale factor and bias
    from GPS and ADM temperature, baro compensation and an alpha-beta Kalman filter."""

    core_class = whang.WhangGAEstimator
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("h_prior", "m", "A priori height estimate of the alpha-beta filter"),
        fmi.Output("h_comp", "m", "Compensated baro height h^c (eq. 32)"),
        fmi.Output("scale_factor", "1", "Estimated baro scale factor a"),
        fmi.Output("bias", "m", "Estimated baro bias b"),
        fmi.Output("scale_factor_var", "1", "Variance P^a of the scale factor"),
        fmi.Output("bias_var", "m2", "Variance P^b of the bias"),
        fmi.Output("lambda_meas", "1", "Temperature pseudo-measurement λ (eq. 6)"),
    ))
