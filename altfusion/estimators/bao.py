"""BaoDriftEstimator: barometer error correction with an adaptive drift Kalman filter (bao2017).

Fig. 3 of the paper, block by block. Each ε is a correction, true minus barometric height: the
paper writes the baro height as H_B = h_t - δh_B (Section 3.3) and δh_B = ε_p + ε_d + ε_e
(eq. 1), and eqs. (4)-(5) and (11) are differences "actual minus measured" as well.

* Principle error (Sections 2.1, 3.1), eq. (5): ε_p = a·(H - H0) + b with
  a = (Rβ/g)·ΔP/P0 + ΔT/T0 and b = (R·T0/g)·ΔP/P0, where P0, T0 are the pressure and temperature
  at the reference height H0 that the barometer's height formula (eq. 2) assumes, and
  ΔP = P0' - P0, ΔT = T0' - T0 their differences from the actual values a weather station
  reports (parameters ``p0_actual``, ``T0_actual``). H is "the altitude of the last time": the
  previous estimate (the baro height itself at the first sample). With H0 = 0 this is the
  paper's eq. (5); with ``p0_actual`` = ``p0`` and ``T0_actual`` = ``T0`` (the defaults) ε_p = 0.
* Wind disturbance (Sections 2.3, 3.2), eq. (11): the wind's dynamic pressure ½ρv² (eq. 7)
  lowers the static pressure the barometer measures (eq. 8), so with P_S' the undisturbed
  static pressure = measured ``baro_p`` + ½ρv²,
  ε_e = (T0/β)[(P_S'/P0)^(-βR/g) - ((P_S' - ½ρv²)/P0)^(-βR/g)]  (negative: wind reads high).
  This is eq. (11) with P_S' read as the undisturbed pressure (our reading, see the deviations
  below). ``wind_speed`` is an
  input, used only when ``use_wind`` is true (FMI cannot tell whether an input is connected);
  a non-finite wind speed is noted and the last finite one is used.
* Drift (Sections 2.2, 3.3): the random walk of eq. (6) discretised as eq. (12),
  X(k+1) = X(k) + W(k), Q = σ²·dt per step (``drift_psd``); the observation of eq. (13),
  Z = H_G - H_B = δh_B + δh_G with H = [1], at each GPS sample against the latest corrected baro
  height; the measurement noise R_k = η_k·C of eq. (14).

The factor η of eq. (14), which the paper does not define (docs/papers.md): the GPS height error is
modelled as σ_G = UERE·VDOP·√max(1, N_ref/N), the user-equivalent range error times the
vertical dilution of precision, growing further when fewer than N_ref satellites are used (the
same model as the GnssReceiver FMU). C is the variance at the worst accuracy the filter
accepts and η = min(1, σ_G²/C), so 0 < η ≤ 1 and R_k = η_k·C = σ_G² until the GPS gets worse
than the worst case. A sample reporting VDOP ≤ 0 or no satellites gets the worst case η = 1.
With ``adaptive_R`` false the filter is the paper's "normal Kalman filter" with the constant
R = ``R_gps``.

Outputs: h_est = H_B + ε_p + ε_e + ε̂_d (the corrected baro height); h_std = √(P + R_baro)
(the drift estimate's variance plus the baro's white noise, which the random-walk state does
not carry); the algorithm estimates no vertical speed, so vz_est is always 0. The filter starts
at the first baro sample; GPS samples before it are not used.

Deviations from the paper:

* Eq. (11)'s P_S' is read as the undisturbed static pressure (measured + ½ρv²), which makes
  the wind correction exact; the paper leaves it open, and reading it as the measured
  pressure differs in the second order only. This reading is ours (the reading notes in
  docs/papers.md discuss only Table 3's values).
* η of eq. (14), which the paper does not define: the GPS error model above (docs/papers.md
  asks for one).
* GPS gate: a sample whose innovation exceeds ``gate_sigma`` standard deviations √(P + R_k)
  is rejected and logged.
* Baro gate: a baro sample that jumps from the last accepted one by more than ``gate_sigma``
  standard deviations of the jump (2 R_baro and ``max_vz``) is rejected.
* Health (estimators/base.py): a baro that stays off for ``reset_timeout`` while the GPS
  agrees is isolated; with no height source fused for that long the estimate resets.
* Held baro height (with ``fault_detection``): h_est is the last accepted baro height plus
  the drift, so when no baro sample is accepted for longer than ``reset_timeout`` (a failed,
  isolated or stopped barometer) the drift state must also carry the vehicle's motion since:
  its variance grows as (``max_vz``·t)², t the time beyond the timeout (the motion bound of
  the baro gate, counted as one standard deviation), and the GPS takes over the height.
* Baro noise shown by its scatter (with ``fault_detection``): h_est carries each accepted baro
  sample's noise unfiltered, so ``R_baro`` stated too small (told nothing: the MS5611's
  0.1 m under a 20 m baro) leaves ``h_std`` far too small and the jump gate rejecting the
  sensor's own scatter. The baro is checked on the scatter of its samples instead of its
  jumps' innovations (:meth:`_check_baro_noise`: a jump carries the motion ``max_vz``
  allows, which hides the noise): while the shown factor f exceeds 1, ``h_std`` takes
  f·R_baro, the jump gate min(f, 100)·R_baro (every shown noise's bound on a gate,
  :data:`~altfusion.estimators.noise_check.SHOWN_MAXIMUM`), and the baro's
  ``NOISE_INFLATED`` bit is set. The drift filter's R stays the paper's (docs/estimators.md
  says why).

Scenarios of the paper (for the systems that will reproduce them):

* Section 4.2 (wind): static at the ground, AirDataModule at 10 Hz (MS5611, Table 1) with the
  wind's dynamic pressure and ρ = 1.25 kg/m³ (eq. 7), Atmosphere wind 1.5 / 2.5 / 3.5 m/s for
  about 1 min after 1 min of calm; ``use_wind`` true. At ISA sea level eq. (11) gives
  0.117 / 0.325 / 0.637 m (Table 3's values need a warmer day, docs/papers.md).
* Section 4.3 (static drift): 1 h at a fixed height, no wind, AirDataModule at 10 Hz with a
  drift of about +10 m/h (Fig. 1), GnssReceiver (u-blox LEA-6H) at 5 Hz with VDOP and satellite
  count varying (``dop_mode`` scheduled or random, the same ``user_range_error`` and
  ``nsat_reference`` here); compare ``adaptive_R`` true with false (Fig. 8).
"""

