"""WhangGAEstimator: baro-error estimation by a Gaussian-approximation filter (whang2008).

Fig. 1 of the paper, block by block:

* baro-height computation: done by the air-data sensor (eq. 1), input ``baro_h``;
* baro-error estimation, a GA filter on the scale factor a and bias b (eqs. 11-31):
  - system propagation, random walks (eqs. 11-12, 17-18), Q_a and Q_b per air-data step;
  - λ-update at the air-data rate with the temperature pseudo-measurement (eqs. 6-7, 19-22),
    λ = s·(T_ADM - Γ̂ (ĥ_{k|k-1} - H0) - T0)/T0, Var = (Var T + Γ̂² Var ĥ + (ĥ - H0)² Var Γ)/T0²
    (T0² as corrected in docs/papers.md);
  - z-update at the GPS rate with z = h^B - h^GPS (eqs. 23-31), using h^GPS - H0 where the
    paper, taking H0 ≈ 0, writes h^GPS;
* baro-error compensation: h^c = H0 + (h^B - H0 - b̂)/(1 + â) (eq. 32) filtered by the
  alpha-beta Kalman filter of eqs. (33)-(34) with R_h = ((h^c - H0)² P^a + P^b + R^B)/(1 + â)².

Rates: the alpha-beta filter and the random walks propagate at the estimator's own step (their
noises, given per air-data step Δt^B, are scaled by dt/Δt^B); with the estimator stepped at
Δt^B this is exactly the paper's filter.

With ``fault_detection`` false this is the estimator, in the methods that carry the paper's
equation numbers: :meth:`WhangGAEstimator._time_update` (eqs. 17-18, 33),
:meth:`WhangGAEstimator._measurement_update` with ``_lambda_update`` (eqs. 6-7, 19-22),
``_gps_update`` and ``_z_update`` (eqs. 23-31), ``_compensate``, ``_compensated`` and
``_alpha_beta_update`` (eqs. 32-34); none of them tests ``fault_detection``: only
:meth:`WhangGAEstimator.propagate` (time update) and :meth:`WhangGAEstimator.fuse_samples`
(measurement updates, then ``_publish``) do, each once per step, choosing the paper's method
or the fault layer's around it. The deviations below are in the paper's methods.

Deviations from the paper:

* Sign of λ (docs/papers.md): a warmer day than the calibration makes the barometer read low,
  h^B - H0 ≈ (1 - ΔT/T0)(h - H0), so a ≈ -ΔT/T0, opposite to eq. (3). ``paper_lambda_sign``
  false (default) takes the physical sign s = -1; true restores eq. (6), s = +1.
* GPS gate: a z-update whose innovation exceeds ``gate_sigma`` standard deviations
  √(P^b + R + (h^GPS - H0)² P^a) is rejected.
* ``MIN_LEVER``: below 1 m of h^GPS - H0 the scale-factor update of eqs. (23)-(26) is skipped
  (z_a = (z - b̂)/(h^GPS - H0) would divide by a vanishing lever); the bias update runs.
* GPS samples that arrive before the first air-data sample are not fused (z needs h^B; in a
  replayed log GPS may come first).
* Health (estimators/base.py): the GPS calibrates the baro and does not aid the height,
  except while the baro is rejected (the fault layer's baro gate below).

The fault layer (``fault_detection`` true; the estimate is the paper's without it), not in
the paper, composed around the paper's methods: :meth:`WhangGAEstimator._time_update_with_error`
and :meth:`WhangGAEstimator._measurement_update_with_baro_gate` with ``_gate_baro``,
``_gps_height_update``, ``_compensate_with_error``, ``_error_update``, ``_interval``,
``_samples_per_calibration``, ``reset_height`` and ``reset_offset`` (section ``fault layer``
of the class); ``docs/estimators.md`` gives the cases behind it:

* baro gate: the compensated height h^c (eq. 32, with the calibration â, b̂ before this
  step's z-update) against the alpha-beta prediction ĥ_{k|k-1} of eq. (33),
  S = P^h_{k|k-1} + R_h (R_h of eq. 34, P^h that of ``h_std`` below), at ``gate_sigma``. The
  filter's error variance starts at the first sample's R_h, which holds the calibration's
  prior P^b_00. While the baro is rejected, z = h^B - h^GPS (eq. 23) has no valid h^B: the
  GPS height is fused into the alpha-beta filter instead (eq. 34 with R^GPS), so the GPS aids
  the height and the shared isolation (:mod:`~altfusion.estimators.fault_detection`) can
  isolate the baro; an isolated baro whose innovations keep one sign is re-admitted with b̂
  moved onto it (``reset_offset``: b̂ += (1 + â)·(h^c - ĥ_{k|k-1})), a height reset moves ĥ;
* ``h_std``: eq. (34) fuses R_h = R^B' + C as white noise, C = ((h^c - H0)² P^a + P^b)/(1 + â)²
  the variance of the calibration â, b̂; but â and b̂ change at GPS samples only, so the N
  air-data samples between two GPS samples (N = GPS interval / air-data interval, from the
  time stamps) share one calibration error, which the filter would average down as if
  independent. ``h_std`` is the error covariance of the filter's own gain K under the
  equivalent white noise of that shared error, R^B' + N·C
  (``kalman.joseph_first_of_two``), from the first sample's R_h.
"""

