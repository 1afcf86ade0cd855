"""YangFusionKF: optimal weighted fusion of GPS, baro and radio-altimeter heights, then a
Kalman filter on height, vertical speed and acceleration (yang2020, Fig. 1).

Section 3.1, space-time unification of the heights:

* time (3.1.1): each height sensor's samples are brought to the time t_b of the benchmark
  sample by eq. (5) as corrected in docs/papers.md, a linear extrapolation through its last two
  samples (t_c < t_a) read from their ``<prefix>_time`` stamps:
  Q_tb = Q_ta + (t_b - t_a)(Q_ta - Q_tc)/(t_a - t_c)  (Q_ta alone after a sensor's first sample).
  The benchmark is the sensor with the largest sampling period (radio altimeter 200 ms, GPS
  100 ms, baro 10 ms in Section 4.2): a fusion happens at each new sample of the first *live*
  sensor in the order radar, GPS, baro, and a sensor is live while its last sample is at most
  ``max_sample_age`` old. So the fusion falls back to GPS and baro when the radar is out of
  range, and to the baro alone when GPS is out as well.
* space (3.1.2), eq. (6): the radio altimeter measures above the terrain, so its height is
  Q_real = Q + Q_sealevel with Q_sealevel the parameter ``terrain_h`` (yang2020 flies over
  terrain at sea level: 0).

Section 3.2, optimal weighted fusion (eqs. 7-8) of the live sensors at t_b:
y = Σ ω_i x_i with ω_i = [σ_i² Σ_j 1/σ_j²]⁻¹, whose variance σ_y² = [Σ_j 1/σ_j²]⁻¹ is the
smallest (8.57 m for 30 / 20 / 10 m). The σ_i are the parameters R_gps, R_baro, R_radar.

Section 3.3, Kalman filter (eqs. 9-14) on Ω = [y, v, a] (and three bias states, below):
A of eq. (9) for each step of the estimator, and at each step the rows of Ψ = H·Ω + δ (H = I)
for which a sample arrived: the fused height (σ_y²), the GPS vertical speed (σ_v²) and the IMU
acceleration (σ_a²): eqs. 12-14 in Joseph form, the independent rows applied one after the
other (the joint update, for a diagonal R), in the shared machinery's scalar arithmetic (a
small filter stepped at 100 Hz, where numpy's per-call overhead would dominate). The filter
starts at the first fusion with h = y, Var h = σ_y².

Deviations from the paper:

* process noise: the paper's filter has none (eq. 11); taken literally it cannot follow the
  trajectory's acceleration steps (docs/papers.md), so eq. (11) gets a white-jerk process
  noise of spectral density ``jerk_psd``, Q = q·∫ φφᵀ with φ = [t²/2, t, 1];
* gates: a height sample whose difference from the predicted height exceeds ``gate_sigma``
  standard deviations √(P_hh + σ_i²) is rejected before it enters the fusion, and so is a GPS
  vertical speed against √(P_vv + σ_v²) (rejected for ``reset_timeout``, the speed resets onto
  the GPS; gate and reset only with ``fault_detection``); the acceleration gets the base's
  plausibility bound only (acceleration steps are real), which drops clipped readings
  (beyond 95 % of 16 g: a ±16 g clipping episode fused as accelerations threw the height
  3 m off);
* accelerometer bias (with ``fault_detection``; yang2020 has none): eq. (12)'s row for the
  IMU measures a + b, b a fourth state, constant up to a random walk of spectral density
  ``acc_bias_psd``, starting at 0 with variance ``P0_acc_bias`` (PX4 EKF2's EKF2_ACC_B_NOISE
  and EKF2_ABIAS_INIT). Without it the acceleration row (σ_a = 0.01 m/s²) pins the speed and
  the height to a biased accelerometer: 0.1-0.4 m/s² drifted the height about 30 m with h_std
  0.55 m on the fault suite's flight (``acc_bias``), and every height sample then fell outside
  the gate. The GPS vertical speed makes b observable (v̇ = a = z_acc - b): the bias is learnt
  and the height stays within its h_std (0.42 m RMS, coverage 96 %). With
  ``fault_detection`` false the state has zero variance and no process noise: the filter is
  the paper's, bit for bit;
* baro offset (with ``fault_detection``; yang2020's barometer has none): a fifth state d,
  the barometer's offset, a random walk of spectral density ``baro_bias_psd`` (PX4 EKF2's
  baro_bias_nsd, 0.13 m/s/√Hz) from 0 with variance ``P0_baro_bias`` (0: calibrated at the
  start, as in yang2020). Eqs. (7)-(8) fuse the heights as independent white errors; a
  drifting barometer (warm-up, weather) moved the fused height by its weight 9/49 and the
  filter, which averages y down to 0.2 m, followed it (fault suite ``baro_drift``: 1.26 m
  RMS against 0.18 m nominal, coverage 0.54). With the offset state the time-unified
  heights of a fusion (eq. 5) are fused one by one, the baro as h + d (H = [1, 0, 0, 0, 1]):
  with d known (zero variance) this is the update with y and σ_y² (the information of
  independent measurements adds up), so y and its weights stay the diagnostics of eqs.
  (7)-(8); d is learnt from the baro's disagreement with GPS and radar (``baro_drift``:
  0.28 m RMS). The baro gate is on z - h - d against P_hh + 2 P_hd + P_dd + σ_ba²;
* GPS offset (with ``fault_detection`` and ``gps_bias_psd`` > 0; off by default, the GPS
  then an absolute height as in the paper): a sixth state g, the GPS height's offset, a
  random walk of spectral density ``gps_bias_psd`` from 0 (known: the GPS unbiased at the
  start), the GPS fused as h + g and gated and re-admitted like the baro. Over terrain known
  exactly the radio altimeter is an absolute height without a bias; a GPS off by 10 m, a
  third of one sample's 30 m noise, entered the height with its weight against the radar
  (fault suite ``all_fail``: 0.82 m RMS against 3x nominal 0.76 m); with g it is taken up
  (0.46 m). Without a radar (or over unknown terrain) leave it off: baro and GPS would both
  be relative and the height would drift as their offsets' random walks;
* GNSS delay (``gps_delay``, AltitudeEKF's parameter; 0 by default, the paper's fusion at
  the estimator's clock): the GPS vertical speed is fused against the speed taken back to
  its instant s = gps_time - gps_delay along eq. (9)'s model, v(s) = v - δ·a with
  δ = now - s. Under a Jacobi-type master (libcosim, ECOS) a sensor samples the plant one of
  its steps before its stamp: at the closed-loop take-off of ``fault_demo_yang``
  (±10-16 m/s²) the GPS speed was then up to 1.6 m/s off against its σ of 0.2 m/s, its gate
  rejected it and the speeds that passed drove the accelerometer-bias state wrong (ECOS:
  9.96 m RMS over the first 120 s; 1.62 m with ``gps_delay`` the GNSS's 0.1 s step). The
  heights keep eq. (5) at their stamps: a delay moves one by v·δ (1 m at 10 m/s and 0.1 s)
  against its 10-30 m noise, and unifying a delayed GPS height to the benchmark's instant
  would extrapolate two noisy samples (eq. 5: 1.74 m instead of 1.62 m in that run);
* health (estimators/base.py): a height source rejected for ``reset_timeout`` while another
  agrees is isolated (an isolated barometer with a constant offset is re-admitted with d
  reset onto it, :meth:`reset_offset`); with every height source rejected that long the
  height resets onto the next sample (the overconfident prediction can no longer lock the
  measurements out).

Scenario of the paper (Section 4): profile ``yang2020`` (climb, cruise at 1440 m, descent over
420 s, reference altitude sea level); GnssReceiver every 100 ms with σ_h = 30 m
(``user_range_error`` 20 m at VDOP 1.5) and σ_v = 0.2 m/s; AirDataModule every 10 ms with 20 m
white noise, no scale-factor error and no drift; RadioAltimeter every 200 ms with 10 m over flat
terrain at 0 m; Accelerometer with 0.01 m/s² (its rate is not given: 10 ms here); sensor
clocks aligned (docs/papers.md); the estimator stepped every 10 ms; 500 Monte Carlo runs, accuracy
by eq. (15).
"""