import math
from dataclasses import dataclass

from altfusion.constants import G0, ISA_LAPSE_RATE, ISA_P0, ISA_T0, R_AIR
from altfusion.estimators.base import Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import update_one_state
from altfusion.estimators.noise_check import SHOWN_MAXIMUM, ShownNoise
from altfusion.estimators.streams import BARO_P, GPS_QUALITY, Stream
from altfusion.params import param
from altfusion.physics.barometric import height_from_pressure

SCATTER_MAXIMUM = 1e6
"""Largest factor the baro's scatter shows on ``R_baro`` (σ 1000x: 100 m on the MS5611's
0.1 m). Not the paper filters' bound on a gated source's weight
(:data:`~altfusion.estimators.noise_check.SHOWN_MAXIMUM`): the baro's samples are the
estimate itself, so its noise, however large, is ``h_std``'s."""


def principle_error(H: float, H0: float, p0: float, T0: float, p0_actual: float,
                    T0_actual: float, lapse_rate: float) -> float:
    """ε_p = a·(H - H0) + b (eq. 5): the first-order correction (true minus baro height) for
    actual reference pressure and temperature differing from the assumed ones (eq. 4)."""
    dP, dT = p0_actual - p0, T0_actual - T0
    a = R_AIR * lapse_rate / G0 * dP / p0 + dT / T0
    b = R_AIR * T0 / G0 * dP / p0
    return a * (H - H0) + b


def wind_error(p_measured: float, wind_speed: float, air_density: float, H0: float, p0: float,
               T0: float, lapse_rate: float) -> float:
    """ε_e (eq. 11): true minus baro height for the dynamic pressure ½ρv² (eq. 7) of the wind;
    ``p_measured`` is the disturbed static pressure P_S - ½ρv² (eq. 8) the barometer reads."""
    dynamic = 0.5 * air_density * wind_speed**2                                 # (7)
    undisturbed = p_measured + dynamic                                          # (8)
    return (height_from_pressure(undisturbed, p0, T0, lapse_rate, H0)
            - height_from_pressure(p_measured, p0, T0, lapse_rate, H0))         # (9)-(11)


def gps_height_std(vdop: float, nsat: int, user_range_error: float, nsat_reference: int) -> float:
    """σ_G = UERE·VDOP·√max(1, N_ref/N): the GPS height error the reported quality implies."""
    return user_range_error * vdop * math.sqrt(max(1.0, nsat_reference / nsat))


