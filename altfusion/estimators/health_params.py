"""The parameters every estimator shares: health, sample timing and the fault layer's
switches (:class:`HealthParams`)."""

from dataclasses import dataclass

from altfusion.params import param

PX4_HEIGHT_BIAS_PSD = 0.0169
"""The random walk of a height source's offset, m²/s: PX4 EKF2's height-bias estimators'
process noise (``baro_bias_nsd``, ``gps_hgt_bias_nsd``: 0.13 m/s/√Hz, ``common.h``), squared;
the default of every estimator's offset walk that follows PX4."""


@dataclass(frozen=True)
class HealthParams:
    """The parameters every estimator shares (health and sample timing); each estimator's
    parameters extend these."""

    aiding_timeout: float = param(5.0, "s", "h_valid turns false when no height sample was "
                                            "fused, or a required source (XuSHAEKF's acc) gave "
                                            "none, for this long (PX4 EKF2: 5 s)", positive=True)
    fault_detection: bool = param(True, None, "Height reset when every height source "
                                              "disagrees and the isolation flags; false: the "
                                              "paper's algorithm")
    reset_timeout: float = param(2.5, "s", "A height source rejected this long while no "
                                           "source is fused resets the height; rejected this "
                                           "long while another is fused, it is isolated",
                                 positive=True)
    max_vz: float = param(50.0, "m/s", "Largest plausible vertical speed: bounds the jump of a "
                                       "height between two samples where the estimator has "
                                       "no speed state to predict it", positive=True)
    max_sample_lead: float = param(1.0, "s", "A sample stamped at most this far ahead of the "
                                             "estimator's clock is held until due; further: "
                                             "refused (counted in <prefix>_rejected)", min=0.0)
    max_sample_delay: float = param(3.0, "s", "A sample stamped more than this behind the "
                                              "estimator's clock is stale: refused (counted in "
                                              "<prefix>_rejected)", positive=True)
    stuck_samples: int = param(10, None, "A reading repeated bit for bit this many times in a "
                                         "row (a frozen sensor, an unconnected input) is not "
                                         "fused until it changes, with fault_detection (0: "
                                         "off, for noise-free simulated sensors, which repeat "
                                         "themselves at rest)", min=0)