import math
from collections import deque
from dataclasses import dataclass

from altfusion.estimators.base import MAX_DELAY, Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import (
    constant_states_noise,
    predict_constant_acceleration,
    quadratic_form,
    reset_state,
    update_scalar,
    white_jerk_noise,
)
from altfusion.estimators.streams import ACC, BARO, GPS_VZ, RADAR
from altfusion.params import param

HEIGHT_SENSORS = ("radar", "gps", "baro")
"""The height sensors in benchmark order: largest sampling period first (Section 4.2)."""


ACC_ROW = ((2, 1.0), (3, 1.0))
"""H of the IMU acceleration: the acceleration plus the accelerometer bias."""

HEIGHT_ROW = ((0, 1.0),)
"""H of the height itself: the fused height y (eq. 12)."""

HEIGHT_ROWS = {"radar": HEIGHT_ROW, "gps": (*HEIGHT_ROW, (5, 1.0)),
               "baro": (*HEIGHT_ROW, (4, 1.0))}
"""H of each height sensor: the height, plus the sensor's offset for the GPS and the baro."""

OFFSET_STATE = {"baro": 4, "gps": 5}
"""The state of each height sensor's offset."""

SPEED_ROW = ((1, 1.0),)
"""H of the GPS vertical speed."""


HEIGHT_STREAMS = (("baro", BARO, "baro_h", "baro_time"),
                  ("gps", GPS_VZ, "gps_h", "gps_time"),
                  ("radar", RADAR, "radar_h", "radar_time"))