import math
from dataclasses import dataclass

from altfusion.constants import ISA_LAPSE_RATE, ISA_T0
from altfusion.estimators.base import Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import (
    decorrelate,
    diagonal,
    joseph_first_of_two,
    predict_sparse,
    shift_state,
    update_first_of_two,
    update_one_state,
)
from altfusion.estimators.streams import BARO_T, GPS
from altfusion.params import param

MIN_LEVER = 1.0
"""Below this height above H0 (m) the GPS carries no scale-factor information (eq. 23): a
deviation from the paper (module documentation)."""


@dataclass(frozen=True)
class WhangParams(HealthParams):
    H0: float = param(0.0, "m", "Launch height of the baro calibration")
    T0: float = param(ISA_T0, "K", "Launch temperature of the baro calibration")
    lapse_rate: float = param(ISA_LAPSE_RATE, "K/m", "Nominal lapse rate Γ̂")
    lapse_rate_var: float = param(0.003**2, "K2/m2", "Var{Γ̂} (whang2008: (0.003 K/m)²)",
                                  min=0.0)
    R_temperature: float = param(1.5**2, "K2", "Var{T_ADM} (whang2008: 1.5² K²)", min=0.0)
    R_baro: float = param(5.0**2, "m2", "R^B, baro-height noise variance (whang2008: 5² m²)",
                          positive=True)
    R_gps: float = param(70.0**2, "m2", "R^GPS (whang2008: 70² m²)", positive=True)
    Q_a: float = param(2e-5, "1", "Scale-factor random-walk variance per air-data step",
                       min=0.0)
    Q_b: float = param(400.0, "m2", "Bias random-walk variance per air-data step", min=0.0)
    P0_a: float = param(0.2**2, "1", "Initial scale-factor variance P^a_00", positive=True)
    P0_b: float = param(20.0**2, "m2", "Initial bias variance P^b_00", positive=True)
    Q_h: float = param(39.69, "m2/s2", "Alpha-beta process noise Q^h per air-data step",
                       min=0.0)
    P0_h: float = param(100.0, "m2", "Alpha-beta initial height variance", positive=True)
    P0_vz: float = param(144.0, "m2/s2", "Alpha-beta initial rate variance", positive=True)
    tau: float = param(100.0, "s", "Time constant τ of the rate state", positive=True)
    adm_period: float = param(0.2, "s", "Air-data period Δt^B the noises are given for",
                              positive=True)
    paper_lambda_sign: bool = param(False, None, "λ with the sign of eq. (6) instead of "
                                                 "the physical sign (see docs/papers.md)")
    gate_sigma: float = param(5.0, "1", "Innovation gate on GPS (z-update) and, with "
                                        "fault_detection, on the baro, in standard "
                                        "deviations (0: off); not in the paper", min=0.0)


