"""YangFusionKF: optimal weighted fusion of GPS, baro and radio-altimeter heights, then a
Kalman filter on height, vertical speed and acceleration (yang2020, Fig. 1).

Section 3.1, space-time unification of the heights:

* time (3.1.1): each height sensor's samples are brought to the time t_b of the benchmark
  sample by eq. (5) as corrected in docs/papers.md (reading notes), a linear extrapolation
  through its last two samples (t_c < t_a) read from their ``<prefix>_time`` stamps:
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

Section 3.3, Kalman filter (eqs. 9-14) on Ω = [y, v, a]: A of eq. (9) for each step of the
estimator, and at each step the rows of Ψ = H·Ω + δ (H = I) for which a sample arrived: the
fused height (σ_y²), the GPS vertical speed (σ_v²) and the IMU acceleration (σ_a²): eqs.
12-14 in Joseph form, the independent rows applied one after the other (the joint update, for
a diagonal R), in the shared machinery's scalar arithmetic. The filter starts at the first
fusion with h = y, Var h = σ_y². With ``fault_detection`` false this is the estimator
(:meth:`YangFusionKF._kalman_update`), with the deviations below.

Deviations from the paper:

* process noise: eq. (11) has none, and taken literally the filter cannot follow the
  trajectory's acceleration steps (docs/papers.md, reading notes): a white jerk of spectral
  density ``jerk_psd``, Q = q·∫ φφᵀ with φ = [t²/2, t, 1];
* height gates: a height sample further than ``gate_sigma`` standard deviations √(P_hh + σ_i²)
  from the predicted height does not enter the fusion; the acceleration has the shared
  plausibility bound only (acceleration steps are real; clipped readings are dropped);
* GNSS delay (``gps_delay``, 0 by default): the GPS vertical speed is fused against the speed
  at its instant s = gps_time - gps_delay along eq. (9)'s model, v(s) = v - δ·a, δ = now - s
  (a Jacobi-type master samples the GNSS one of its steps before its stamp); the heights keep
  eq. (5) at their stamps.

The fault layer (``fault_detection`` true, :meth:`YangFusionKF._kalman_update_with_offsets`),
not in the paper; ``docs/estimators.md`` says which fault-suite scenario each part is for:

* the GPS vertical speed gated against √(P_vv + σ_v²); rejected for ``reset_timeout``, the
  speed resets onto it (PX4's velocity reset);
* accelerometer bias: the IMU row measures a + b, b a fourth state, a random walk of
  spectral density ``acc_bias_psd`` from 0 with variance ``P0_acc_bias`` (PX4 EKF2's
  EKF2_ACC_B_NOISE and EKF2_ABIAS_INIT), observable through the GPS vertical speed;
* baro offset: a fifth state d, a random walk of spectral density ``baro_bias_psd`` (PX4
  EKF2's baro_bias_nsd) from 0 with variance ``P0_baro_bias``; the time-unified heights of a
  fusion (eq. 5) are fused one by one instead of as y, the baro as h + d (H = [1, 0, 0, 0, 1];
  with d known this is the update with y and σ_y², so y and its weights stay the diagnostics
  of eqs. 7-8); the baro gate is on z - h - d against P_hh + 2 P_hd + P_dd + σ_ba²;
* GPS offset (``gps_bias_psd`` > 0; off by default, the GPS then an absolute height as in the
  paper): a sixth state g from 0 (known), the GPS fused as h + g and gated and re-admitted
  like the baro. Only where another absolute height exists (a radio altimeter over known
  terrain): with baro and GPS both relative the height would drift;
* the accelerometer's noise measured from its samples' scatter and used in the IMU row when
  it is more than 1.5x σ_a (:mod:`~altfusion.estimators.accelerometer_check`; only the
  scatter: the height sources' disagreement does not judge it here, see docs/estimators.md);
* stuck readings (:mod:`~altfusion.estimators.stuck`, in the shared intake): a reading
  repeated bit for bit ``stuck_samples`` times in a row is not fused until it changes. A
  GNSS vertical speed left unconnected reads 0 while the heights arrive; fused, it held the
  speed at 0 through every climb (on ±10 m waves at 2 m/s: 8.8 m RMS at coverage 13 %, ``h_valid``
  true). A receiver that holds still repeats itself too, and is only held;
* isolation, height resets and re-referencing (:mod:`~altfusion.estimators.fault_detection`):
  an isolated baro or GPS with a constant offset is re-admitted with its offset state reset
  onto it (:meth:`YangFusionKF.reset_offset`); a height reset moves h onto the sample and the
  other states back to their initial variances.

Scenario of the paper (Section 4): profile ``yang2020`` (climb, cruise at 1440 m, descent over
420 s, reference altitude sea level); GnssReceiver every 100 ms with σ_h = 30 m
(``user_range_error`` 20 m at VDOP 1.5) and σ_v = 0.2 m/s; AirDataModule every 10 ms with 20 m
white noise, no scale-factor error and no drift; RadioAltimeter every 200 ms with 10 m over flat
terrain at 0 m; Accelerometer with 0.01 m/s² (its rate is not given: 10 ms here); sensor
clocks aligned (docs/papers.md); the estimator stepped every 10 ms; 500 Monte Carlo runs,
accuracy by eq. (15).
"""

