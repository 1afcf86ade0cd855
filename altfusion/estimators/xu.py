"""XuSHAEKF: the improved Sage-Husa adaptive Kalman filter of Xu et al. (xu2016, Fig. 7).

State and model (Section 2.1): x = [h, vz, b_a, ε_b], altitude, vertical speed, accelerometer
bias and the barometer's constant error ε_b of eqs. (4), (14). The accelerometer ``acc_z`` is
the input u of eqs. (8)-(10); with the fusion cycle T = dt

    x_k = Φ x_{k-1} + B u_{k-1} + Γ W_{k-1},   Φ = [[1, T, -T²/2, 0], [0, 1, -T, 0],
                                                   [0, 0, 1, 0], [0, 0, 0, 1]],
    B = Γ = [T²/2, T, 0, 0]ᵀ                                                   (10), (11)

Measurements (eq. 14): GPS z = h at every GPS sample; the active height source, the laser
(z = laser_h + ``terrain_h``, H = [1, 0, 0, 0]) below ``switch_h`` above the terrain, the
barometer (z = h + ε_b, H = [1, 0, 0, 1]) above it, with ``switch_hysteresis`` and
``laser_timeout``; output ``height_source``: 0 = barometer, 1 = laser.

Each measurement of sensor x is one scalar update (Section 2.3), the nominal R_k (``R_gps``,
``R_baro``, ``R_laser``) in the theoretical innovation variance and the convergence test, the
estimate R̂_k in the gain:

1. v = z - H x⁻ (eq. 20), C = H P⁻ Hᵀ + R_k (eq. 16);
2. data analysis (eqs. 15-18): α_C = √(mean of v²/C over the sensor's last N innovations),
   weight α = min(1, (c/α_C)²);
3. gate (a deviation, below);
4. R̂_k = (1-β_k) R̂_{k-1} + β_k [(1 - H K_{k-1})² v² + H P_{k-1} Hᵀ] (eq. 22), fading factor
   β_k = β_{k-1}/(β_{k-1} + b) (eq. 28) per sensor, β = 1 before the first sample;
5. convergence test v² ≤ γ (H P⁻ Hᵀ + R_k) (eq. 23) on the active height source; if it fails,
   strong tracking P⁻ ← λ P⁻ (eq. 24), λ = max(1, (v² - R_k)/H P⁻ Hᵀ);
6. K = P⁻Hᵀ/(H P⁻ Hᵀ + R̂) (eq. 25), x = x⁻ + α K v (eq. 26), Joseph form of eq. (27) for
   the gain α K;
7. system noise (step 8): Q̂ = B σ̂_a² Bᵀ, σ̂_a² = mean((Δa)²)/2 over the last ``acc_window``
   accelerometer samples, never below ``acc_noise_std``².

With ``adaptive`` false the filter is the "Kalman filter improved before" of Figs. 10-11: the
same model and gate with the nominal R and Q, α = 1 and no strong tracking.

Deviations from the paper (the reasons in docs/estimators.md):

* eq. (19) carries the input term B·u the paper dropped; the accelerometer is the input, not
  the double-integrated "MEMS" measurement row of eq. (14) (docs/papers.md);
* states b_a (random walk ``acc_bias_psd``) and a random walk ``baro_bias_psd`` on ε_b;
* α_C averages each innovation normalised by its own C; α = min(1, (c/α_C)²) is the bounded
  mapping of eq. (18) (docs/papers.md), with α = 1 for α_C ≤ c (no division by α_C = 0);
* K_{k-1}, P_{k-1} of eq. (22) are read as this sample's gain and posterior with R̂_{k-1};
* R̂ of eq. (22) never falls below ``NOISE_FLOOR`` = 1/4 of the nominal R_k (σ half the
  stated): identical samples (frozen sensors, a stub, a stuck replay) make v → 0, so that
  eq. (22) drove R̂ toward (1 - H K) H P⁻ Hᵀ, which shrinks with R̂ itself, to 0 (laser
  6·10⁻¹³ m², GPS 0.005 m² after 60 s); when the noise resumed, the gates (R̂ in C) rejected
  most samples of the healthy sensors, a rejected sample does not feed R̂, and the estimate
  drifted with an overconfident h_std (issue 29; docs/estimators.md);
* γ = 16 (not given in the paper); strong tracking scales h, vz and b_a, and ε_b only on a
  baro sample, at most ``MAX_FADING`` per step, and b_a's variance is then held at most
  ``MAX_ACC_BIAS_VARIANCE`` (PX4 EKF2's bound);
* gate: a sample with v² > ``gate_sigma``²·(H P⁻ Hᵀ + R̂) is rejected (its innovation still
  enters the window of step 2); after ``max_rejections`` consecutive rejections the active
  height source is re-acquired, unless another source contradicts it (estimators/base.py);
* health (estimators/base.py): a height source rejected for ``reset_timeout`` while another
  agrees is isolated; with no source fused for that long the height resets; an isolated
  barometer with a constant offset is re-admitted with ε_b reset onto it (:meth:`reset_offset`;
  docs/estimators.md); in the adaptive filter, the baro's and the laser's nominal R in eqs.
  (23)-(24) is replaced by the noise their innovations show once that is beyond
  ``CHECK_FLAGGED`` times it (:meth:`_nominal`, the shared noise check).

Scenarios (Section 3): profiles ``xu_hover15``, ``xu_hover35`` and ``xu_multipoint`` (bounds of
Section 3.2: error ≤ 1 m below 25 m, ≤ 1.2 m above, 1.1 / 1.5 m with wind grade 3); realistic
sensors since the paper gives none (docs/papers.md): laser 100 Hz ±5 mm 0.1-25 m, MEMS baro
0.5 m, GNSS 5 Hz a few metres, accelerometer 100 Hz 0.05 m/s² with a bias of a few 0.01 m/s².
"""