"""Each height sensor's stream, height input and time-stamp input."""


def speed_row(delta: float) -> tuple[tuple[int, float], ...]:
    """H of the GPS vertical speed taken ``delta`` before the state's time, along eq. (9)'s
    constant-acceleration model: v(s) = v - δ·a (process noise over δ neglected, as
    AltitudeEKF does)."""
    return SPEED_ROW if delta == 0.0 else ((1, 1.0), (2, -delta))


def predicted(x, row) -> float:
    """H x for a sparse row H ((state index, coefficient) pairs)."""
    return sum(c * x[i] for i, c in row)


def unify_time(history, t_b: float) -> float:
    """Eq. (5) corrected: the height at t_b from the last two samples (t_c, Q_tc), (t_a, Q_ta)."""
    t_a, q_a = history[-1]
    if len(history) < 2 or history[0][0] >= t_a:
        return q_a
    t_c, q_c = history[0]
    return q_a + (t_b - t_a) * (q_a - q_c) / (t_a - t_c)


def weighted_fusion(heights: dict[str, float], variances: dict[str, float],
                    ) -> tuple[float, float, dict[str, float]]:
    """Eqs. (7)-(8): y = Σ ω_i x_i, ω_i = [σ_i² Σ 1/σ_j²]⁻¹; returns y, σ_y², the weights."""
    information = sum(1.0 / variances[name] for name in heights)
    weights = {name: 1.0 / (variances[name] * information) for name in heights}
    return sum(weights[n] * heights[n] for n in heights), 1.0 / information, weights