import math
from collections import deque
from dataclasses import dataclass

from altfusion.estimators.aid_source import FUSED
from altfusion.estimators.base import MAX_DELAY, Estimator, HealthParams
from altfusion.estimators.health_params import PX4_HEIGHT_BIAS_PSD
from altfusion.estimators.kalman import (
    STATE_AND_COVARIANCE,
    constant_states_noise,
    decorrelate,
    diagonal,
    predict_constant_acceleration_in_place,
    quadratic_form,
    running_sum,
    shift_state,
    sparse_dot,
    update_scalar_in_place,
    white_jerk_noise,
)
from altfusion.estimators.streams import ACC, BARO, GPS_VZ, RADAR
from altfusion.params import param

HEIGHT_SENSORS = ("radar", "gps", "baro")
"""The height sensors in benchmark order: largest sampling period first (Section 4.2)."""

HEIGHT_ROW = ((0, 1.0),)
"""H of the height itself: the fused height y (eq. 12)."""

ACC_ROW = ((2, 1.0),)
"""H of the IMU acceleration (eq. 12)."""

SPEED_ROW = ((1, 1.0),)
"""H of the GPS vertical speed (eq. 12)."""

ACC_BIAS, BARO_OFFSET, GPS_OFFSET = 3, 4, 5
"""The fault layer's states after Ω = [y, v, a]."""

ACC_BIAS_ROW = ((2, 1.0), (ACC_BIAS, 1.0))
"""H of the IMU acceleration with the fault layer: the acceleration plus its bias."""

OFFSET_STATE = {"baro": BARO_OFFSET, "gps": GPS_OFFSET}
"""The state of each height sensor's offset (fault layer)."""

HEIGHT_STREAMS = (("baro", BARO, "baro_h", "baro_time"),
                  ("gps", GPS_VZ, "gps_h", "gps_time"),
                  ("radar", RADAR, "radar_h", "radar_time"))
"""Each height sensor's stream, height input and time-stamp input."""