class WhangGAEstimator(Estimator):
    """Whang & Ra's GA baro-error estimation and compensation filter (whang2008, Fig. 1)."""

    Params = WhangParams
    streams = (BARO_T, GPS)
    state_covariances = {"x": ("P", "P_error")}
    """The state vector and its covariances, the filter's and its actual error's (a restored
    FMU state must keep them one size: :mod:`altfusion.fmi.state`)."""

    def configure(self, clock) -> None:
        """F and Q of eq. (33) for one step of the estimator, built once: ``propagate`` is
        always called with this step."""
        p, dt = self.params, clock.step_size
        self._F = (((0, 1.0), (1, dt)), ((1, 1.0 - dt / p.tau),))                # (33)
        self._Q = ((0.0, 0.0), (0.0, p.Q_h * (dt / p.adm_period)))

    def initialize_filter(self) -> None:
        """The paper's initial state, then the fault layer's (its error covariance and its
        record of sample intervals and of the baro's verdict)."""
        p = self.params
        self.a, self.P_a = 0.0, p.P0_a
        self.b, self.P_b = 0.0, p.P0_b
        self.x = [p.H0, 0.0]
        self.P = diagonal((p.P0_h, p.P0_vz))
        self.P_error = self.P
        self._stamps: dict[str, float] = {}
        self._intervals: dict[str, float] = {}
        self.h_prior = p.H0
        self.h_comp = p.H0
        self.lambda_meas = 0.0
        self.baro = float(self.baro_h)
        self._baro_rejected = False
        self._publish(self.P)

    # -------------------------------------------------------------- dispatch
    def propagate(self, dt: float) -> None:
        """The paper's time update, or the fault layer's around it."""
        if self.params.fault_detection:
            self._time_update_with_error(dt)
        else:
            self._time_update(dt)

    def fuse_samples(self, samples) -> None:
        """The paper's measurement updates, or the fault layer's around them; then the
        outputs, ``h_std`` from the paper's P or from the fault layer's error covariance."""
        air_data, gps = samples.get(BARO_T), samples.get(GPS)
        if self.params.fault_detection:
            self._measurement_update_with_baro_gate(air_data, gps)
            self._publish(self.P_error)
        else:
            self._measurement_update(air_data, gps)
            self._publish(self.P)

    # -------------------------------------------------------------- time update
    def _time_update(self, dt: float) -> None:
        """Eqs. (17)-(18), the random walks, and eq. (33), the alpha-beta prediction."""
        p = self.params
        scale = dt / p.adm_period
        self.P_a += p.Q_a * scale                                               # (17)
        self.P_b += p.Q_b * scale                                               # (18)
        if self.started:
            self.x, self.P = predict_sparse(self.x, self.P, self._F, self._Q)   # (33)
        self.h_prior = self.x[0]

    # -------------------------------------------------------------- measurements
    def _measurement_update(self, air_data, gps) -> None:
        """Air data: λ-update; GPS: z-update; then compensation with the latest estimates."""
        if air_data is not None:
            self._lambda_update(air_data.get("baro_T"))
            self.accept(self.aid["baro"])
            self.baro = air_data["baro_h"]
        if gps is not None:
            self._gps_update(gps["gps_h"])
        if air_data is not None:
            self._compensate()

    def _lambda_update(self, temperature: float | None) -> None:
        """Eqs. (6), (7), (19)-(22): scale factor from the ADM temperature (None: an
        implausible one, left out by the intake; the z-update alone estimates it then)."""
        if temperature is None:
            return
        p = self.params
        lever = self.h_prior - p.H0
        sign = 1.0 if p.paper_lambda_sign else -1.0
        self.lambda_meas = sign * (temperature - p.lapse_rate * lever - p.T0) / p.T0   # (6)
        variance = (p.R_temperature + p.lapse_rate**2 * self.P[0][0]
                    + lever**2 * p.lapse_rate_var) / p.T0**2                        # (7)
        self.a, self.P_a, _ = update_one_state(self.a, self.P_a, self.lambda_meas,
                                               variance)                        # (20)-(22)

    def _gps_update(self, h_gps: float) -> None:
        """The z-update (eqs. 23-31), once an air-data sample gives h^B (a deviation)."""
        if not self.has_sample("baro"):
            self.note("gps: sample before the first air-data sample not fused (z = h^B - "
                      "h^GPS needs h^B)", "gps before baro")
            return
        self._z_update(h_gps)

    def _z_update(self, h_gps: float) -> None:
        """Eqs. (23)-(31): scale factor and bias from z = h^B - h^GPS."""
        p = self.params
        R = p.R_baro + p.R_gps                                                  # (10)
        z = self.baro - h_gps
        lever = h_gps - p.H0
        innovation = z - lever * self.a - self.b
        if self.gate(self.aid["gps"], innovation, self.P_b + R + lever**2 * self.P_a, p.gate_sigma,
                         aids_height=False) is not Verdict.FUSED:
            return
        if abs(lever) >= MIN_LEVER:
            z_a = (z - self.b) / lever                                          # (23)
            S_a = (self.P_b + R) / lever**2
            self.a, self.P_a, _ = update_one_state(self.a, self.P_a, z_a, S_a)  # (25), (26)
        z_b = z - lever * self.a                                                # (30)
        self.b, P_b, gain = update_one_state(self.b, self.P_b, z_b, R)          # (27)-(29)
        self.P_b = P_b + (gain * lever) ** 2 * self.P_a                         # (31)

    def _compensated(self, h_baro: float) -> tuple[float, float]:
        """Eq. (32) and the R_h of eq. (34): h^c and its variance."""
        p = self.params
        h_comp = p.H0 + (h_baro - p.H0 - self.b) / (1.0 + self.a)               # (32)
        R_h = (((h_comp - p.H0) ** 2 * self.P_a + self.P_b + p.R_baro)
               / (1.0 + self.a) ** 2)
        return h_comp, R_h

    def _compensate(self) -> tuple[float, list[float] | None]:
        """Eq. (32) and the alpha-beta filter update (eq. 34) with its R_h; the filter starts
        at the first compensated height. Returns R_h and the gain K of eq. (34) (None at
        the start)."""
        self.h_comp, R_h = self._compensated(self.baro)
        if not self.started:
            self.x = [self.h_comp, 0.0]
            self.started = True
            return R_h, None
        return R_h, self._alpha_beta_update(self.h_comp, R_h)

    def _alpha_beta_update(self, z: float, R: float) -> list[float]:
        """Eq. (34): the alpha-beta filter updated by the height z of variance R (H = [1, 0]);
        returns its gain K."""
        self.x, self.P, K = update_first_of_two(self.x, self.P, z, R)
        return K

    def _publish(self, P: list[list[float]]) -> None:
        """The outputs, ``h_std`` from the covariance ``P``."""
        self.h_est, self.vz_est = self.x
        self.h_std = math.sqrt(P[0][0])
        self.scale_factor, self.bias = self.a, self.b
        self.scale_factor_var, self.bias_var = self.P_a, self.P_b

    # -------------------------------------------------------------- fault layer
    def _time_update_with_error(self, dt: float) -> None:
        """The paper's time update, and that of the error covariance of ``h_std``."""
        self._time_update(dt)
        if self.started:
            self.P_error = predict_sparse(self.x, self.P_error, self._F, self._Q)[1]

    def _measurement_update_with_baro_gate(self, air_data, gps) -> None:
        """The paper's measurement updates with the baro height gated first: while it is
        rejected (or isolated as stuck, its samples held back by the intake) the GPS aids
        the height instead of calibrating the baro, and the last accepted h^B is held
        (module documentation)."""
        for name, sample in (("baro", air_data), ("gps", gps)):
            if sample is not None:
                self._interval(name, sample[f"{name}_time"])
        if air_data is not None:
            self._lambda_update(air_data.get("baro_T"))
            self._baro_rejected = not self._gate_baro(air_data["baro_h"])
            if not self._baro_rejected:
                self.baro = air_data["baro_h"]
        elif self.aid["baro"].isolated:     # and silent: stuck, its samples held back
            self._baro_rejected = True
        if gps is not None and self._baro_rejected:
            self._gps_height_update(gps["gps_h"])
        elif gps is not None:
            self._gps_update(gps["gps_h"])
        if air_data is not None and not self._baro_rejected:
            self._compensate_with_error()

    def _gate_baro(self, h_baro: float) -> bool:
        """True if the baro height may be fused (always before the filter starts): its
        compensated height (eq. 32, the calibration before this step's z-update) against
        the alpha-beta prediction, S = P⁻_hh + R_h (eq. 34)."""
        if not self.started:
            self.accept(self.aid["baro"])
            return True
        h_comp, R_h = self._compensated(h_baro)
        return self.gate(self.aid["baro"], h_comp - self.h_prior, self.P_error[0][0] + R_h,
                         self.params.gate_sigma) is Verdict.FUSED

    def _gps_height_update(self, h_gps: float) -> None:
        """The GPS height fused into the alpha-beta filter (eq. 34 with R^GPS) while the baro
        is rejected: z = h^B - h^GPS has no valid h^B then."""
        R = self.params.R_gps
        if self.gate(self.aid["gps"], h_gps - self.h_prior, self.P_error[0][0] + R,
                     self.params.gate_sigma) is Verdict.FUSED:
            self._error_update(self._alpha_beta_update(h_gps, R), R)

    def _compensate_with_error(self) -> None:
        """The paper's compensation and alpha-beta update, and the error covariance of
        ``h_std``: from the first sample's R_h, then updated under R^B' + N·C."""
        R_h, gain = self._compensate()
        if gain is None:
            self.P_error = diagonal((R_h, self.P[1][1]))
            return
        white = self.params.R_baro / (1.0 + self.a) ** 2
        shared = self._samples_per_calibration() * (R_h - white)
        self._error_update(gain, white + shared)

    def _error_update(self, gain: list[float], R_error: float) -> None:
        """The error covariance of ``h_std`` after the alpha-beta update of gain ``gain``,
        under the variance ``R_error`` that the height's error truly has (Joseph form)."""
        self.P_error = joseph_first_of_two(self.P_error, gain, R_error)

    def _interval(self, name: str, stamp: float) -> None:
        """Record the interval between the last two samples of ``name`` (positive only)."""
        last = self._stamps.get(name)
        if last is not None and stamp > last:
            self._intervals[name] = stamp - last
        self._stamps[name] = stamp

    def _samples_per_calibration(self) -> float:
        """N: the air-data samples between two GPS samples (at least 1), each compensated
        with the same calibration â, b̂ (they change at GPS samples only)."""
        baro, gps = self._intervals.get("baro"), self._intervals.get("gps")
        return max(1.0, gps / baro) if baro and gps else 1.0

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A GPS sample gated on z (the baro fused): b̂ moves onto it; a baro sample, or a GPS
        sample gated on the height (the baro rejected): the alpha-beta height moves onto it."""
        if source == "gps" and not self._baro_rejected:
            self.b, self.P_b = self.b + innovation, variance
            return
        shift_state(self.x, self.P, 0, innovation, variance)
        decorrelate(self.P_error, 0, variance)

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """The baro's offset is b̂ (an isolated baro re-admitted, estimators/base.py): moved
        so that its compensated height (eq. 32) lies on the prediction."""
        if source != "baro":
            return False
        scale = 1.0 + self.a
        self.b, self.P_b = self.b + scale * innovation, scale**2 * variance
        return True