@dataclass(frozen=True)
class YangParams(HealthParams):
    R_gps: float = param(900.0, "m2", "GPS height variance σ_GPS² (Section 4.2: 30 m)",
                         positive=True)
    R_baro: float = param(400.0, "m2", "Baro height variance σ_ba² (Section 4.2: 20 m)",
                          positive=True)
    R_radar: float = param(100.0, "m2", "Radio-altimeter variance σ_ra² (Section 4.2: 10 m)",
                           positive=True)
    R_gps_vz: float = param(0.04, "m2/s2", "GPS vertical-speed variance (Section 4.2: "
                                           "0.2 m/s)", positive=True)
    R_acc: float = param(1e-4, "m2/s4", "IMU acceleration variance (Section 4.2: 0.01 m/s²)",
                         positive=True)
    jerk_psd: float = param(0.01, "m2/s5", "Spectral density of the white jerk added to eq. "
                                           "(11); the paper has no process noise (docs/papers.md)",
                            positive=True)
    terrain_h: float = param(0.0, "m", "Q_sealevel of eq. (6): terrain height under the radio "
                                       "altimeter (yang2020: sea level)")
    max_sample_age: float = param(0.5, "s", "A height sensor takes part in a fusion while its "
                                            "last sample is at most this old", positive=True)
    P0_vz: float = param(100.0, "m2/s2", "Initial vertical-speed variance", positive=True)
    P0_az: float = param(1.0, "m2/s4", "Initial acceleration variance", positive=True)
    P0_acc_bias: float = param(0.04, "m2/s4", "Initial variance of the accelerometer-bias "
                                              "state (PX4 EKF2_ABIAS_INIT: 0.2 m/s²); with "
                                              "fault_detection only, not in the paper",
                               min=0.0)
    acc_bias_psd: float = param(9e-6, "m2/s5", "Spectral density of the accelerometer bias's "
                                               "random walk (PX4 EKF2_ACC_B_NOISE: 3e-3 "
                                               "m/s³); with fault_detection only", min=0.0)
    P0_baro_bias: float = param(0.0, "m2", "Initial variance of the baro-offset state (0: the "
                                           "baro calibrated at the start, as in yang2020); "
                                           "with fault_detection only", min=0.0)
    baro_bias_psd: float = param(0.0169, "m2/s", "Spectral density of the baro offset's "
                                                 "random walk (PX4 EKF2 baro_bias_nsd: 0.13 "
                                                 "m/s/√Hz); with fault_detection only",
                                 min=0.0)
    gps_bias_psd: float = param(0.0, "m2/s", "Spectral density of the random walk of a GPS "
                                             "height offset state (from 0, known: the GPS "
                                             "unbiased at the start; 0: no such state, the "
                                             "GPS an absolute height as in the paper); with "
                                             "fault_detection only", min=0.0)
    gps_delay: float = param(0.0, "s", "Time from a GNSS measurement to its stamp: the GPS "
                                       "vertical speed is fused against the speed at "
                                       "gps_time - gps_delay (AltitudeEKF's and PX4's "
                                       "EKF2_GPS_DELAY; a Jacobi or ECOS master samples the "
                                       "plant one GNSS step before the stamp); not in the "
                                       "paper", min=0.0, max=MAX_DELAY)
    gate_sigma: float = param(5.0, "1", "Gate on each height sample against the predicted "
                                        "height and on the GPS vertical speed against the "
                                        "predicted speed, in standard deviations (0: off); not "
                                        "in the paper", min=0.0)