def speed_row(delta: float) -> tuple[tuple[int, float], ...]:
    """H of the GPS vertical speed taken ``delta`` before the state's time, along eq. (9)'s
    constant-acceleration model: v(s) = v - δ·a (process noise over δ neglected, as
    AltitudeEKF does)."""
    return SPEED_ROW if delta == 0.0 else ((1, 1.0), (2, -delta))


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
    information = running_sum(1.0 / variances[name] for name in heights)
    weights = {name: 1.0 / (variances[name] * information) for name in heights}
    return running_sum(weights[n] * heights[n] for n in heights), 1.0 / information, weights


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
    baro_bias_psd: float = param(PX4_HEIGHT_BIAS_PSD, "m2/s", "Spectral density of the baro "
                                 "offset's random walk (PX4 EKF2 baro_bias_nsd: 0.13 m/s/√Hz); "
                                 "with fault_detection only", min=0.0)
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
    state_covariances = STATE_AND_COVARIANCE
    acc_drives_prediction = False

    def configure(self, clock) -> None:
        """The states (Ω of eq. 9; with ``fault_detection`` the accelerometer bias, the baro
        offset and, with ``gps_bias_psd`` > 0, the GPS offset) and Q of one step of the
        estimator (white jerk, the offsets' random walks), built once: ``propagate`` is
        always called with this step."""
        p, dt = self.params, clock.step_size
        walks = ()
        if p.fault_detection:
            walks = (p.acc_bias_psd * dt, p.baro_bias_psd * dt,
                     *((p.gps_bias_psd * dt,) if p.gps_bias_psd > 0.0 else ()))
        self._n = 3 + len(walks)
        self._walks = walks
        self._Q = constant_states_noise(white_jerk_noise(dt, p.jerk_psd), walks)
        self._Q_inflation = 1.0
        self._height_rows = {name: (*HEIGHT_ROW, *(((OFFSET_STATE[name], 1.0),)
                                                   if OFFSET_STATE.get(name, self._n) < self._n
                                                   else ()))
                             for name in HEIGHT_SENSORS}
        """H of each height sensor: the height, plus its offset where it has one."""

    def initialize_filter(self) -> None:
        p = self.params
        self.x = [0.0] * self._n
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
        check = self.acc_check
        if check is not None and check.inflation != self._Q_inflation:
            self._Q_inflation = check.inflation
            self._Q = constant_states_noise(
                white_jerk_noise(dt, self.params.jerk_psd * check.inflation), self._walks)
        predict_constant_acceleration_in_place(self.x, self.P, dt, self._Q)

    def fuse_samples(self, samples) -> None:
        """Gate and store the new heights, fuse them at a benchmark sample (eqs. 5-8), then
        one Kalman update (eqs. 12-14; also publishes the time update of :meth:`propagate`)."""
        now, p = self.clock.now, self.params
        arrived = self._new_heights(samples, now)
        benchmark = self._benchmark(now)
        heights = None
        if benchmark in arrived:
            live = self._fuse_heights(self.history[benchmark][-1][0])
            if self.started:
                heights = live
            else:
                self._start()
        gps = samples.get(GPS_VZ)
        lag = 0.0 if gps is None or p.gps_delay == 0.0 else \
            max(0.0, now - (gps["gps_time"] - p.gps_delay))
        acc = samples.get(ACC)
        if p.fault_detection:
            self._kalman_update_with_offsets(heights, gps, lag, acc)
        else:
            self._kalman_update(heights, gps, lag, acc)
        self._publish()

    def _new_heights(self, samples, now: float) -> set[str]:
        """Eq. (6) for the radio altimeter, then each new height sample through its gate
        (always passed before the filter starts) into its sensor's history; the sensors whose
        sample entered."""
        p = self.params
        arrived = set()
        for name, stream, value, stamp in HEIGHT_STREAMS:
            sample = samples.get(stream)
            if sample is None or value not in sample:
                continue
            z = sample[value] + (p.terrain_h if name == "radar" else 0.0)             # (6)
            if sample[stamp] < now - p.max_sample_age and name not in self._stale:
                self._stale.add(name)
                self.note(f"{name}: sample stamped {sample[stamp]!r} s arrives older than "
                          f"max_sample_age; it cannot take part in a fusion (is {stamp} set?)")
            if self._gate(name, z):
                self.history[name].append((sample[stamp], z))
                arrived.add(name)
        return arrived

    def _kalman_update(self, heights, gps, lag: float, acc) -> None:
        """Eqs. (12)-(14), H = I: the rows of the fused height y (σ_y²), the GPS vertical
        speed (σ_v²) and the IMU acceleration (σ_a²) that arrived, one after the other."""
        p = self.params
        x, P = self.x, self.P
        if heights is not None:
            update_scalar_in_place(x, P, HEIGHT_ROW, self.h_fused - sparse_dot(x, HEIGHT_ROW),
                                   self.fused_std**2)
        if gps is not None:
            self.accept(self.aid["gps_vz"])
            row = speed_row(lag)
            update_scalar_in_place(x, P, row, gps["gps_vz"] - sparse_dot(x, row), p.R_gps_vz)
        if acc is not None:
            self.accept(self.aid["acc"])
            update_scalar_in_place(x, P, ACC_ROW, acc["acc_z"] - x[2], p.R_acc)

    # ------------------------------------------------------------------ fault layer
    def _kalman_update_with_offsets(self, heights, gps, lag: float, acc) -> None:
        """The fault layer's eqs. (12)-(14): the time-unified heights one by one, each with
        its offset; the GPS vertical speed gated; the IMU acceleration with its bias."""
        p = self.params
        speed = gps is not None and "gps_vz" in gps and self._speed_passes(gps["gps_vz"], lag)
        x, P = self.x, self.P
        for name, z in (heights or {}).items():
            row = self._height_rows[name]
            update_scalar_in_place(x, P, row, z - sparse_dot(x, row), self.variances[name])
        if speed:
            row = speed_row(lag)
            update_scalar_in_place(x, P, row, gps["gps_vz"] - sparse_dot(x, row), p.R_gps_vz)
        if acc is not None:
            self.accept(self.aid["acc"])
            check = self.acc_check
            check.sample(acc["acc_z"])
            R_acc = p.R_acc * check.inflation
            update_scalar_in_place(x, P, ACC_BIAS_ROW, acc["acc_z"] - x[2] - x[ACC_BIAS], R_acc)

    def _speed_passes(self, vz: float, lag: float) -> bool:
        """The gate on the GPS vertical speed against the predicted speed at its instant,
        ``lag`` before the clock (none before the filter starts, whose speed is then a
        guess). The speed variance is overconfident at a closed-loop take-off: after
        ``reset_timeout`` of rejections the speed resets onto the GPS."""
        if not self.started:
            self.accept(self.aid["gps_vz"])
            return True
        row = speed_row(lag)
        return self.gate(self.aid["gps_vz"], vz - sparse_dot(self.x, row),
                         quadratic_form(self.P, row) + self.params.R_gps_vz,
                         self.params.gate_sigma) is FUSED

    def gnss_height_sigma(self, sample) -> float:
        """σ_GPS (Section 3.2's R_gps)."""
        return math.sqrt(self.params.R_gps)

    def accelerometer_noise(self) -> float:
        """σ_a = √R_acc: its scatter checked with ``fault_detection``."""
        return math.sqrt(self.params.R_acc)

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A GPS speed reset moves the speed onto the sample. A height reset: height onto the
        sample; speed, acceleration, accelerometer bias and baro offset back to their initial
        variances (their estimates kept): a prediction that drifted out of every gate had an
        overconfident speed and acceleration."""
        if source == "gps_vz":
            shift_state(self.x, self.P, 1, innovation, variance)
            return
        self.x[0] += innovation
        self.P = self._initial_covariance(variance)

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """The offset of an isolated baro or GPS re-admitted (the GPS offset only with
        ``gps_bias_psd`` > 0, else the GPS is an absolute height)."""
        offset = OFFSET_STATE.get(source, self._n)
        if offset >= self._n:
            return False
        shift_state(self.x, self.P, offset, innovation, variance)
        return True

    # ------------------------------------------------------------------ shared
    def _gate(self, name: str, z: float) -> bool:
        """True if the height sample may enter the fusion (always before the filter starts):
        z - H x against H P Hᵀ + σ_i² (H with the sensor's offset in the fault layer)."""
        source = self.aid[name]
        if not self.started:
            self.accept(source)
            return True
        P, row = self.P, self._height_rows[name]
        variance = P[0][0]
        if len(row) > 1:                                    # h + offset k
            k = row[1][0]
            variance = P[0][0] + 2.0 * P[0][k] + P[k][k]
        return self.gate(source, z - sparse_dot(self.x, row), variance + self.variances[name],
                         self.params.gate_sigma) is FUSED

    def _initial_covariance(self, height_variance: float) -> list[list[float]]:
        """Diagonal: ``height_variance``, then the initial variances of speed, acceleration
        and the fault layer's accelerometer bias, baro offset and GPS offset (0: known)."""
        p = self.params
        return diagonal((height_variance, p.P0_vz, p.P0_az, p.P0_acc_bias, p.P0_baro_bias,
                         0.0)[:self._n])

    def _benchmark(self, now: float) -> str | None:
        """The first live height sensor in order of decreasing sampling period (Section 4.2)."""
        oldest = now - self.params.max_sample_age
        for name, history in self.history.items():                  # in HEIGHT_SENSORS order
            if history and history[-1][0] >= oldest:
                return name
        return None

    def _fuse_heights(self, t_b: float) -> dict[str, float]:
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
        self.x[0] = self.h_fused
        decorrelate(self.P, 0, self.fused_std**2)
        self.started = True

    def _publish(self) -> None:
        self.h_est, self.vz_est, self.az_est, self.acc_bias, self.baro_bias, self.gps_bias = \
            (*self.x, 0.0, 0.0, 0.0)[:6]
        self.h_std = math.sqrt(self.P[0][0])
