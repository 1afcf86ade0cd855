"""FMU HajiyevAdaptiveEstimator: maps FMI variables onto altfusion.estimators.hajiyev."""

from altfusion import fmi
from altfusion.estimators import hajiyev


class HajiyevAdaptiveEstimator(fmi.CoreSlave):
    """Maximum-likelihood baro/GPS fusion with the adaptive filter-gain correction of
    Hajiyev et al. (hajiyev); no vertical-speed estimate (vz_est = 0)."""

    core_class = hajiyev.HajiyevAdaptiveEstimator
    variables = fmi.estimator_variables(core_class.streams, (
        fmi.Output("adaptive_factor", "1", "Adaptive factor S(k) (eq. 30; 1 when eq. 28 fails)"),
        fmi.Output("gain", "1", "Filter gain K(k) (eqs. 16, 27)"),
        fmi.Output("residual", "m", "Residual Δ(k) = h_GPS - h_B (eq. 18)"),
        fmi.Output("normalized_residual", "1", "Normalised residual (eq. 34)"),
    ), initial_depends_on={"h_est": ("baro_h",), "status": ("baro_count",)})