import math
from dataclasses import dataclass

from altfusion.estimators.base import Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import (
    STATE_AND_COVARIANCE,
    decorrelate,
    diagonal,
    limit_variance,
    predict_sparse,
    quadratic_form,
    shift_state,
    sparse_dot,
    update_scalar,
)
from altfusion.estimators.noise_check import WINDOW, NoiseCheck
from altfusion.estimators.streams import ACC, BARO, GPS, LASER, Stream
from altfusion.estimators.window_sum import WindowSum
from altfusion.params import param

BARO_SOURCE, LASER_SOURCE = 0, 1
N = 4
"""States: h, vz, b_a, ε_b."""
ACC_BIAS = 2
"""The index of b_a, the accelerometer bias."""
BARO_OFFSET = 3
"""The index of ε_b, the barometer's slow error."""
ALTITUDE_ROW = ((0, 1.0),)
"""H of a height measurement (laser, GPS), as (state index, coefficient) pairs."""
BARO_ROW = ((0, 1.0), (BARO_OFFSET, 1.0))
"""H of the barometer: h + ε_b (eq. 14)."""
MOTION_STATES = (True, True, True, False)
"""h, vz and the accelerometer bias: the states strong tracking always inflates."""
MIN_VARIANCE = 1e-12
"""Floor of H P⁻ Hᵀ in the strong-tracking factor, m²."""
MAX_FADING = 1000.0
"""Largest λ of one strong-tracking step (eq. 24); a larger mismatch takes a few samples."""
MAX_ACC_BIAS_VARIANCE = 1.0
"""Largest variance of the accelerometer bias b_a after strong tracking, m²/s⁴ (PX4 EKF2's
bound on its accelerometer bias variance): see :meth:`XuSHAEKF._strong_tracking`."""
CHECK_MAXIMUM = 1e4
"""Largest factor of a noise check on a nominal R (σ a hundredfold: a 0.5 m baro stated for
a 20-50 m one)."""
CHECK_FLAGGED = 16.0
"""A noise check's factor beyond which the nominal R is replaced (σ shown beyond four times
the stated): strong tracking's corrections make successive innovations of this filter
correlated, and for sensors as told the checks' ratio reached 1.2-4.4 over ten fault-flight
runs, where :data:`~altfusion.estimators.noise_check.FLAGGED` (4) is meant for a consistent
filter; a noise told 5x too small shows 25-71."""
NOISE_FLOOR = 0.25
"""Floor of a noise estimate R̂ (eq. 22) as a fraction of its nominal R: a sensor is taken to
be at most twice as precise (in σ) as stated. Without it identical samples drive R̂ to 0
(see the module documentation)."""


