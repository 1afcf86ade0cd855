"""AltitudeEKF: one height filter for any subset of the sensors, after PX4 EKF2's height fusion.

The model, its equations and every deviation from PX4 EKF2 / ArduPilot EKF3 are written up in
``docs/altitude_ekf.md``; this docstring is the short form.

State x = [h, v, b_a, d, k, t, g]: height (m, in the datum of the reference source), vertical
speed (m/s), accelerometer bias (m/s²), the baro's offset d (m), its scale factor k (1), the
terrain height t (m) under the rangefinders and the GNSS's offset g (m). The reference source
has no offset: ``height_ref`` baro freezes d and k at 0, gps freezes g, range freezes t (PX4
EKF2: a bias estimator for every height source but the reference).

Time update over the estimator's step Δ, the accelerometer as input (PX4: the IMU drives the
prediction), a = acc_z - b_a, acc_z the mean of two samples that bound the step (else the
latest one, held):

    h⁺ = h + Δ·v + Δ²/2·a,   v⁺ = v + Δ·a,   b_a, d, k, t, g: random walks
    Q: white acceleration of PSD acc_noise²·T_acc on (h, v), T_acc the accelerometer's
       sample period, at least Δ (acc_noise inflated while the accelerometer is found bad,
       PX4's bad_acc_vertical: ``accelerometer_check``); acc_bias_psd, baro_bias_psd,
       baro_scale_psd, terrain_psd and gps_bias_psd on the others (0 on the reference's
       frozen states)

Without an accelerometer acc_z is taken as 0, so that b_a carries minus the vehicle's
acceleration: a constant-acceleration model (yang2020's eq. 11 with white jerk), b_a a random
walk of ``jerk_psd``, plus white acceleration of ``accel_psd`` on (h, v); both multiplied
by a scale raised from 1 while every source finds the prediction off, up to the bound of
``max_acceleration`` (``adaptive_motion_noise``: :mod:`~altfusion.estimators.process_noise`).

Measurements (one scalar update each, Joseph form, ``kalman.update_scalar``), each at its own
instant s ≤ now, its time stamp less the sensor's delay (``baro_delay``, ``gps_delay``,
``range_delay``; 0 by default): the state is taken back by δ = now - s along the model,
h(s) = h - δ·v + δ²/2·a and v(s) = v - δ·a, and the Jacobian row follows (H F(δ)⁻¹):

    baro:  z = h(s) + d + k·(h(s) - h_c)    (h_c: height at start; d = k = 0: height_ref baro;
           k held before the datum is pinned or while no other height source measures
           the height: ``_scale_observed``)
    GNSS height:  z = h(s) + g    (g = 0: height_ref gps),
                  σ = gps_noise·(VDOP/gps_vdop_ref)·√max(1, gps_nsat_ref/N)  (bao2017)
    GNSS vertical speed:  z = v(s);   radar, laser:  z = h(s) - t

Each sample passes the shared innovation gate (``gate_sigma``, PX4's 5σ) and health logic of
``estimators/base.py`` (isolation, height reset when every source disagrees); on top, PX4's
reset to the height reference (a reference that jumped takes the height; one returning
inconsistent after an outage is not re-admitted), a terrain reset when a rangefinder stays
inconsistent while the height is pinned by the others, and the ground constraint: once the
terrain is known an estimate below it is reset onto it, not sinking (h = t, v >= 0).

Deviations from PX4 EKF2 (reasons in docs/altitude_ekf.md):

* one joint filter on the vertical axis only, with the bias "estimators" (baro/GNSS offset,
  terrain) as states, instead of EKF2's 24 states and its separate bias filters;
* samples fused at the estimator's clock with the state taken back to their stamp (exact for
  the deterministic model, process noise over δ neglected) instead of a delayed fusion
  horizon and an output predictor;
* the height-reference fallback needs no switch: a lost source's offset state simply stops
  being observed and the remaining sources carry the height without a step;
* a GNSS reference whose innovations' mean over 30 s shows it shifted, while a rangefinder
  over a terrain known better agrees with the prediction, hands the datum over to the
  terrain and gets its offset state (``gps_handover``,
  :mod:`~altfusion.estimators.reference_handover`); EKF2 has no slow test of its reference;
* the ground-effect dead zone applies within ``ground_effect_height`` of the terrain (or of
  the starting height), not on a land detector's flag; off by default;
* each source's noise checked against its innovations (``adaptive_noise``, on by default):
  its R inflated, within [1, ``adaptive_max``], while the scatter of its innovations shows
  it too small (xu2016's bounded adaptation, on innovation differences:
  :mod:`~altfusion.estimators.noise_check`); EKF2 has none. A noise not stated (its
  ``<source>_noise`` 0, the default) is measured instead, both ways, from
  :data:`TYPICAL_NOISE` (EKF2 uses its default noises as they are); a rise of the height
  reference's factor raises the datum's variance with it (:meth:`_datum_follows_noise`);
* a filter started by another source moves its datum onto a disagreeing first sample of the
  reference, the height taking that sample's variance (EKF2 starts on its reference);
* a terrain reset takes the height's error and the sample's noise (EKF2's
  ``resetTerrainToRng`` sets the range noise alone, right against its local origin, not
  against a GNSS datum);
* PX4's conditional range aid (``range_aid``): below ``range_aid_max_height`` and while the
  rangefinders are consistent with flat terrain the terrain state is held, so the
  rangefinder pins the height (:mod:`~altfusion.estimators.range_aid`; no horizontal-speed
  condition);
* the barometer's temperature error (whang2008) is the scale-factor state k, not a
  temperature model: ``baro_p`` and ``baro_T`` are read but not fused;
* without an accelerometer, a motion model whose noise adapts to the innovations
  (PX4 EKF2 always has its IMU);
* the GNSS's slowly varying error (``gps_slow_error``, or the share of the noise its
  samples do not show) a consider variance, not a state: in ``h_std`` while the GNSS
  defines the datum, in its gate, in its bias test's mean and, stated, in its R
  (:meth:`_slow_error`).
"""

import math
from dataclasses import dataclass

from altfusion.errors import ParameterError
from altfusion.estimators.aid_source import FUSED
from altfusion.estimators.base import MAX_DELAY, Estimator, HealthParams, Verdict
from altfusion.estimators.ground_range import GroundRange
from altfusion.estimators.health import NOISE_CHECKED, STEP_BITS, UNKNOWN_STD
from altfusion.estimators.health_params import PX4_HEIGHT_BIAS_PSD
from altfusion.estimators.kalman import (
    STATE_AND_COVARIANCE,
    add_height_speed_noise,
    decorrelate,
    inflate_along,
    move_datum,
    predict_height_and_speed,
    quadratic_form,
    rederive,
    shift_state,
    update_scalar_in_place,
    update_scalar_of,
)
from altfusion.estimators.noise_check import WINDOW, NoiseCheck
from altfusion.estimators.process_noise import MotionNoise, maximum_scale
from altfusion.estimators.range_aid import RangeAid
from altfusion.estimators.reference_handover import SPAN, ReferenceHandover
from altfusion.estimators.streams import ACC, BARO_ALL, GPS_ALL, LASER, RADAR
from altfusion.params import param

H, V, BA, D, K, T, G = range(7)
N = 7
"""Indices and size of the state vector [h, v, b_a, d, k, t, g]."""

RANGEFINDERS = (("radar", RADAR), ("laser", LASER))
"""The rangefinders and their streams, in the order their samples are fused."""

