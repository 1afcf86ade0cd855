"""HajiyevAdaptiveEstimator: maximum-likelihood baro/GPS fusion with adaptive gain (seed 002).

Maximum-likelihood fusion of simultaneous baro and GPS altitudes (eqs. 11-19):

    ĥ(k) = h^B(k) + K(k) Δ(k),   Δ(k) = h^GPS(k) - h^B(k)              (15), (18)
    K(k) = R_B / (R_B + R_GPS),   P(k) = R_GPS K(k)                     (16), (17)

Adaptive filter-gain correction (eqs. 26-31): when the residual exceeds its theoretical
variance, Δ² ≥ R_GPS + R_B (condition 28), the baro noise is scaled by the adaptive factor

    S(k) = (Δ² - R_GPS) / R_B                                           (30)
    K(k) = S R_B / (S R_B + R_GPS),   P(k) = R_GPS K(k)                  (27), (31)

and S = 1 otherwise (seeds NOTES.md). This is the shared Kalman update of a prior h^B with
variance S·R_B by the measurement h^GPS with variance R_GPS. With ``adaptive`` false the
estimator is the paper's non-adaptive filter (S ≡ 1).

Multi-rate: the fusion runs when a new GPS sample arrives, with the latest baro sample;
between GPS samples the estimate follows each new baro sample with the last correction K·Δ
held. The algorithm estimates no vertical speed: ``vz_est`` is always 0.

Deviations from the paper:

* between GPS samples the variance grows by ``drift_psd`` per second, so that ``h_std`` stays
  honest through GPS outages;
* GPS gate: a sample whose residual jumps by more than ``gate_sigma`` standard deviations from
  the last accepted residual is rejected and logged (outliers are jumps, while the drift the
  adaptation follows is gradual; a gate on the residual itself would reject that drift);
* baro gate: a baro sample that jumps from the last accepted one by more than ``gate_sigma``
  standard deviations of the jump (2 R_B and ``max_vz``) is rejected;
* GPS samples that arrive before the first baro sample are not fused (eq. 18 needs h_B; in a
  replayed log GPS may come first);
* health (estimators/base.py): a baro that stays off for ``reset_timeout`` while the GPS
  agrees is isolated; with no source fused for that long the estimate resets.
"""

from dataclasses import dataclass

import numpy as np

from altfusion.estimators.base import BARO, GPS, Estimator, HealthParams, Stream
from altfusion.estimators.kalman import update
from altfusion.params import param

H = np.array([[1.0]])


@dataclass(frozen=True)
class HajiyevParams(HealthParams):
    R_baro: float = param(81.0, "m2", "Baro altitude noise variance R_B (seed 002: 9² m²)",
                          positive=True)
    R_gps: float = param(169.0, "m2", "GPS altitude noise variance R_GPS (seed 002: 13² m²)",
                         positive=True)
    adaptive: bool = param(True, None, "Adaptive gain correction (eqs. 26-31); false: eqs. 15-19")
    gate_sigma: float = param(
        4.0, "1", "Outlier gate on the jump of the residual since the last accepted one, in "
        "standard deviations of that jump, sqrt(2 (R_B + R_GPS)), and on the jump of the baro "
        "height since its last accepted sample (2 R_B and max_vz); 0: off. Not in the paper: "
        "a gate on the residual itself would reject the drift the adaptation must follow",
        min=0.0)
    drift_psd: float = param(
        1.0, "m2/s", "Growth rate of the estimate's variance while no GPS sample arrives "
        "(the baro error the held correction no longer tracks); not in the paper", min=0.0)


class HajiyevAdaptiveEstimator(Estimator):
    """Baro/GPS maximum-likelihood fusion with the adaptive factor S(k) of seed 002."""

    Params = HajiyevParams
    streams = (BARO, GPS)

    def initialize_filter(self) -> None:
        self.baro = float(self.baro_h)
        self._baro_time = float(self.baro_time)
        self.started = self.has_sample("baro")
        self.adaptive_factor = 1.0
        self.gain = 0.0
        self.residual = 0.0
        self.normalized_residual = 0.0
        self.correction = 0.0
        self.variance = self.params.R_baro
        self._accepted_residual: float | None = None
        self._publish()

    def propagate(self, dt: float) -> None:
        """The fusion is static (eqs. 11-19); only the held correction ages."""
        self.variance += self.params.drift_psd * dt
        self._publish()

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        p = self.params
        if stream is BARO:
            self._baro_sample(sample["baro_h"], sample["baro_time"])
            return
        if not self.has_sample("baro"):
            self.note("gps: sample before the first baro sample not fused (no h_B for eq. 18)")
            return
        residual = sample["gps_h"] - self.baro                                  # (18)
        if self._accepted_residual is not None:
            jump, jump_variance = residual - self._accepted_residual, 2 * (p.R_baro + p.R_gps)
            if not self.gate("gps", jump, jump_variance, p.gate_sigma):
                return
        self._accepted_residual = residual
        factor = 1.0
        if p.adaptive and residual**2 >= p.R_gps + p.R_baro:                     # (28)
            factor = (residual**2 - p.R_gps) / p.R_baro                         # (30)
        result = update(np.array([self.baro]), np.array([[factor * p.R_baro]]),
                        sample["gps_h"], H, p.R_gps)                            # (27), (31)
        self.adaptive_factor = factor
        self.gain = float(result.K[0, 0])
        self.residual = residual
        self.normalized_residual = residual / np.sqrt(p.R_baro + p.R_gps)       # (34)
        self.correction = float(result.x[0]) - self.baro
        self.variance = float(result.P[0, 0])
        self._publish()

    def _baro_sample(self, h_baro: float, stamp: float) -> None:
        """h_B of eq. (18): the first baro sample starts the estimator; a later one whose jump
        from the last accepted exceeds the gate is rejected (an addition to the paper)."""
        p = self.params
        if not self.started:
            self.started = True
            self.accept("baro")
        else:
            elapsed, self._baro_time = stamp - self._baro_time, stamp
            if not self.gate("baro", h_baro - self.baro, self.jump_variance(p.R_baro, elapsed),
                             p.gate_sigma):
                return
        self._baro_time = stamp
        self.baro = h_baro
        self._publish()

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A baro reset takes the new baro level; a GPS reset drops the residual the jump
        gate compares with, so that the next GPS sample is fused whatever its residual."""
        if source == "baro":
            self.baro += innovation
        self._accepted_residual = None
        self._publish()

    def _publish(self) -> None:
        self.h_est = self.baro + self.correction
        self.vz_est = 0.0
        self.h_std = float(np.sqrt(self.variance))