@dataclass(frozen=True)
class XuParams(HealthParams):
    R_gps: float = param(9.0, "m2", "Nominal GPS height variance R (3 m: a few metres, "
                                    "docs/papers.md)", positive=True)
    R_baro: float = param(0.25, "m2", "Nominal baro height variance (MEMS baro: 0.5 m)",
                          positive=True)
    R_laser: float = param(2.5e-5, "m2", "Nominal laser variance (Section 1.2.4: ±5 mm)",
                           positive=True)
    acc_noise_std: float = param(0.05, "m/s2", "Nominal accelerometer white noise per sample "
                                               "(MEMS at 100 Hz); floor of the estimate σ̂_a",
                                 positive=True)
    acc_window: int = param(100, None, "Accelerometer samples of the real-time noise estimate",
                            min=2)
    acc_bias_std: float = param(0.05, "m/s2", "Initial 1σ of the accelerometer bias (calibrated "
                                              "MEMS: 0.01-0.05 m/s²)", positive=True)
    acc_bias_psd: float = param(1e-6, "m2/s5", "Random walk of the accelerometer bias",
                                min=0.0)
    baro_bias_std: float = param(1.0, "m", "Initial 1σ of the baro constant error ε_b (eq. 4; "
                                           "after the take-off calibration)", positive=True)
    baro_bias_psd: float = param(0.01, "m2/s", "Random walk of ε_b (weather drift, about 6 m "
                                               "per hour)", min=0.0)
    P0_vz: float = param(1.0, "m2/s2", "Initial vertical-speed variance", positive=True)
    terrain_h: float = param(0.0, "m", "Terrain height under the laser (MSL)")
    switch_h: float = param(25.0, "m", "Laser below, baro above this height over the terrain "
                                       "(eq. 14)", positive=True)
    switch_hysteresis: float = param(1.0, "m", "Back to the laser only below switch_h minus "
                                               "this", min=0.0)
    laser_timeout: float = param(0.1, "s", "Without a valid laser sample for this long the "
                                           "baro takes over", positive=True)
    adaptive: bool = param(True, None, "Improved SHAEKF (eqs. 15-28); false: the Kalman filter "
                                       "with nominal R and Q (Figs. 10-11's comparison)")
    b_gps: float = param(0.99, "1", "Fading memory factor b of eq. (28) for GPS", min=0.5,
                         max=0.9999)
    b_baro: float = param(0.99, "1", "Fading memory factor b of eq. (28) for the baro",
                          min=0.5, max=0.9999)
    b_laser: float = param(0.99, "1", "Fading memory factor b of eq. (28) for the laser",
                           min=0.5, max=0.9999)
    innovation_window: int = param(20, None, "N of eq. (15): innovations per sensor in the "
                                             "actual innovation variance", min=1)
    weight_c: float = param(1.5, "1", "c of the weight α = min(1, (c/α_C)²) (eq. 18): the "
                                      "innovation ratio tolerated at full weight",
                            positive=True)
    gamma: float = param(16.0, "1", "Convergence threshold γ of eq. (23) (4σ, see the module "
                                    "documentation)", positive=True)
    gate_sigma: float = param(6.0, "1", "Gate in standard deviations √C (0: off); not in the "
                                        "paper", min=0.0)
    max_rejections: int = param(10, None, "Consecutive rejections of the active height source "
                                          "before it is re-acquired", min=1)