HEIGHT_REFERENCES = ("gps", "baro", "range")

TYPICAL_NOISE = {"baro": 2.0, "gps": 3.0, "gps_vz": 0.5, "acc": 0.35, "radar": 1.0,
                 "laser": 0.1}
"""A small UAV's sensor noises (1σ, SI units; PX4 EKF2's defaults where it has one): where
each source's noise starts when the user states none (its ``<source>_noise`` at 0); the noise
check then measures it (:mod:`~altfusion.estimators.noise_check`)."""


def information(variance: float) -> float:
    """1/variance, the information of a measurement of that variance, 1/m²; infinite for a
    variance of 0 (a reading rounded to exact: the datum's share is then capped at 1/Var h
    where it is used, never a division by zero)."""
    return 1.0 / variance if variance > 0.0 else math.inf


@dataclass(frozen=True)
class AltitudeEKFParams(HealthParams):
    baro_noise: float = param(0.0, "m", "Baro height noise, 1σ (0: not stated: measured "
                                        "from the data, starting at 2 m)", min=0.0)
    gps_noise: float = param(0.0, "m", "GNSS height noise at VDOP 1 with enough satellites, "
                                       "1σ, the user range error (0: not stated: measured, "
                                       "starting at 3 m)", min=0.0)
    gps_vz_noise: float = param(0.0, "m/s", "GNSS vertical-speed noise, 1σ (0: not stated: "
                                            "measured, starting at PX4 EKF2_GPS_V_NOISE's "
                                            "0.5 m/s)", min=0.0)
    acc_noise: float = param(0.0, "m/s2", "Accelerometer noise per sample, 1σ (0: not "
                                          "stated: measured from its scatter, starting at "
                                          "PX4 EKF2_ACC_NOISE's 0.35 m/s2)", min=0.0)
    radar_noise: float = param(0.0, "m", "Radio-altimeter noise, 1σ (0: not stated: "
                                         "measured, starting at 1 m)", min=0.0)
    laser_noise: float = param(0.0, "m", "Laser-rangefinder noise, 1σ (0: not stated: "
                                         "measured, starting at PX4 EKF2_RNG_NOISE's 0.1 m)",
                               min=0.0)
    accel_psd: float = param(0.01, "m2/s3", "PSD of the white vertical acceleration added "
                                            "to the motion model while no accelerometer is "
                                            "fused", positive=True)
    jerk_psd: float = param(0.01, "m2/s5", "PSD of the white jerk driving the motion model's "
                                           "acceleration (state b_a) while no accelerometer is "
                                           "fused (yang2020's jerk_psd)", min=0.0)
    adaptive_motion_noise: bool = param(True, None, "Raise accel_psd and jerk_psd together "
                                                    "while every source finds the motion "
                                                    "model's prediction off (a manoeuvre), "
                                                    "back to them when it agrees again")
    max_acceleration: float = param(9.80665, "m/s2", "Largest vertical acceleration of the "
                                                     "vehicle: the adapted accel_psd stays at "
                                                     "most max_acceleration² x 1 s (1 g: a "
                                                     "free fall)", positive=True)
    acc_bias_psd: float = param(1e-5, "m2/s5", "PSD of the accelerometer-bias random walk "
                                               "(PX4 EKF2_ACC_B_NOISE 0.003 m/s³ squared)",
                                min=0.0)
    baro_bias_psd: float = param(PX4_HEIGHT_BIAS_PSD, "m2/s", "PSD of the random walk of the "
                                 "baro offset d (height_ref gps or range; PX4 EKF2's "
                                 "baro_bias_nsd 0.13 m/s/√Hz, squared)", min=0.0)
    gps_bias_psd: float = param(PX4_HEIGHT_BIAS_PSD, "m2/s", "PSD of the random walk of the "
                                "GNSS offset g (height_ref baro or range; PX4 EKF2's "
                                "gps_hgt_bias_nsd 0.13 m/s/√Hz, squared)", min=0.0)
    baro_scale_psd: float = param(1e-6, "1/s", "PSD of the random walk of the baro scale "
                                               "factor k (1e-6: about 1 % per 100 s, the "
                                               "temperature and lapse-rate error of an "
                                               "unknown baro)", min=0.0)
    terrain_psd: float = param(0.01, "m2/s", "PSD of the terrain-height random walk",
                               min=0.0)
    gps_slow_error: float = param(0.0, "m", "The GNSS height's slowly varying error, 1σ, "
                                            "beside gps_noise's white noise: its error over "
                                            "minutes (atmosphere, multipath: a Gauss-Markov "
                                            "error, GnssReceiver's gm_std) or an unknown "
                                            "constant height bias. No number of samples "
                                            "averages it away: while the GNSS defines the "
                                            "datum (height_ref gps) its variance is added to "
                                            "h_std; each sample is weighted and gated with "
                                            "it, gps_noise then the white part (0: the "
                                            "GNSS's error is white)", min=0.0)
    gps_dop_scaling: bool = param(True, None, "Scale the GNSS height noise by VDOP and the "
                                              "satellite count (bao2017)")
    gps_vdop_ref: float = param(1.0, "1", "VDOP at which gps_noise holds: the GNSS noise is "
                                          "scaled by VDOP/gps_vdop_ref", positive=True)
    gps_nsat_ref: int = param(6, None, "Satellites below which the GNSS noise grows as "
                                       "√(gps_nsat_ref/N)", min=1)
    gate_sigma: float = param(5.0, "1", "Innovation gate of every source in standard "
                                        "deviations (PX4: 5; 0: off)", min=0.0)
    gps_handover: bool = param(True, None, "A GNSS height reference whose innovations are "
                                           "found shifted over 30 s, while a rangefinder "
                                           "over a terrain known better agrees with the "
                                           "prediction, hands the datum over to the "
                                           "terrain and gets its offset state")
    height_ref: str = param("gps", None, "Height reference: gps (GNSS defines the datum, the "
                                         "baro gets offset and scale), baro (the baro defines "
                                         "it, GNSS gets the offset) or range (the terrain "
                                         "under the first range sample is the datum: held "
                                         "constant)")
    laser_max_height: float = param(25.0, "m", "The laser is fused below this range (xu2016: "
                                               "25 m)", positive=True)
    laser_min_range: float = param(0.1, "m", "The laser's shortest reading (PX4 EKF2_MIN_RNG; "
                                             "xu2016: 0.1 m): an invalid laser frame while "
                                             "the vehicle may stand on the ground reads "
                                             "between 0 and it (0: never)", min=0.0)
    starts_on_ground: bool = param(True, None, "The vehicle stands on the ground when the "
                                               "estimator starts (PX4's land detector boots "
                                               "landed): until the laser's first valid frame "
                                               "its invalid ones are read as the ground while "
                                               "the height is 2σ within the laser's reach, "
                                               "not 5σ")
    radar_max_height: float = param(5000.0, "m", "The radio altimeter is fused below this "
                                                 "range", positive=True)
    range_hysteresis: float = param(1.0, "m", "A rangefinder switched off above its "
                                              "maximum height is used again below it minus "
                                              "this", min=0.0)
    ground_effect_deadzone: float = param(0.0, "m", "Negative baro innovations down to this "
                                                    "are ignored near the ground (PX4 "
                                                    "EKF2_GND_EFF_DZ; 0: off)", min=0.0)
    ground_effect_height: float = param(1.0, "m", "Height above the terrain within which the "
                                                  "ground-effect dead zone applies", min=0.0)
    adaptive_noise: bool = param(True, None, "Check each source's noise against the scatter "
                                             "of its innovations and inflate its R while "
                                             "found too small (xu2016's bounded adaptation)")
    adaptive_window: float = param(WINDOW, "1", "Pairs of successive innovations in the "
                                               "exponential window of the noise check",
                                   min=1.0)
    adaptive_max: float = param(100.0, "1", "Largest factor of the noise check on a "
                                            "source's R (100: its σ tenfold)", min=1.0)
    range_aid: bool = param(True, None, "PX4's conditional range aid (EKF2_RNG_CTRL 1): hold "
                                        "the terrain while a rangefinder is within "
                                        "range_aid_max_height and consistent with flat "
                                        "terrain")
    range_aid_max_height: float = param(25.0, "m", "The range aid stops above this range "
                                                   "(PX4 EKF2_RNG_A_HMAX; xu2016's 25 m)",
                                        positive=True)
    acc_timeout: float = param(0.5, "s", "Without an accelerometer sample for this long the "
                                         "motion model takes over", positive=True)
    baro_delay: float = param(0.0, "s", "Time from a baro measurement to its stamp: the "
                                        "sample is fused at baro_time - baro_delay (PX4 "
                                        "EKF2_BARO_DELAY)", min=0.0, max=MAX_DELAY)
    gps_delay: float = param(0.0, "s", "Time from a GNSS measurement to its stamp (PX4 "
                                       "EKF2_GPS_DELAY; a Jacobi or ECOS master samples the "
                                       "plant one GNSS step before the stamp)",
                             min=0.0, max=MAX_DELAY)
    range_delay: float = param(0.0, "s", "Time from a radio-altimeter or laser measurement to "
                                         "its stamp (PX4 EKF2_RNG_DELAY)",
                               min=0.0, max=MAX_DELAY)
    P0_vz: float = param(25.0, "m2/s2", "Initial vertical-speed variance", positive=True)
    P0_acc_bias: float = param(0.04, "m2/s4", "Initial accelerometer-bias variance",
                               positive=True)
    P0_offset: float = param(100.0, "m2", "Variance of an offset d or g before its source's "
                                          "first sample", positive=True)
    P0_scale: float = param(1e-4, "1", "Initial variance of the baro scale factor",
                            min=0.0)
    P0_terrain: float = param(100.0, "m2", "Variance of the terrain height before the first "
                                           "range sample", positive=True)
    terrain_h: float = param(0.0, "m", "Terrain height before the first range sample (its "
                                        "prior, of variance P0_terrain)")