@dataclass(frozen=True)
class BaoParams(HealthParams):
    H0: float = param(0.0, "m", "Reference height H0 of the baro height formula (eq. 2); "
                                "0: sea level, as in eq. (5)")
    p0: float = param(ISA_P0, "Pa", "Pressure P0 at H0 that the baro height formula assumes "
                                    "(standard sea level)", positive=True)
    T0: float = param(ISA_T0, "K", "Temperature T0 at H0 that the baro height formula assumes "
                                   "(standard sea level)", positive=True)
    lapse_rate: float = param(ISA_LAPSE_RATE, "K/m", "Lapse rate β = dT/dh of the formula",
                              max=0.0)
    p0_actual: float = param(ISA_P0, "Pa", "Actual pressure at H0 from weather data (Section "
                                           "3.1); equal to p0: no principle-error correction",
                             positive=True)
    T0_actual: float = param(ISA_T0, "K", "Actual temperature at H0 from weather data; equal "
                                          "to T0: no principle-error correction", positive=True)
    use_wind: bool = param(False, None, "Correct the wind disturbance (eq. 11) with the "
                                        "wind_speed input; false: the input is not used")
    air_density: float = param(1.25, "kg/m3", "Air density ρ of the dynamic pressure (eq. 7: "
                                              "1.25 kg/m³)", positive=True)
    drift_psd: float = param(0.03, "m2/s", "Variance growth σ² of the drift random walk (eq. 6): "
                                           "0.03 m²/s wanders about 10 m per hour (Fig. 1)",
                             min=0.0)
    P0_drift: float = param(100.0, "m2", "Initial variance P(0) of the drift estimate",
                            positive=True)
    adaptive_R: bool = param(True, None, "R_k = η_k·C (eq. 14); false: the normal Kalman "
                                         "filter with constant R = R_gps")
    R_gps: float = param(9.0, "m2", "Constant R of the normal Kalman filter (adaptive_R false): "
                                    "the GPS height variance at VDOP 1.5 with UERE 2 m",
                         positive=True)
    R_worst: float = param(225.0, "m2", "C of eq. (14): the GPS height variance at the worst "
                                        "accuracy accepted (15 m), where η = 1", positive=True)
    user_range_error: float = param(2.0, "m", "UERE of the GPS height error model "
                                              "σ_G = UERE·VDOP·√max(1, N_ref/N)", positive=True)
    nsat_reference: int = param(6, None, "N_ref: below this many satellites σ_G grows as "
                                         "√(N_ref/N)", min=1)
    R_baro: float = param(0.01, "m2", "White-noise variance of the baro height (MS5611: 0.1 m, "
                                      "Table 1), added to h_std", min=0.0)
    gate_sigma: float = param(5.0, "1", "Innovation gate on GPS, and on the jump of the baro "
                                        "height since its last accepted sample (2 R_baro and "
                                        "max_vz), in standard deviations (0: off); not in the "
                                        "paper", min=0.0)