@dataclass
class Channel:
    """The adaptive statistics of one sensor's measurements (eqs. 15-18, 22, 28)."""

    R_nominal: float
    b: float
    window: WindowSum
    """v²/C of the last N innovations (eq. 15)."""
    R_hat: float = 0.0
    beta: float = 1.0
    weight: float = 1.0
    rejections: int = 0

    def __post_init__(self):
        self.R_hat = self.R_nominal

    def innovation_ratio(self, nis: float) -> float:
        """Eqs. (15)-(17): push v²/C and return α_C, the actual over the theoretical spread."""
        self.window.push(nis)
        return math.sqrt(self.window.total() / len(self.window))

    def estimate_noise(self, innovation: float, hph: float) -> None:
        """Eqs. (22) and (28), with H K_{k-1} = H P⁻ Hᵀ/(H P⁻ Hᵀ + R̂_{k-1}), the gain before
        this noise estimate, and H P_{k-1} Hᵀ = (1 - H K_{k-1}) H P⁻ Hᵀ its posterior; R̂ is
        kept at or above :data:`NOISE_FLOOR` R_k (a deviation)."""
        self.beta = self.beta / (self.beta + self.b)                            # (28)
        hk = hph / (hph + self.R_hat)
        residual = (1.0 - hk) * innovation
        estimate = ((1.0 - self.beta) * self.R_hat
                    + self.beta * (residual**2 + (1.0 - hk) * hph))             # (22)
        self.R_hat = max(estimate, NOISE_FLOOR * self.R_nominal)