class AltitudeEKF(Estimator):
    """Height, vertical speed and the bias states of every sensor in one Kalman filter."""

    Params = AltitudeEKFParams
    streams = (BARO_ALL, GPS_ALL, RADAR, LASER, ACC)
    state_covariances = STATE_AND_COVARIANCE

    def configure(self, clock) -> None:
        p = self.params
        if p.height_ref not in HEIGHT_REFERENCES:
            raise ParameterError("height_ref", p.height_ref,
                                 f"must be one of {', '.join(HEIGHT_REFERENCES)}")
        if p.laser_min_range >= p.laser_max_height:
            raise ParameterError("laser_min_range", p.laser_min_range,
                                 f"must be below laser_max_height ({p.laser_max_height:g} m)")
        stated = {source: getattr(p, f"{source}_noise") for source in TYPICAL_NOISE}
        self.sensor_noise = {source: value or TYPICAL_NOISE[source]
                             for source, value in stated.items()}
        """Each source's noise, 1σ: the stated one, or the typical one where none is."""
        self.noise_stated = {source: value > 0.0 for source, value in stated.items()}
        """Whether the user stated each source's noise (else it is measured)."""

    def initialize_filter(self) -> None:
        p = self.params
        self.x = [0.0, 0.0, 0.0, 0.0, 0.0, p.terrain_h, 0.0]
        self.P = [[0.0] * N for _ in range(N)]
        baro_ref, gps_ref = p.height_ref == "baro", p.height_ref == "gps"
        for i, var in ((V, p.P0_vz), (BA, p.P0_acc_bias),
                       (D, 0.0 if baro_ref else p.P0_offset),
                       (K, 0.0 if baro_ref else p.P0_scale), (T, p.P0_terrain),
                       (G, 0.0 if gps_ref else p.P0_offset)):
            self.P[i][i] = var
        self._q_rw = [0.0, 0.0, 0.0, 0.0 if baro_ref else p.baro_bias_psd,
                      0.0 if baro_ref else p.baro_scale_psd,
                      0.0 if p.height_ref == "range" else p.terrain_psd,
                      0.0 if gps_ref else p.gps_bias_psd]
        self.h_c = 0.0
        self._acc = None                  # (stamp, value) of the last accelerometer sample
        self._acc_used = False
        self._acc_period = 0.0            # between the last two accelerometer samples
        self._offset_known = {"baro": False, "gps": False}   # set by the first sample
        self._terrain_known = False
        self._range_on = {"radar": True, "laser": True}
        self._range_rejected_since: dict[str, float] = {}
        self.noise_checks = {name: NoiseCheck(self.aid[name], p.adaptive_window,
                                              p.adaptive_max, self.noise_stated[name])
                             for name in NOISE_CHECKED if p.adaptive_noise}
        """Each checked source's noise check (none without ``adaptive_noise``)."""
        self.range_aid = RangeAid((self.aid["radar"], self.aid["laser"]), self.health.heights,
                                  p.range_aid_max_height, p.range_hysteresis) \
            if p.range_aid else None
        """PX4's conditional range aid (None without ``range_aid``)."""
        self.ground_range = GroundRange(p.laser_min_range, p.laser_max_height, p.gate_sigma,
                                        p.starts_on_ground) \
            if p.laser_min_range > 0.0 and p.gate_sigma > 0.0 else None
        """PX4's on-ground range (None without ``laser_min_range`` or a gate)."""
        self._laser_out = False           # an invalid laser frame arrived in this step
        self.handover = ReferenceHandover(name for name, _ in RANGEFINDERS) \
            if p.gps_handover and p.height_ref == "gps" and p.fault_detection else None
        """The GNSS reference's long test, for its hand-over to the terrain
        (:mod:`~altfusion.estimators.reference_handover`; None: ``gps_handover`` off, not the
        reference, handed over, or no fault layer)."""
        self._reference = p.height_ref if p.height_ref != "range" else None
        self._reference_rejected_since: float | None = None
        self._reference_sample = (0.0, 0.0, 1.0)       # its last rejected (z, stamp, σ)
        self._reference_seen = False
        self._reference_information = 0.0
        """Σ 1/R of the reference's samples fused since the datum was last set, 1/m²: the
        share of the datum's information its samples gave (:meth:`_datum_follows_noise`;
        :func:`information`)."""
        self._datum_variance = 0.0
        """The datum's variance that no sample shows, m², after the last GNSS height sample
        (nothing else moves it: :meth:`_slow_error`)."""
        self._slow_error()        # as stated, before any GNSS sample (and after a restart)
        self.n_terrain_resets = 0
        self.motion_noise = MotionNoise(
            (*self.health.heights, self.aid["gps_vz"]), maximum_scale(p.accel_psd,
                                                                p.max_acceleration),
            p.gate_sigma) if p.adaptive_motion_noise else None
        """The motion model's noise adaptation (None: ``adaptive_motion_noise`` off)."""
        self._publish()

    # ------------------------------------------------------------------ time update
    def propagate(self, dt: float) -> None:
        """Nothing here: the time update needs this step's accelerometer sample, so it runs
        first in :meth:`fuse_samples`."""

    def _predict(self, acc_sample) -> None:
        """x⁺ = F x + B a, P⁺ = F P Fᵀ + Q over one step (F P Fᵀ:
        :func:`~altfusion.estimators.kalman.predict_height_and_speed`; Q in the rows of h and
        v, then mirrored: :func:`~altfusion.estimators.kalman.add_height_speed_noise`)."""
        clock, p = self.clock, self.params
        dt, now = clock.step_size, clock.now
        previous = self._acc
        if acc_sample is not None:
            self._acc = (acc_sample["acc_time"], acc_sample["acc_z"])
            if self.acc_check is not None:
                self.acc_check.sample(self._acc[1])
            if previous is not None and self._acc[0] > previous[0]:
                self._acc_period = min(self._acc[0] - previous[0], p.acc_timeout)
        acc_on = self._acc is not None and now - self._acc[0] <= p.acc_timeout
        if acc_on and acc_sample is not None and previous is not None \
                and previous[0] >= now - dt * (1.0 + 1e-6):
            a_in = 0.5 * (previous[1] + self._acc[1])    # two samples bound the step
        else:
            a_in = self._acc[1] if acc_on else 0.0
        if self.started and acc_on != self._acc_used:
            self._switch_acceleration(acc_on)
        self._acc_used = acc_on
        if not self.started:
            return
        x, P = predict_height_and_speed(self.x, self.P, dt, a_in, BA)
        noise = self.sensor_noise["acc"] if self.acc_check is None else self.acc_check.noise
        scale = 1.0 if self.motion_noise is None else self.motion_noise.scale
        q = noise**2 * max(dt, self._acc_period) if acc_on else p.accel_psd * scale
        add_height_speed_noise(P, dt, q, self._q_rw, BA,
                               p.acc_bias_psd if acc_on else p.jerk_psd * scale)
        self.x, self.P = x, P

    def checks_own_noise(self) -> bool:
        """Its noise checks inflate R (``adaptive_noise``)."""
        return self.params.adaptive_noise

    def accelerometer_noise(self) -> float:
        """``acc_noise`` (or the typical one): checked, and inflated while found bad, with
        ``fault_detection`` (:mod:`~altfusion.estimators.accelerometer_check`)."""
        return self.sensor_noise["acc"]

    def accelerometer_noise_stated(self) -> bool:
        return self.noise_stated["acc"]

    def _switch_acceleration(self, acc_on: bool) -> None:
        """The accelerometer came or went: b_a changes meaning (its bias, or minus the
        motion model's acceleration) and restarts from its prior, uncorrelated."""
        self.x[BA] = 0.0
        for j in range(N):
            self.P[BA][j] = self.P[j][BA] = 0.0
        self.P[BA][BA] = self.params.P0_acc_bias
        self.note(f"accelerometer {'back' if acc_on else 'lost'}: "
                  f"{'its bias' if acc_on else 'the motion model'} takes state b_a")

    # ------------------------------------------------------------------ measurements
    def fuse_samples(self, samples) -> None:
        """The new samples of a step, without their stuck readings (the intake's
        :mod:`~altfusion.estimators.stuck` check; a stuck source's noise-check pair is
        broken): the prediction with the accelerometer's, then the GNSS height and speed,
        the baro and the rangefinders."""
        if self.stuck is not None:
            for source in self.stuck.found:
                if source in self.noise_checks:
                    self.noise_checks[source].forget()
        acc = samples.get(ACC)
        self._predict(acc)
        if acc is not None:
            self.accept(self.aid["acc"])
        gps = samples.get(GPS_ALL)
        if gps is not None:
            instant = gps["gps_time"] - self.params.gps_delay
            if "gps_h" in gps:
                self._fuse_height("gps", gps["gps_h"], instant, self._gps_sigma(gps))
                self._slow_error()
            if self.started and "gps_vz" in gps:
                self._fuse_speed(gps["gps_vz"], instant)
        baro = samples.get(BARO_ALL)
        if baro is not None and "baro_h" in baro:
            self._fuse_height("baro", baro["baro_h"], baro["baro_time"] - self.params.baro_delay,
                              self.sensor_noise["baro"])
        for name, stream in RANGEFINDERS:
            sample = samples.get(stream)
            if sample is None:
                continue
            reading, stamp = sample[stream.values[0]], sample[stream.time] - self.params.range_delay
            sigma = self.sensor_noise[name]
            if self.range_aid is not None and self.started:
                self.range_aid.sample(name, stamp, reading, self._noise_variance(name, sigma),
                                      self.x[V], self.P[V][V])
            if self._range_in_use(name, reading):
                self._fuse_height(name, reading, stamp, sigma)
            elif name in self.noise_checks:
                self.noise_checks[name].forget()
            if stream is LASER and self.ground_range is not None:
                self.ground_range.in_range()
        if self._laser_out:
            self._laser_out = False
            self._ground_reading()
        self._update_range_aid()
        self._ground_constraint()
        self._adapt_motion_noise()
        self._publish()

    def baro_height_sigma(self) -> float:
        """The baro height noise, with the noise check's factor."""
        return math.sqrt(self._noise_variance("baro", self.sensor_noise["baro"]))

    def gnss_height_sigma(self, sample) -> float:
        """The GNSS height noise of this ``sample``: its VDOP- and satellite-scaled σ, with
        the noise check's factor."""
        return math.sqrt(self._noise_variance("gps", self._gps_sigma(sample)))

    def _update_range_aid(self) -> None:
        """The conditional range aid decided for this step: the terrain held while it is
        active (its random walk back when it stops), ``status`` bit ``RANGE_AID``."""
        aid = self.range_aid
        if aid is None or not self.started:
            return
        if aid.update(self.clock.now):
            walk = 0.0 if self._reference is None else self.params.terrain_psd
            self._q_rw[T] = 0.0 if aid.active else walk
            self.note(f"range aid {'started: the terrain held' if aid.active else 'stopped'}")
        if aid.active:
            self.health.step_flags |= STEP_BITS.RANGE_AID

    def frame_invalid(self, stream) -> None:
        """An invalid laser frame: perhaps the vehicle on the ground (:meth:`_ground_reading`,
        in this step's fusion)."""
        if stream is LASER and self.ground_range is not None:
            self._laser_out = True

    def _ground_reading(self) -> None:
        """PX4's on-ground range: this step's invalid laser frame read as the laser between 0
        and its minimum range above the terrain, fused (as the laser's, ``status`` its FUSED
        bit) where :mod:`~altfusion.estimators.ground_range` says: the height above the
        terrain less certain than the reading and not possibly beyond the laser's reach; the
        reading within the gate and the speed a standing vehicle's, else the ground refuted
        until the laser's next valid frame; never for an isolated laser."""
        x, laser, ground = self.x, self.aid["laser"], self.ground_range
        if not self.started or laser.isolated:
            return
        y, above, row, _ = self._innovation("laser", ground.reading(), self.clock.now, 0.0)
        if not ground.tells(x[H] - x[T], above):          # above: Var(h - t)
            return
        noise = self._noise_variance("laser", self.sensor_noise["laser"])
        if not ground.judge(y, above, noise, x[V], math.sqrt(self.P[V][V])):
            return
        R = ground.noise(above, noise)
        self._terrain_known = True                        # the terrain under the laser read
        self.x, self.P = update_scalar_of(x, self.P, row, y, R, (H, V, D, K, T, G))
        self.accept(laser)

    def _adapt_motion_noise(self) -> None:
        """Without an accelerometer, the motion model's noise adapted to this step's
        innovations (:mod:`~altfusion.estimators.process_noise`) and flagged in ``status``
        while raised."""
        adaptation = self.motion_noise
        if adaptation is None or not self.started or self._acc_used:
            return
        adaptation.step(self.time)
        if adaptation.adapted:
            self.health.step_flags |= STEP_BITS.PROCESS_NOISE_ADAPTED

    def _ground_constraint(self) -> None:
        """The vehicle cannot be below the ground its rangefinders see, nor sink into it:
        once the terrain is known, an estimate with h < t is moved onto h = t, h and t each
        by its share w = (P_hh - P_ht)/Var(h - t) of the violation (the estimate projection
        of a Kalman filter with an equality constraint, on these two states), and its
        downward speed cut by the height's share (v -= w·min(v, 0): a vehicle on a known
        ground does not sink); the covariance is kept. PX4 EKF2 likewise keeps its terrain
        estimate below the vehicle. It catches the speed an accelerometer integrates
        through a touchdown whose impact it misses (the vehicle model stops without one)
        while a rangefinder below its minimum range delivers nothing; a pseudo-measurement
        instead lets the accelerometer-bias state explain the repeated corrections."""
        x, P = self.x, self.P
        if not (self.started and self._terrain_known) or x[H] >= x[T]:
            return
        variance = P[H][H] - 2.0 * P[H][T] + P[T][T]
        if variance <= 0.0:
            return
        share = min(max((P[H][H] - P[H][T]) / variance, 0.0), 1.0)
        below = x[T] - x[H]
        x[H] += share * below
        x[T] -= (1.0 - share) * below
        x[V] -= share * min(x[V], 0.0)

    def _gps_sigma(self, sample) -> float:
        """σ_G = gps_noise·(VDOP/gps_vdop_ref)·√max(1, N_ref/N) (bao2017's η; VDOP or N
        not given: factor 1)."""
        p = self.params
        if not p.gps_dop_scaling:
            return self.sensor_noise["gps"]
        vdop = sample["gps_vdop"] / p.gps_vdop_ref if sample["gps_vdop"] > 0.0 else 1.0
        nsat = sample["gps_nsat"]
        return self.sensor_noise["gps"] * vdop * math.sqrt(max(1.0, p.gps_nsat_ref / nsat)
                                              if nsat > 0 else 1.0)

    def _range_in_use(self, name: str, reading: float) -> bool:
        """A rangefinder is fused below its maximum height, with hysteresis."""
        p = self.params
        top = p.laser_max_height if name == "laser" else p.radar_max_height
        on = self._range_on[name]
        on = reading <= top if on else reading <= top - p.range_hysteresis
        if on != self._range_on[name]:
            self.note(f"{name}: {'used' if on else 'not used'} at a reading of {reading:.3g} m")
            self._range_on[name] = on
        return on

    def _back(self, stamp: float) -> tuple[float, float, list[tuple[int, float]], float]:
        """The state taken back to ``stamp``: h(s), v(s), the Jacobian row of h(s) on the
        present state, and δ (≥ 0: a sample is never fused before its stamp)."""
        delta = max(0.0, self.clock.now - stamp)
        x = self.x
        if delta == 0.0:
            return x[H], x[V], [(H, 1.0)], 0.0
        a = (self._acc[1] if self._acc_used else 0.0) - x[BA]
        row = [(H, 1.0), (V, -delta), (BA, -0.5 * delta * delta)]
        return x[H] - delta * x[V] + 0.5 * delta * delta * a, x[V] - delta * a, row, delta

    def _innovation(self, source: str, z: float, stamp: float, R: float
                    ) -> tuple[float, float, list[tuple[int, float]], list[tuple[int, float]]]:
        """A height sample's innovation y = z - h(x(s)) at its stamp s, its variance
        S = H P Hᵀ + R + the slow error's share in S (:meth:`_slow_shares`), its Jacobian
        row H and that of h(s) (``R``: the sample's noise variance in use)."""
        h_s, _, row_h, _ = self._back(stamp)
        predicted, row = self._model(source, h_s, row_h)
        return (z - predicted, quadratic_form(self.P, row) + R + self._slow_shares(source)[1],
                row, row_h)

    def _model(self, source: str, h_s: float, row_h) -> tuple[float, list[tuple[int, float]]]:
        """The predicted measurement of a height source and its Jacobian row."""
        x, ref = self.x, self._reference
        if source in ("radar", "laser"):
            return h_s - x[T], [*row_h, (T, -1.0)]
        if source == "baro" and ref != "baro":
            scale = 1.0 + x[K]
            row = [*((i, scale * c) for i, c in row_h), (D, 1.0)]
            if self._scale_observed():
                row.append((K, h_s - self.h_c))
            return h_s + x[D] + x[K] * (h_s - self.h_c), row
        if source == "gps" and ref != "gps":
            return h_s + x[G], [*row_h, (G, 1.0)]
        return h_s, list(row_h)

    def _scale_observed(self) -> bool:
        """Whether the baro's scale factor k is observed: once the datum is pinned (the
        height reference has delivered: the GNSS's first sample, or the terrain under the
        first range sample with ``height_ref`` range), while another height source (the
        GNSS, a rangefinder) was fused within ``reset_timeout``, measuring the height's
        changes the scale multiplies. The baro alone sees h + d + k·(h - h_c) and no sample
        tells k from a height change; with no datum, every source's offset free, nothing
        tells the height's level apart from the offsets'. Either way, linearized at the
        estimate, the product k·(h - h_c) made k, and with it the level, look observed: h
        and the offsets walked apart along the direction no source sees while P shrank
        (measured: a baro alone, told nothing, on a 10-55 m flight, the height 128 m off at
        h_std 6.4 m within 12 s; the SITL log with ``height_ref`` range and no
        rangefinder, 16 m off at 4.3 m). So k is left out of the baro's Jacobian row then
        (its random walk goes on). PX4 EKF2 has no scale factor, and estimates no baro bias
        while the baro is its height reference, its fall-back without GNSS."""
        if not (self._reference_seen if self._reference is not None else self._terrain_known):
            return False
        now, window = self.time, self.params.reset_timeout
        return any(now - source.last_fused <= window for source in self.health.heights
                   if source.name != "baro")

    def _fuse_height(self, source: str, z: float, stamp: float, sigma: float) -> None:
        R = self._noise_variance(source, sigma)
        if not self.started:
            self._start(source, z, R)
            return
        if self._first_sample(source, z, R):
            return
        y, S, row, row_h = self._innovation(source, z, stamp, R)
        if source == "baro":
            y = self._ground_effect(y)
        slow_R, slow_S = self._slow_shares(source)
        if source in ("radar", "laser") and self._terrain_step(source, y, S, row_h, R):
            return
        if source == self._reference:
            if self._reference_step(source, y, S):
                return
            self._reference_sample = (z, stamp, sigma)
        elif self._reference_first(y, S):
            self._fuse_height(source, z, stamp, sigma)     # sets its offset anew
            return
        fused = self._gate_checked(source, y, S, R, slow_S)
        if fused:
            self._range_rejected_since.pop(source, None)
            if source == self._reference:
                self._reference_rejected_since = None
            update_scalar_in_place(self.x, self.P, row, y, R + slow_R)
            if source == self._reference:
                self._reference_information += information(R + slow_R)
        if self.handover is not None:
            self._judge_reference(source, y, S, fused)
        if source == self._reference:
            self._datum_follows_noise()

    def _fuse_speed(self, vz: float, stamp: float) -> None:
        _, v_s, _, delta = self._back(stamp)
        row = [(V, 1.0)]
        if delta > 0.0:
            row.append((BA, delta))
        R = self.sensor_noise["gps_vz"] ** 2 * self._adaptation("gps_vz")
        y = vz - v_s
        S = self.P[V][V] + (2.0 * delta * self.P[V][BA] + delta * delta * self.P[BA][BA]
                            if len(row) > 1 else 0.0) + R
        if self._gate_checked("gps_vz", y, S, R):
            update_scalar_in_place(self.x, self.P, row, y, R)

    def _ground_effect(self, y: float) -> float:
        """PX4's ground-effect dead zone: near the ground a negative baro innovation down to
        ``ground_effect_deadzone`` is ignored (the rotor wash lowers the static pressure)."""
        p = self.params
        ground = self.x[T] if self._terrain_known else self.h_c
        if p.ground_effect_deadzone > 0.0 and self.x[H] - ground <= p.ground_effect_height \
                and y < 0.0:
            return min(0.0, y + p.ground_effect_deadzone)
        return y

    def _terrain_step(self, source: str, y: float, S: float, row_h, R: float) -> bool:
        """Range consistency: a rangefinder rejected for ``reset_timeout`` while the height is
        aided by others has seen the terrain change (a step, a box): the terrain resets
        onto it, t = h(s) - z (counted in ``n_terrain_resets``). True if it did.

        With ``height_ref`` range the terrain is the datum (variance 0). Otherwise t takes
        the height's error and the sample's noise: Var(t) = row_h P row_hᵀ + R and
        Cov(t, x) = row_h P, the covariance of the reset (PX4 EKF2's ``resetTerrainToRng``
        sets the range noise and no correlations, right for its local frame's origin but,
        against a GNSS datum, a terrain as precise as the range while the height is known to
        metres: measured, a 5 mm laser's reset left ``h_std`` 0.14 m with the height 2.4 m
        off)."""
        p = self.params
        if p.gate_sigma <= 0.0 or y * y <= p.gate_sigma**2 * S:
            return False
        since = self._range_rejected_since.setdefault(source, self.time)
        if self.time - since < p.reset_timeout or not self.contradicted(self.aid[source], y):
            return False
        self._range_rejected_since.pop(source)
        self.x[T] -= y
        if self._reference is None:                     # the terrain is the datum
            decorrelate(self.P, T, 0.0)
        else:
            rederive(self.P, T, row_h, R)
        self.n_terrain_resets += 1
        for name, _ in RANGEFINDERS:                     # both rangefinders' predictions moved
            if name in self.noise_checks:
                self.noise_checks[name].forget()
        self.note(f"{source}: inconsistent for {p.reset_timeout:g} s while the height is "
                  f"aided: terrain reset by {-y:.3g} m")
        self.accept(self.aid[source])
        return True

    def _reference_step(self, source: str, y: float, S: float) -> bool:
        """PX4's reset to the height reference: the reference source, fused until its
        samples jumped, rejected for ``reset_timeout``, takes the height with it (the other
        sources' offsets are learnt anew), unless another source fused within
        ``reset_timeout`` pins the height tighter than the jump (``contradicted``): then the
        reference is the faulty one and is isolated (the fault suite's gnss_step). A
        reference returning inconsistent after an outage (not fused for ``reset_timeout``
        before its first rejection) is not re-admitted: it stays rejected and, contradicted
        by the sources that carried the height, isolated.
        True if the height was reset."""
        p = self.params
        if not p.fault_detection or p.gate_sigma <= 0.0 or y * y <= p.gate_sigma**2 * S:
            return False
        now = self.time
        if self._reference_rejected_since is None:
            in_use = now - self.aid[source].last_fused <= p.reset_timeout
            self._reference_rejected_since = now if in_use else math.inf
        if now - self._reference_rejected_since < p.reset_timeout \
                or self.contradicted(self.aid[source], y):
            return False
        self._reset_to_reference(y, S)
        return True

    def _reference_first(self, y: float, S: float) -> bool:
        """With every height source rejected for ``reset_timeout`` (the base's height reset)
        while the reference delivers, the height resets onto the reference's last sample,
        not onto whichever source comes first (PX4 *AllHgtFailReset). True if it did."""
        p = self.params
        since = self._reference_rejected_since
        if not (p.fault_detection and since is not None and math.isfinite(since)
                and self.time - self.health.last_aiding >= p.reset_timeout
                and y * y > p.gate_sigma**2 * S):
            return False
        z, stamp, sigma = self._reference_sample
        y_ref, S_ref, _, _ = self._innovation(self._reference, z, stamp,
                                              self._noise_variance(self._reference, sigma))
        self._reset_to_reference(y_ref, S_ref)
        return True

    def _judge_reference(self, source: str, y: float, S: float, fused: bool) -> None:
        """The GNSS reference's long test (:mod:`~altfusion.estimators.reference_handover`)
        told the gated sample of ``source`` (it keeps the GNSS's and the rangefinders'); at
        a fused GNSS sample, the datum handed over if the test finds the GNSS shifted."""
        handover = self.handover
        handover.gated(source, self.time, y, S, fused)
        if source != "gps" or not fused:
            return
        rangefinder = handover.shifted(self.time, self.aid, self.params.reset_timeout,
                                       self.P[T][T])
        if rangefinder is not None:
            self._hand_over(rangefinder, handover.reference.mean())

    def _hand_over(self, rangefinder: str, shift: float) -> None:
        """The GNSS, the height reference, found ``shift`` m off over the long test's span
        while ``rangefinder`` over the terrain agrees with the prediction: the terrain
        becomes the datum (frozen, as with ``height_ref`` range) and the GNSS gets its
        offset g, at ``shift`` with the offsets' prior variance ``P0_offset`` and its random
        walk ``gps_bias_psd``; its bias window and noise-check pair start anew. What its
        samples taught the height is withdrawn: their share of 1/Var h
        (:meth:`_datum_follows_noise`'s I) leaves the height, along with the offsets of the
        other sources (so that their predictions stay), at most ``shift``² more uncertain
        (the most the GNSS can have moved it). Once: the handover is dropped."""
        p, P = self.params, self.P
        self.note(f"gps: its innovations {shift:.3g} m off over {SPAN:g} s while the "
                  f"{rangefinder} agrees: the datum handed over to the terrain, the GNSS "
                  f"given its offset")
        direction = self._datum_direction()
        direction[T] = direction[G] = 0.0
        self._withdraw_reference_share(math.inf, direction, P[H][H] + shift * shift)
        self.x[G] = shift
        decorrelate(P, G, p.P0_offset)
        self._q_rw[G], self._q_rw[T] = p.gps_bias_psd, 0.0
        self._offset_known["gps"] = True
        self._reference = self.handover = self._reference_rejected_since = None
        self._datum_variance = 0.0
        self.aid["gps"].window.clear()
        if "gps" in self.noise_checks:
            self.noise_checks["gps"].forget()

    def _reset_to_reference(self, y: float, S: float) -> None:
        self._reference_rejected_since = None
        self.height_reset(self.aid[self._reference], y, S, f"the height reference rejected for "
                                                 f"{self.params.reset_timeout:g} s")

    def _noise_variance(self, source: str, sigma: float) -> float:
        """R of a ``source`` sample of noise ``sigma``: σ² times its noise check's factor."""
        return sigma * sigma * self._adaptation(source)

    def _adaptation(self, source: str) -> float:
        """The factor on ``source``'s R of its noise check (1: off)."""
        check = self.noise_checks.get(source)
        return 1.0 if check is None else check.factor

    def _gate_checked(self, source: str, y: float, S: float, R: float,
                      slow: float = 0.0) -> bool:
        """The gate of ``source`` (True: fused), its noise check told the verdict (and the
        sample's noise variance R; S less the ``slow`` error it holds, which successive
        innovations do not show: :meth:`_slow_error`)."""
        verdict = self.gate(self.aid[source], y, S, self.params.gate_sigma)
        check = self.noise_checks.get(source)
        if check is not None:
            if verdict in (Verdict.FUSED, Verdict.REJECTED):
                check.gated(y, S - slow, R)
            else:
                check.forget()
        return verdict is FUSED

    # ------------------------------------------------------------------ start and resets
    def _offset_index(self, source: str) -> int | None:
        """The state that offsets ``source``'s reading from the height: z = h + d (baro),
        z = h + g (GNSS), z = h - t (rangefinders); None for the height reference."""
        if source in ("radar", "laser"):
            return T
        if source == self._reference:
            return None
        return D if source == "baro" else G

    def _start(self, source: str, z: float, R: float) -> None:
        """The first height sample (of variance R) starts the filter: h = z less the source's
        offset (its prior), with the offset's prior variance in Var h and their correlation."""
        x, P = self.x, self.P
        offset = self._offset_index(source)
        x[H] = z
        P[H][H] = R
        if offset == T and self._reference is None:
            P[T][T] = 0.0                                 # the terrain is the datum
        if offset is not None:
            sign = -1.0 if offset == T else 1.0           # z = h + sign·offset
            x[H] = z - sign * x[offset]
            P[H][H] += P[offset][offset]
            P[H][offset] = P[offset][H] = -sign * P[offset][offset]
            if offset == T:
                self._terrain_known = True
            else:
                self._offset_known[source] = True
        self.h_c = x[H]
        self._reference_seen = source == self._reference
        self._reference_information = information(R) if self._reference_seen else 0.0
        self.started = True
        self.accept(self.aid[source])

    def _first_sample(self, source: str, z: float, R: float) -> bool:
        """The first sample of the reference after a start from another source: see
        :meth:`_first_reference`. The first sample of the source of an offset state (d, g
        or the rangefinders' t) that disagrees with the state's prior (``P0_offset``,
        ``P0_terrain``: beyond the gate) sets that state (d = z - h, g = z - h or
        t = h - z, uncorrelated, Var = Var h + R) and is consumed; one that agrees is fused
        as any sample (a calibrated baro, a known terrain). Over a terrain told (its prior
        known better than both the height and the range sample) the disagreement is the
        height's: the height moves onto the sample instead, h = z + t (:meth:`reset_height`,
        Var h = Var t + R; the offsets d and g learnt anew), and the terrain stays.
        (Else a 30 m GNSS told 6 m, starting the filter 28 m off on the ground, had the
        radar's first sample take the told terrain to 28 m, and the height stayed 2-3 m off
        at an ``h_std`` of 1 m: docs/altitude_ekf.md.) The offsets' default priors and an unknown
        terrain's are vague (a GNSS datum at sea level over a terrain at 400 m) and do
        not move the height. With ``height_ref`` range the terrain is the datum from the
        first range sample on (variance 0): set by it if it disagrees with the prior, else
        the prior itself. True if consumed."""
        if source == self._reference and not self._reference_seen:
            self._reference_seen = True
            return self._first_reference(z, R)
        index = self._offset_index(source)
        if index == T and not self._terrain_known:
            self._terrain_known = True
        elif index in (D, G) and not self._offset_known[source]:
            self._offset_known[source] = True
        else:
            return False
        value = self.x[H] - z if index == T else z - self.x[H]
        sigmas = self.params.gate_sigma
        y = value - self.x[index]                         # against the state's prior
        consistent = y * y <= sigmas * sigmas * (self.P[index][index] + self.P[H][H] + R)
        frozen = index == T and self._reference is None
        if consistent and not frozen:
            return False                                  # fused as any sample
        if index == T and not (consistent or frozen) \
                and self._terrain_told(R):                # h onto z + t
            self.reset_height(source, -y, self.P[T][T] + R)
            self.note(f"{source}: first sample {-y:.4g} m from the height over the terrain "
                      f"told: height moved onto it")
            self.accept(self.aid[source])
            return True
        for j in range(N):
            self.P[index][j] = self.P[j][index] = 0.0
        if consistent:
            return False                                  # the datum: its prior
        self.x[index] = value
        self.P[index][index] = 0.0 if frozen else self.P[H][H] + R
        self.accept(self.aid[source])
        return True

    def _terrain_told(self, noise_variance: float) -> bool:
        """Whether the terrain's prior is known better than the height and than a sample of
        that ``noise_variance``: a disagreement between them is the height's (or the
        sample's), not the terrain's (:meth:`_first_sample`, :meth:`_first_reference`)."""
        return self.P[T][T] < min(self.P[H][H], noise_variance)

    def _first_reference(self, z: float, R: float) -> bool:
        """The reference's first sample (of variance R) after a start from another source sets
        the datum: if it disagrees with the height (beyond the gate), h moves onto it and the
        offsets a sample has set (d, g, t) move with it, so that those sources' predictions
        stay where they were (a lidar at 0 m, then GNSS at 429 m MSL: the terrain becomes
        429 m - range); an offset still at its prior stays (:meth:`_datum_direction`). The height's
        error is then the sample's (variance R, its old error forgotten) and the moved
        states keep their errors relative to it (:func:`~altfusion.estimators.kalman.
        move_datum`); the sample is consumed. One that agrees is fused as any sample, and so
        is one over a terrain told that a rangefinder has tied the height to (the terrain's
        prior known better than the height and than the reference's stated or typical
        noise, as in :meth:`_first_sample`; not than R, which a noise not stated starts
        100-fold above): the told terrain is in the reference's datum, so the height is
        known in it already. (Else, with the vehicle presumed on the ground, the GNSS's
        first sample of the fault flight told x0.2, 30 m off against a told 6 m, moved the
        datum and the told terrain with it: the height 1-3.6 m off for the flight, RMS 2.1 m
        against 0.83 m. Against R, the Auterion log told nothing, started on its lidar over
        the default terrain prior of 10 m, kept that datum and rejected its GNSS, 423 m
        off, 179 times.) True if consumed."""
        h_s, _, row_h, _ = self._back(self.time)
        predicted, row = self._model(self._reference, h_s, row_h)
        y = z - predicted
        S = quadratic_form(self.P, row) + R
        told = self._terrain_known and self._terrain_told(self.sensor_noise[self._reference] ** 2)
        if told or y * y <= self.params.gate_sigma**2 * S:
            return False
        direction = self._datum_direction()
        self.x = [xi + ui * y for xi, ui in zip(self.x, direction, strict=True)]
        move_datum(self.P, H, direction, R)
        self._reference_information = information(R)
        self.note(f"{self._reference}: first sample of the height reference {y:.4g} m from "
                  f"the height: datum moved onto it")
        self.accept(self.aid[self._reference])
        return True

    def _datum_direction(self) -> list[float]:
        """u: how the states move with the datum (h and t by +1, the offsets d and g of the
        sources other than the reference by -1): x + u·δ predicts every source's reading as x
        does, but the reference's, which moves by δ. An offset no sample has set yet stays
        (0): its prior is relative to the reference's datum (``terrain_h``, an offset of 0),
        and no reading of its source is there to keep. (Measured on the Auterion log told
        nothing: started on the lidar, the GNSS moved the datum by 423 m and took the baro's
        unset d along, so that the baro's first sample, 269 m from that prediction, was
        rejected, and so was every later one.)"""
        direction = [0.0] * N
        direction[H] = 1.0
        if self._terrain_known:
            direction[T] = 1.0
        for source in ("baro", "gps"):
            offset = self._offset_index(source)
            if offset is not None and self._offset_known[source]:
                direction[offset] = -1.0
        return direction

    def _datum_follows_noise(self) -> None:
        """The reference's noise check raised its factor above its earlier peak by r: what
        its samples taught the datum is that much less certain. Of the datum's information
        1/Var h, the share I its samples gave (Σ 1/R since the datum was set, at most
        1/Var h) falls to I/r, the rest (the offsets' priors: a calibrated baro, a terrain
        told) stays (:meth:`_withdraw_reference_share`), along the datum direction: every
        difference the other sources see unchanged. (A noise stated x0.2 or not stated
        would otherwise leave the first samples' average, weighted as precise, with an
        ``h_std`` of the stated noise for minutes.) The whole Var h times r, right only where
        the reference alone placed the datum, took the priors' share for the reference's: a
        GNSS not stated, its first pair's bound 30x its start, lifted xu2016_hover15's
        ``h_std`` from the baro offset's 10 m to 52 m (docs/altitude_ekf.md has the
        figures)."""
        check = self.noise_checks.get(self._reference)
        if check is not None and check.rise > 1.0:
            self._withdraw_reference_share(check.rise, self._datum_direction())

    def _withdraw_reference_share(self, rise: float, direction: list[float],
                                  limit: float = math.inf) -> None:
        """What the reference's samples taught the height made ``rise`` times less certain
        (r ≥ 1; infinite: withdrawn): of 1/Var h their share I (Σ 1/R since the datum was
        set, at most 1/Var h) falls to I/r, Var h ← 1/(1/Var h - I·(1 - 1/r)), at most
        ``limit``, added along ``direction``
        (:func:`~altfusion.estimators.kalman.inflate_along`). For a rise of the reference's
        noise (:meth:`_datum_follows_noise`) and its hand-over (:meth:`_hand_over`)."""
        variance = self.P[H][H]
        if variance <= 0.0:
            return
        shown = min(self._reference_information, 1.0 / variance)
        remaining = 1.0 / variance - shown * (1.0 - 1.0 / rise)
        grown = min(1.0 / remaining if remaining > 0.0 else math.inf, limit)
        inflate_along(self.P, direction, grown - variance)
        self._reference_information = shown / rise

    def _slow_error(self) -> None:
        """After each GNSS height sample, the variance of the GNSS's slow error
        (:meth:`_slow_variance`) where it belongs. The filter takes the GNSS's error as
        white: averaging its samples makes the datum look ever more certain, its innovations'
        mean over a few seconds looks biased, and a precise receiver's wander is followed as
        motion; while the error of a real receiver's height wanders over minutes (its
        Gauss-Markov part, correlation times of minutes to hours) and every sample of that
        time shares it. So:

        * the gate and each sample's R (:meth:`_slow_shares`);
        * the bias test's window: its mean is uncertain by at least the whole slow error
          (:attr:`~altfusion.estimators.aid_source.InnovationWindow.shared`);
        * while the GNSS defines the datum (the height reference, once its first sample is
          in), ``h_std``: the datum is as uncertain, however many samples were averaged.

        Measured on a hover (``tests/gnss_flights.py``: 0.1 m baro at 50 Hz; a GNSS at 10 Hz
        read to 0.1 m with a 0.5 m / 30 s Gauss-Markov error): told nothing, 206-624 of its
        1200 samples rejected and the GNSS isolated for 6.4-47.5 s before (the slow error in
        ``h_std`` only), none now; told 0.05 m white and 0.5 m slow, 516-775 and 33.6-67.2 s
        before, none now.
        Deviation (PX4 EKF2 has none): not a Gauss-Markov state, which would average the
        error down over flights much longer than its correlation time while the baro holds
        the height; bounded above by its full variance instead."""
        slow = self._slow_variance()
        self.aid["gps"].window.shared = slow
        if self.handover is not None:
            self.handover.reference.shared = slow
        self._datum_variance = slow if self._reference == "gps" and self._reference_seen \
            else 0.0

    def _slow_shares(self, source: str) -> tuple[float, float]:
        """The shares of ``source``'s slow error (:meth:`_slow_error`; the GNSS's, 0 for
        the others) in its samples' R and in their gate's innovation variance S, m²:

        * R takes the stated ``gps_slow_error``² (the gain: a stated slow error is not
          followed as motion), ``gps_noise`` then being the white part;
        * S takes it too (a sample that far off is the receiver's own wander, not a fault)
          and, where ``gps_noise`` is not stated (R is then the white noise measured), the
          whole slow variance, the share inferred from the typical receiver's noise
          included; that share widens the gate only: a white GNSS told nothing is weighted
          as precisely as it shows. A stated ``gps_noise`` beyond what its samples show (a
          datasheet's σ, the whole error) has the slow part in R already."""
        if source != "gps":
            return 0.0, 0.0
        stated = self.params.gps_slow_error ** 2
        return stated, (stated if self.noise_stated["gps"] else self.aid["gps"].window.shared)

    def _slow_variance(self) -> float:
        """The variance of the GNSS height's slowly varying error, m²: ``gps_slow_error``²,
        or, larger, the share of the stated ``gps_noise``'s variance its successive
        innovations do not show (:meth:`~altfusion.estimators.noise_check.NoiseCheck.
        unshown`: a datasheet's σ stated for a receiver whose samples scatter far less)."""
        slow = self.params.gps_slow_error ** 2
        check = self.noise_checks.get("gps")
        if check is None:
            return slow
        return max(slow, check.unshown() * self.sensor_noise["gps"] ** 2)

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """Height (or, for the GNSS speed, the speed) onto the sample; its variance the
        innovation's, its correlations zero (PX4's height and velocity resets). After a
        height reset the offset d and the terrain are set anew by their sources' next
        samples, unless the reset was onto that source."""
        i = V if source == "gps_vz" else H
        shift_state(self.x, self.P, i, innovation, variance)
        if i == H:
            self._reference_information = information(variance) \
                if source == self._reference else 0.0
        for check in self.noise_checks.values():       # every prediction moved
            check.forget()
        if i == H:                        # the other sources' offsets: learnt anew
            for owner, known in self._offset_known.items():
                self._offset_known[owner] = known and source == owner
            self._terrain_known = self._terrain_known and source in ("radar", "laser")
        self._publish()

    def _publish(self) -> None:
        x, P = self.x, self.P
        self.h_est, self.vz_est = x[H], x[V]
        self.h_std = math.sqrt(max(P[H][H], 0.0) + self._datum_variance) if self.started \
            else UNKNOWN_STD
        self.vz_std = math.sqrt(max(P[V][V], 0.0))
        self.acc_bias = x[BA] if self._acc_used else 0.0
        self.baro_bias = x[D]
        self.gps_bias = x[G]
        self.baro_scale = x[K]
        self.terrain_est = x[T]
        self.terrain_std = math.sqrt(max(P[T][T], 0.0))
