"""FMU HajiyevAdaptiveEstimator: maps FMI variables onto altfusion.estimators.hajiyev."""

from altfusion.estimators import hajiyev
from altfusion.fmi import CoreSlave, Output, estimator_variables


class HajiyevAdaptiveEstimator(CoreSlave):
    """Maximum-likelihood baro/GPS fusion with the adaptive filter-gain correction of
    Hajiyev et al. (seed 002); no vertical-speed estimate (vz_est = 0)."""

    core_class = hajiyev.HajiyevAdaptiveEstimator
    variables = estimator_variables(core_class.streams, (
        Output("adaptive_factor", "1", "Adaptive factor S(k) (eq. 30; 1 when eq. 28 fails)"),
        Output("gain", "1", "Filter gain K(k) (eqs. 16, 27)"),
        Output("residual", "m", "Residual Δ(k) = h_GPS - h_B (eq. 18)"),
        Output("normalized_residual", "1", "Normalised residual (eq. 34)"),
        Output("n_rejected", None, "GPS samples rejected by the outlier gate", type=int),
        Output("n_ignored", None, "Non-finite samples ignored", type=int),
    ))