class XuSHAEKF(Estimator):
    """Xu et al.'s improved Sage-Husa adaptive Kalman filter (xu2016): accelerometer-driven
    height with laser/baro switching, GPS, adaptive noise, sensor weights and strong tracking."""

    Params = XuParams
    streams = (ACC, LASER, BARO, GPS)
    state_covariances = STATE_AND_COVARIANCE
    required_sources = {"acc": "its process model is driven by the accelerometer (xu2016 eqs. "
                               "10-11, 19: acc_z is the input u)"}

    def configure(self, clock) -> None:
        """Φ (as sparse rows), B and B·Bᵀ of eqs. (10)-(11) for one step of the estimator,
        built once: ``propagate`` is always called with this step."""
        dt = clock.step_size
        self._Phi = (((0, 1.0), (1, dt), (2, -dt * dt / 2.0)), ((1, 1.0), (2, -dt)),
                     ((2, 1.0),), ((3, 1.0),))
        self._B = (dt * dt / 2.0, dt, 0.0, 0.0)
        self._BBt = tuple(tuple(b_a * b_b for b_b in self._B) for b_a in self._B)

    def initialize_filter(self) -> None:
        p = self.params
        self.x = [0.0] * N
        self.P = diagonal((p.R_baro, p.P0_vz, p.acc_bias_std**2, p.baro_bias_std**2))
        self.u = 0.0
        self._acc_last: float | None = None
        self._acc_diffs = WindowSum(p.acc_window)
        self.acc_noise_est = p.acc_noise_std
        self.channels = {
            "gps": Channel(p.R_gps, p.b_gps, WindowSum(p.innovation_window)),
            "baro": Channel(p.R_baro, p.b_baro, WindowSum(p.innovation_window)),
            "laser": Channel(p.R_laser, p.b_laser, WindowSum(p.innovation_window)),
        }
        self.noise_checks = {name: NoiseCheck(self.aid[name], WINDOW, CHECK_MAXIMUM,
                                              flagged=CHECK_FLAGGED)
                             for name in ("baro", "laser")} \
            if p.fault_detection and p.adaptive else {}
        """The noise check of each height source that strong tracking watches (the fault
        layer's, for the adaptive filter: :meth:`_nominal`)."""
        self.height_source = BARO_SOURCE
        self._last_laser_time = -math.inf
        self.strong_tracking_factor = 1.0
        self.n_strong_tracking = 0
        self._publish()

    # -------------------------------------------------------------- time update
    def propagate(self, dt: float) -> None:
        """Eqs. (10)-(11), (19), (21) with the input u = latest acc_z and Q̂ = B σ̂_a² Bᵀ."""
        if not self.started:
            return
        p = self.params
        variance = self.acc_noise_est**2
        Q = [[b * variance for b in row] for row in self._BBt]
        Q[2][2] += p.acc_bias_psd * dt
        Q[3][3] += p.baro_bias_psd * dt
        Bu = [b * self.u for b in self._B]
        self.x, self.P = predict_sparse(self.x, self.P, self._Phi, Q, Bu)
        # published by fuse_samples, which ends every step

    # -------------------------------------------------------------- measurements
    def fuse_samples(self, samples: dict[Stream, dict[str, float]]) -> None:
        p = self.params
        if ACC in samples:
            self.accept(self.aid["acc"])
            self._accelerometer(samples[ACC]["acc_z"])
        if LASER in samples:
            self._last_laser_time = self.time
        self._select_source()
        if LASER in samples and self.height_source == LASER_SOURCE:
            self._measure("laser", samples[LASER]["laser_h"] + p.terrain_h, ALTITUDE_ROW)
        if BARO in samples and self.height_source == BARO_SOURCE:
            self._measure("baro", samples[BARO]["baro_h"], BARO_ROW)
        if GPS in samples:
            self._measure("gps", samples[GPS]["gps_h"], ALTITUDE_ROW)
        self._publish()

    def _accelerometer(self, acc: float) -> None:
        """The input u of eq. (9) and the real-time noise estimate of step 8."""
        if self._acc_last is not None:
            self._acc_diffs.push((acc - self._acc_last) ** 2)
        self._acc_last = self.u = acc
        if self.params.adaptive and len(self._acc_diffs) > 0:
            estimate = math.sqrt(self._acc_diffs.total() / (2.0 * len(self._acc_diffs)))
            self.acc_noise_est = max(self.params.acc_noise_std, estimate)

    def _select_source(self) -> None:
        """Eq. (14): laser below switch_h over the terrain, baro above, with hysteresis."""
        p = self.params
        laser_live = self.time - self._last_laser_time <= p.laser_timeout
        above = self.x[0] - p.terrain_h
        if self.height_source == LASER_SOURCE:
            if not laser_live or (self.started and above > p.switch_h):
                self.height_source = BARO_SOURCE
        elif laser_live and (not self.started or above < p.switch_h - p.switch_hysteresis):
            self.height_source = LASER_SOURCE

    def _measure(self, name: str, z: float, H: tuple[tuple[int, float], ...]) -> None:
        """Steps 1-6 of the module documentation for one sample of sensor ``name``, whose
        measurement row is H."""
        p = self.params
        channel = self.channels[name]
        if not self.started:
            self._start(z, H, channel.R_hat)
            self.accept(self.aid[name])
            return
        innovation = z - sparse_dot(self.x, H)                                  # (20)
        hph = quadratic_form(self.P, H)
        ratio = channel.innovation_ratio(innovation**2 / (hph + channel.R_nominal))  # (15)-(17)
        if p.adaptive:       # (18), α = min(1, (c/α_C)²) without dividing by α_C = 0
            channel.weight = 1.0 if ratio <= p.weight_c else (p.weight_c / ratio) ** 2
        C = hph + channel.R_hat
        active = name != "gps"
        verdict = self.gate(self.aid[name], innovation, C, p.gate_sigma)
        check = self.noise_checks.get(name)
        if check is not None:                   # judged with the noise it has found so far
            R_checked = channel.R_nominal * check.factor
            check.gated(innovation, hph + R_checked, R_checked)
        if verdict is not Verdict.FUSED:
            channel.rejections += 1
            if not (active and channel.rejections > p.max_rejections
                    and not self.contradicted(self.aid[name], innovation)):
                return
            self.note(f"{name}: re-acquired after {p.max_rejections} consecutive rejections "
                      f"(innovation {innovation:.4g} m)")
            self.accept(self.aid[name])
            channel.window.clear()
            channel.weight = 1.0
            if check is not None:
                check.forget()
        channel.rejections = 0
        if p.adaptive:
            channel.estimate_noise(innovation, hph)                             # (22), (28)
            R_k = self._nominal(name)
            if active and innovation**2 > p.gamma * (hph + R_k):                # (23)
                self._strong_tracking(innovation**2, R_k, hph)                   # (24)
        self.x, self.P, _ = update_scalar(self.x, self.P, H, innovation, channel.R_hat,
                                          channel.weight)                       # (25)-(27)

    def _nominal(self, name: str) -> float:
        """R_k of height source ``name`` in the convergence test of eq. (23) and the factor λ
        of eq. (24): its nominal R or, in the fault layer, the noise its innovations show
        once that is beyond :data:`CHECK_FLAGGED` times the nominal (its noise check's factor;
        the source's ``NOISE_INFLATED`` bit: a deviation). A nominal R far below the sensor's
        noise makes eq. (23) fail on the noise itself: strong tracking then inflates P⁻ sample
        after sample, and the gate, sized by that P⁻, lets a failed sensor's step in (told
        nothing on the fault flight, a 20 m baro for the default's 0.5 m followed its +200 m
        failure in one run of ten; docs/estimators.md). Eqs. (15)-(17) keep the nominal R:
        their weight is what tells a sensor that became noisier (a failing GPS) from one that
        was always so."""
        nominal = self.channels[name].R_nominal
        check = self.noise_checks.get(name)
        return nominal * check.factor if check is not None and check.beyond_flag else nominal

    def _strong_tracking(self, innovation_sq: float, R: float, hph: float) -> None:
        """Eq. (24): P⁻ ← λ P⁻ with λ = max(1, (v² - R)/H P⁻ Hᵀ), at most MAX_FADING.

        λ scales the states of the motion the innovation reveals: h, vz and the accelerometer
        bias that drives them (P⁻ ← D P⁻ D, D = √λ on those states and 1 elsewhere, which keeps
        P⁻ positive definite). The baro's slow error ε_b is not inflated, even on a baro
        sample: in a steady hover H P⁻ Hᵀ is tiny and λ reaches hundreds, and an inflated ε_b
        let the baro sample fix only the sum h + ε_b, so that the next GPS sample moved h by
        nearly its own error (6-7 m spikes above 25 m in the xu2016 reproduction).

        b_a's variance is then held at most :data:`MAX_ACC_BIAS_VARIANCE` (a deviation:
        :func:`~altfusion.estimators.kalman.limit_variance`). The height sources see b_a only
        through its double integral, so its inflation compounds from sample to sample while
        the innovations stay large: told noises 40x too small (the defaults on a 20 m baro),
        it grew until one GNSS sample set b_a to hundreds of m/s² (docs/estimators.md)."""
        factor = min(MAX_FADING, max(1.0, (innovation_sq - R) / max(hph, MIN_VARIANCE)))
        root = math.sqrt(factor)
        roots = [root if motion else 1.0 for motion in MOTION_STATES]
        self.P = [[p_ab * (r_a * r_b) for p_ab, r_b in zip(P_a, roots, strict=True)]
                  for P_a, r_a in zip(self.P, roots, strict=True)]
        limit_variance(self.P, ACC_BIAS, MAX_ACC_BIAS_VARIANCE)
        self.strong_tracking_factor = factor
        self.n_strong_tracking += 1

    def _start(self, z: float, H: tuple[tuple[int, float], ...], R: float) -> None:
        """Start at the first height sample: h = z - (rest of H)·x, uncorrelated with vz."""
        b = BARO_OFFSET
        offset = dict(H).get(b, 0.0)                    # ε_b's coefficient in H
        self.x[0] = z - offset * self.x[b]
        decorrelate(self.P, 0, R + offset**2 * self.P[b][b])
        self.P[0][b] = self.P[b][0] = -offset * self.P[b][b]
        self.started = True

    def checks_own_noise(self) -> bool:
        """The adaptive filter checks its baro's and laser's nominal R (:meth:`_nominal`);
        the plain one is checked by the fault layer as the other paper filters are."""
        return self.params.adaptive

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        shift_state(self.x, self.P, 0, innovation, variance)
        for check in self.noise_checks.values():     # the prediction moved between samples
            check.forget()

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """The barometer's offset ε_b (an isolated baro re-admitted, estimators/base.py)."""
        if source != "baro":
            return False
        shift_state(self.x, self.P, BARO_OFFSET, innovation, variance)
        check = self.noise_checks.get("baro")
        if check is not None:
            check.forget()
        return True

    def _publish(self) -> None:
        self.h_est, self.vz_est, self.acc_bias, self.baro_bias = self.x
        self.h_std = math.sqrt(self.P[0][0])
        self.weight_gps = self.channels["gps"].weight
        self.weight_baro = self.channels["baro"].weight
        self.weight_laser = self.channels["laser"].weight
        self.R_gps_est = self.channels["gps"].R_hat
        self.R_baro_est = self.channels["baro"].R_hat
        self.R_laser_est = self.channels["laser"].R_hat