class YangFusionKF(Estimator):
    """Yang et al.'s altitude measurement (yang2020): time-unified, optimally weighted
    GPS/baro/radio-altimeter heights and a height/speed/acceleration Kalman filter."""

    Params = YangParams
    streams = (BARO, GPS_VZ, RADAR, ACC)

    def configure(self, clock) -> None:
        """Q of one step of the estimator (white jerk; the bias random walks with
        ``fault_detection``), built once: ``propagate`` is always called with this step."""
        p, dt = self.params, clock.step_size
        walks = ((p.acc_bias_psd * dt, p.baro_bias_psd * dt, p.gps_bias_psd * dt)
                 if p.fault_detection else (0.0, 0.0, 0.0))
        self._Q = constant_states_noise(white_jerk_noise(dt, p.jerk_psd), walks)

    def initialize_filter(self) -> None:
        p = self.params
        self.x = (0.0,) * 6
        self.P = self._initial_covariance(p.R_baro)
        self.history = {name: deque(maxlen=2) for name in HEIGHT_SENSORS}
        self.variances = {"radar": p.R_radar, "gps": p.R_gps, "baro": p.R_baro}
        self.h_fused = 0.0
        self.fused_std = 0.0
        self.weight_gps = self.weight_baro = self.weight_radar = 0.0
        self._stale: set[str] = set()
        self._publish()

    def propagate(self, dt: float) -> None:
        """Eqs. (9)-(11) with the white-jerk process noise (A of eq. 9 is the constant-
        acceleration model, written out in scalar arithmetic)."""
        self.x, self.P = predict_constant_acceleration(self.x, self.P, dt, self._Q)

    def fuse_samples(self, samples) -> None:
        """Gate and store the new heights, fuse at a benchmark sample, then one KF update
        (which also publishes the time update of :meth:`propagate`)."""
        now, p = self.time, self.params
        arrived = set()
        for name, stream, value, stamp in HEIGHT_STREAMS:
            sample = samples.get(stream)
            if sample is None:
                continue
            z = sample[value] + (p.terrain_h if name == "radar" else 0.0)             # (6)
            if sample[stamp] < now - p.max_sample_age and name not in self._stale:
                self._stale.add(name)
                self.note(f"{name}: sample stamped {sample[stamp]!r} s arrives older than "
                          f"max_sample_age; it cannot take part in a fusion (is {stamp} set?)")
            if self._gate(name, z):
                self.history[name].append((sample[stamp], z))
                arrived.add(name)
        measurements = []                   # (H, value, variance)
        heights = {}
        benchmark = self._benchmark(now)
        if benchmark in arrived:
            live = self._fuse_heights(self.history[benchmark][-1][0])
            if not self.started:
                self._start()
            elif p.fault_detection:
                heights = live
            else:
                measurements.append((HEIGHT_ROW, self.h_fused, self.fused_std**2))
        gps = samples.get(GPS_VZ)
        lag = 0.0 if gps is None or p.gps_delay == 0.0 else \
            max(0.0, now - (gps["gps_time"] - p.gps_delay))
        if gps is not None and self._speed_passes(gps["gps_vz"], lag):
            measurements.append((speed_row(lag), gps["gps_vz"], p.R_gps_vz))
        x, P = self.x, self.P                    # (12)-(14), H = I: the rows one by one
        for name, z in heights.items():
            row = HEIGHT_ROWS[name]
            x, P, _ = update_scalar(x, P, row, z - predicted(x, row), self.variances[name])
        for row, z, R in measurements:
            x, P, _ = update_scalar(x, P, row, z - predicted(x, row), R)
        acc = samples.get(ACC)
        if acc is not None:                      # the IMU measures a + b (b = 0 in the paper)
            self.accept(self.aid["acc"])
            x, P, _ = update_scalar(x, P, ACC_ROW, acc["acc_z"] - x[2] - x[3], p.R_acc)
        self.x, self.P = x, P
        self._publish()

    def _gate(self, name: str, z: float) -> bool:
        """True if the height sample may enter the fusion (always before the filter starts)."""
        if not self.started:
            self.accept(self.aid[name])
            return True
        P = self.P
        offset = OFFSET_STATE.get(name)
        variance = P[0][0] if offset is None else \
            P[0][0] + 2.0 * P[0][offset] + P[offset][offset]
        return self.gate(self.aid[name], z - predicted(self.x, HEIGHT_ROWS[name]),
                         variance + self.variances[name], self.params.gate_sigma) is Verdict.FUSED

    def _speed_passes(self, vz: float, lag: float) -> bool:
        """The gate on the GPS vertical speed against the predicted speed at its instant,
        ``lag`` before the clock (``gps_delay``; not in the paper;
        none before the filter starts, whose speed is then a guess). The speed variance is
        overconfident at a closed-loop take-off: after ``reset_timeout`` of rejections the
        speed resets onto the GPS (base machinery). Gate and reset come together: with
        ``fault_detection`` false the speed is fused ungated, as in the paper."""
        if not (self.started and self.params.fault_detection):
            self.accept(self.aid["gps_vz"])
            return True
        row = speed_row(lag)
        return self.gate(self.aid["gps_vz"], vz - predicted(self.x, row),
                         quadratic_form(self.P, row) + self.params.R_gps_vz,
                         self.params.gate_sigma) is Verdict.FUSED

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A GPS speed reset moves the speed onto the sample. A height reset: height onto the
        sample; speed, acceleration, accelerometer bias and baro offset back to their initial
        variances (their estimates kept): a prediction that drifted out of every gate had an
        overconfident speed and acceleration (a biased accelerometer fused as a measurement
        of the acceleration)."""
        if source == "gps_vz":
            self.x, self.P = reset_state(self.x, self.P, 1, self.x[1] + innovation, variance)
            return
        self.x = (self.x[0] + innovation, *self.x[1:])
        self.P = self._initial_covariance(variance)

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """The offset of an isolated baro or GPS re-admitted (estimators/base.py; the states
        exist with ``fault_detection``, the only case the base calls this in; the GPS offset
        only with ``gps_bias_psd`` > 0, else the GPS is an absolute height)."""
        offset = OFFSET_STATE.get(source)
        if offset is None or (source == "gps" and self.params.gps_bias_psd == 0.0):
            return False
        self.x, self.P = reset_state(self.x, self.P, offset, self.x[offset] + innovation,
                                     variance)
        return True

    def _initial_covariance(self, height_variance: float) -> tuple[tuple[float, ...], ...]:
        """Diagonal: ``height_variance``, then the initial variances of speed, acceleration
        and (with ``fault_detection``; else 0: no such state) accelerometer bias and baro
        offset."""
        p = self.params
        biases = (p.P0_acc_bias, p.P0_baro_bias) if p.fault_detection else (0.0, 0.0)
        diagonal = (height_variance, p.P0_vz, p.P0_az, *biases, 0.0)
        return tuple(tuple(v if i == j else 0.0 for j in range(6))
                     for i, v in enumerate(diagonal))

    def _benchmark(self, now: float) -> str | None:
        """The first live height sensor in order of decreasing sampling period (Section 4.2)."""
        for name in HEIGHT_SENSORS:
            history = self.history[name]
            if history and history[-1][0] >= now - self.params.max_sample_age:
                return name
        return None

    def _fuse_heights(self, t_b: float) -> None:
        """Eqs. (5)-(8): unify the live sensors' heights to t_b and fuse them with weights."""
        live = {name: unify_time(history, t_b) for name, history in self.history.items()
                if history and history[-1][0] >= t_b - self.params.max_sample_age}     # (5)
        self.h_fused, variance, weights = weighted_fusion(live, self.variances)      # (7), (8)
        self.fused_std = math.sqrt(variance)
        self.weight_gps = weights.get("gps", 0.0)
        self.weight_baro = weights.get("baro", 0.0)
        self.weight_radar = weights.get("radar", 0.0)
        return live

    def _start(self) -> None:
        """Start the filter at the first fusion: h = y, Var h = σ_y², uncorrelated."""
        self.x, self.P = reset_state(self.x, self.P, 0, self.h_fused, self.fused_std**2)
        self.started = True

    def _publish(self) -> None:
        self.h_est, self.vz_est, self.az_est, self.acc_bias, self.baro_bias, self.gps_bias = \
            self.x
        self.h_std = math.sqrt(self.P[0][0])
