"""BaselineKF: the "normal Kalman filter" the papers compare against.

States x = [h, vz, b]: altitude (m), vertical speed (m/s) and barometer bias (m).

    h(k+1)  = h + vz·dt          white acceleration, PSD q_a (m²/s³)
    vz(k+1) = vz
    b(k+1)  = b                  random walk, PSD q_b (m²/s)
    baro:  z = h + b + v_B,  R_B constant
    GPS:   z = h + v_G,      R_G constant

Baro and GPS are each fused when a new sample arrives, at their own rates. The filter starts
from its first sample (GPS if it comes first, else baro with zero bias).

Deviations from the papers' "normal Kalman filter" (which none of them specifies fully):

* an innovation gate of ``gate_sigma`` standard deviations rejects outliers of either source;
* health (estimators/base.py): a source rejected for ``reset_timeout`` while the other agrees
  is isolated; with no source fused for that long the height resets onto the next sample; an
  isolated barometer with a constant offset is re-admitted with b reset onto it
  (:meth:`reset_offset`).
"""

import math
from dataclasses import dataclass

from altfusion.estimators.base import Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import (
    STATE_AND_COVARIANCE,
    diagonal,
    predict_sparse,
    quadratic_form,
    shift_state,
    sparse_dot,
    update_scalar,
)
from altfusion.estimators.streams import BARO, GPS, Stream
from altfusion.params import param

N = 3
"""States: h, vz, b."""
BIAS = 2
"""The index of the barometer bias b."""
BARO_ROW = ((0, 1.0), (BIAS, 1.0))
"""H of the barometer, h + b, as (state index, coefficient) pairs."""
GPS_ROW = ((0, 1.0),)
"""H of the GPS height."""


@dataclass(frozen=True)
class BaselineKFParams(HealthParams):
    accel_psd: float = param(0.5, "m2/s3", "PSD q_a of the white vertical acceleration",
                             positive=True)
    bias_psd: float = param(0.05, "m2/s", "PSD q_b of the baro-bias random walk", min=0.0)
    R_baro: float = param(25.0, "m2", "Baro height noise variance R_B (whang2008: 5² m²)",
                          positive=True)
    R_gps: float = param(4900.0, "m2", "GPS height noise variance R_G (whang2008: 70² m²)",
                         positive=True)
    P0_h: float = param(100.0, "m2", "Initial altitude variance at the first sample",
                        positive=True)
    P0_vz: float = param(25.0, "m2/s2", "Initial vertical-speed variance", positive=True)
    P0_b: float = param(400.0, "m2", "Initial baro-bias variance", positive=True)
    gate_sigma: float = param(5.0, "1", "Innovation gate in standard deviations (0: off)",
                              min=0.0)


class BaselineKF(Estimator):
    """Three-state Kalman filter on altitude, vertical speed and baro bias, constant R."""

    Params = BaselineKFParams
    streams = (BARO, GPS)
    state_covariances = STATE_AND_COVARIANCE
    stated_aliases = {"baro_bias_psd": "bias_psd"}

    def configure(self, clock) -> None:
        """F (as sparse rows) and Q of one step of the estimator (white acceleration on h and
        v, a random walk on the bias), built once: ``propagate`` is always called with this
        step."""
        p, dt = self.params, clock.step_size
        self._F = (((0, 1.0), (1, dt)), ((1, 1.0),), ((2, 1.0),))
        self._Q = (
            (p.accel_psd * dt**3 / 3.0, p.accel_psd * dt**2 / 2.0, 0.0),
            (p.accel_psd * dt**2 / 2.0, p.accel_psd * dt, 0.0),
            (0.0, 0.0, p.bias_psd * dt),
        )

    def initialize_filter(self) -> None:
        p = self.params
        self.x = [0.0] * N
        self.P = diagonal((p.P0_h, p.P0_vz, p.P0_b))
        self.bias = 0.0
        self.innovation = 0.0
        self._publish()

    def propagate(self, dt: float) -> None:
        if not self.started:
            return
        self.x, self.P = predict_sparse(self.x, self.P, self._F, self._Q)
        self._publish()

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        p = self.params
        if stream is BARO:
            z, H, R = sample["baro_h"], BARO_ROW, p.R_baro
        else:
            z, H, R = sample["gps_h"], GPS_ROW, p.R_gps
        if not self.started:
            self.x[0] = z - self.x[BIAS] if stream is BARO else z
            self.started = True
            self.accept(self.aid[stream.prefix])
            self._publish()
            return
        innovation = z - sparse_dot(self.x, H)
        variance = quadratic_form(self.P, H) + R
        verdict = self.gate(self.aid[stream.prefix], innovation, variance, p.gate_sigma)
        if verdict is not Verdict.FUSED:
            self._publish()
            return
        self.x, self.P, _ = update_scalar(self.x, self.P, H, innovation, R)
        self.innovation = innovation
        self._publish()

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        shift_state(self.x, self.P, 0, innovation, variance)

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """The baro bias b (an isolated baro re-admitted, estimators/base.py)."""
        if source != "baro":
            return False
        shift_state(self.x, self.P, BIAS, innovation, variance)
        return True

    def _publish(self) -> None:
        self.h_est, self.vz_est, self.bias = self.x
        self.h_std = math.sqrt(self.P[0][0])