class BaoDriftEstimator(Estimator):
    """Bao et al.'s barometer error correction (bao2017, Fig. 3): principle error, wind
    disturbance and a drift Kalman filter with the adaptive R of eq. (14)."""

    Params = BaoParams
    streams = (BARO_P, GPS_QUALITY)
    extra_inputs = ("wind_speed",)
    scatter_checked = ("baro",)                 # its height is the sample: _scatter_check

    def initialize_filter(self) -> None:
        p = self.params
        self.x, self.P = 0.0, p.P0_drift          # the drift filter's state and variance
        self.h_baro = float(self.baro_h)
        self._baro_time = self._baro_accepted = float(self.baro_time)
        self.h_baro_corrected = self.h_baro
        self.principle_error = 0.0
        self.wind_error = 0.0
        self.eta = 1.0
        self.R = p.R_worst if p.adaptive_R else p.R_gps
        self.gps_std = math.sqrt(self.R)
        self.innovation = 0.0
        self._baro_scatter = self._scatter_check()
        self._baro_previous: float | None = None
        self._publish()

    def propagate(self, dt: float) -> None:
        """Eq. (12): X(k+1) = X(k) + W(k), F = G = [1], Q = σ²·dt; with ``fault_detection``
        plus the motion of a held baro height (:meth:`_held_baro_motion`)."""
        Q = self.params.drift_psd * dt                                          # (12)
        if self.started and self.params.fault_detection:
            Q += self._held_baro_motion(dt)
        self.P += Q                                            # F = [1]: x⁻ = x, P⁻ = P + Q
        self._publish()

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        if stream is BARO_P:
            self._correct_baro(sample["baro_h"], sample["baro_p"], sample["baro_time"])
        elif self.started:
            self._drift_update(sample["gps_h"], sample["gps_vdop"], int(sample["gps_nsat"]))
        self._publish()

    def _correct_baro(self, h_baro: float, p_baro: float, stamp: float) -> None:
        """Principle (eq. 5) and wind (eq. 11) corrections of one baro sample, after the gate
        on its jump from the last accepted one (not in the paper)."""
        p = self.params
        self._check_baro_noise(h_baro)
        factor = min(self._baro_noise_factor(), SHOWN_MAXIMUM)
        if not self.started:
            self.accept(self.aid["baro"])
        else:
            elapsed, self._baro_time = stamp - self._baro_time, stamp
            verdict = self.gate(self.aid["baro"], h_baro - self.h_baro,
                                self.jump_variance(factor * p.R_baro, elapsed), p.gate_sigma)
            if verdict is not Verdict.FUSED:
                return
        self._baro_time = self._baro_accepted = stamp
        H = self.h_est if self.started else h_baro       # "the altitude of the last time"
        self.principle_error = principle_error(H, p.H0, p.p0, p.T0, p.p0_actual, p.T0_actual,
                                               p.lapse_rate)
        self.wind_error = 0.0
        if p.use_wind:
            wind = self.held_input("wind_speed")
            if p_baro > 0.0:
                self.wind_error = wind_error(p_baro, wind, p.air_density, p.H0, p.p0, p.T0,
                                             p.lapse_rate)
            else:
                self.note(f"baro: pressure {p_baro!r} Pa is not positive; no wind correction",
                          "baro pressure")
        self.h_baro = h_baro
        self.h_baro_corrected = h_baro + self.principle_error + self.wind_error
        self.started = True

    def _drift_update(self, h_gps: float, vdop: float, nsat: int) -> None:
        """Eqs. (13)-(14): Z = H_G - H_B against the latest corrected baro height."""
        p = self.params
        if p.adaptive_R:
            if vdop > 0.0 and nsat > 0:
                sigma = gps_height_std(vdop, nsat, p.user_range_error, p.nsat_reference)
                self.eta = min(1.0, sigma**2 / p.R_worst)
            else:
                self.eta = 1.0
            R = self.eta * p.R_worst                                            # (14)
        else:
            R = p.R_gps
        z = h_gps - self.h_baro_corrected                                       # (13)
        innovation = z - self.x
        variance = self.P + R
        if self.gate(self.aid["gps"], innovation, variance, p.gate_sigma) is not Verdict.FUSED:
            return
        self.x, self.P, _ = update_one_state(self.x, self.P, z, R)
        self.R, self.gps_std = R, math.sqrt(R)
        self.innovation = innovation

    # ------------------------------------------------------------------ fault layer
    def _held_baro_motion(self, dt: float) -> float:
        """The drift state's variance gain over ``dt`` from a held baro height (module
        documentation, deviations): (max_vz·t)² grows with t, the time beyond
        ``reset_timeout`` since the last accepted baro sample."""
        p = self.params
        stale = max(0.0, self.time - self._baro_accepted - p.reset_timeout)
        return (p.max_vz * stale) ** 2 - (p.max_vz * max(0.0, stale - dt)) ** 2

    def _scatter_check(self) -> ShownNoise | None:
        """The baro's noise check (module documentation, deviations), with
        ``fault_detection``: fed the differences of successive baro samples, not the jump
        gate's innovations (:attr:`scatter_checked`)."""
        if not self.params.fault_detection:
            return None
        return ShownNoise(self.aid["baro"], maximum=SCATTER_MAXIMUM)

    def _baro_noise_factor(self) -> float:
        """The factor the baro's scatter shows on ``R_baro`` (1 without the check or while
        not shown)."""
        check = self._baro_scatter
        return 1.0 if check is None else check.factor

    def _check_baro_noise(self, h_baro: float) -> None:
        """The baro's scatter check fed ``h_baro``: each sample's difference from the
        previous one is checked with variance
        3·R_baro, so that a pair of them, a second difference h_k - 2h_(k-1) + h_(k-2),
        is judged against its variance 6·R_baro for white noise (successive differences
        share a sample: the check's S_k + S_(k-1) is that of their difference). The motion
        cancels in it but for the acceleration's a·Δt² (1 mm at 10 m/s² and 100 Hz)."""
        check = self._baro_scatter
        if check is None:
            return
        previous, self._baro_previous = self._baro_previous, h_baro
        if previous is not None:
            check.gated(h_baro - previous, 3.0 * self.params.R_baro)

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A baro reset takes the new baro level; a GPS reset moves the drift estimate."""
        if source == "baro":
            self.h_baro += innovation
            self.h_baro_corrected += innovation
        else:
            self.x, self.P = self.x + innovation, variance

    def _publish(self) -> None:
        self.drift = self.x
        self.drift_std = math.sqrt(self.P)
        self.h_est = self.h_baro_corrected + self.drift
        self.vz_est = 0.0
        self.h_std = math.sqrt(self.P + self._baro_noise_factor() * self.params.R_baro)
