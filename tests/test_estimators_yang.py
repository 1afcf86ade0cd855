"""YangFusionKF (yang2020) on synthetic data: time unification, weighted fusion, 3-state KF."""

import math

import numpy as np
import pytest
from stream_feeder import StreamFeeder

from altfusion.errors import ParameterError
from altfusion.estimators.health import Status
from altfusion.estimators.yang import (
    YangFusionKF,
    YangParams,
    unify_time,
    weighted_fusion,
)
from altfusion.physics.profiles import make_profile

PAPER_FUSED_STD = (1.0 / 30**2 + 1.0 / 20**2 + 1.0 / 10**2) ** -0.5
"""Section 3.2 with Section 4.2's sensors: 8.57 m."""


def test_time_unification_is_the_corrected_eq_5():
    """docs/papers.md: Q_tb = Q_ta + (t_b - t_a)(Q_ta - Q_tc)/(t_a - t_c) (the printed eq. 5
    multiplies by t_b instead of t_b - t_a)."""
    history = [(10.0, 100.0), (10.1, 101.2)]
    assert unify_time(history, 10.15) == pytest.approx(101.8)
    assert unify_time(history, 10.1) == 101.2
    assert unify_time(history[1:], 10.15) == 101.2  # one sample: held


def test_weighted_fusion_weights_by_inverse_variance_and_reaches_the_bound():
    y, variance, weights = weighted_fusion({"gps": 30.0, "baro": 20.0, "radar": 10.0},
                                           {"gps": 900.0, "baro": 400.0, "radar": 100.0})
    # the paper prints 8.57 m: equal to its last digit (±0.005 m)
    assert math.sqrt(variance) == pytest.approx(PAPER_FUSED_STD) == pytest.approx(8.57, abs=5e-3)
    assert weights == pytest.approx({"gps": 4 / 49, "baro": 9 / 49, "radar": 36 / 49})
    assert y == pytest.approx((4 * 30 + 9 * 20 + 36 * 10) / 49)


def paper_run(seed: int = 1):
    """Section 4 with clocks aligned (docs/papers.md): profile yang2020, GPS 30 m / 0.2 m/s every
    100 ms, baro 20 m every 10 ms, radio altimeter 10 m every 200 ms, IMU 0.01 m/s² every
    10 ms; the estimator stepped every 10 ms. Errors by source: each sensor's samples, the
    weighted fusion at each fusion, the KF at each step; and the KF's own variances."""
    rng = np.random.default_rng(seed)
    profile = make_profile("yang2020")
    estimator = YangFusionKF(step_size=0.01)
    feeder = StreamFeeder(estimator)
    errors = {name: [] for name in ("gps", "baro", "radar", "fused", "kf")}
    kf_variance = []
    for k in range(42000):
        h, vz, az = profile.reference(0.01 * (k + 1))
        samples = {"baro": {"baro_h": h + 20.0 * rng.standard_normal()},
                   "acc": {"acc_z": az + 0.01 * rng.standard_normal()}}
        if (k + 1) % 10 == 0:
            samples["gps"] = {"gps_h": h + 30.0 * rng.standard_normal(),
                              "gps_vz": vz + 0.2 * rng.standard_normal()}
        if (k + 1) % 20 == 0:
            samples["radar"] = {"radar_h": h + 10.0 * rng.standard_normal()}
        feeder.step(**samples)
        for name, sample in samples.items():
            if name in errors:
                errors[name].append(sample[f"{name}_h"] - h)
        if "radar" in samples:
            errors["fused"].append(estimator.h_fused - h)
        errors["kf"].append(estimator.h_est - h)
        kf_variance.append(estimator.h_std**2)
    return {name: np.array(e) for name, e in errors.items()}, np.array(kf_variance), estimator


@pytest.fixture(scope="module")
def paper():
    return paper_run()


def test_weighted_fusion_has_the_theoretical_accuracy(paper):
    """2100 fusions (one per radar sample) of independent errors: the sample standard
    deviation has a standard error 8.57/√(2·2100) = 0.13 m; 99.9 % interval ±0.43 m."""
    errors, _, estimator = paper
    assert len(errors["fused"]) == 2100
    assert errors["fused"].std() == pytest.approx(PAPER_FUSED_STD, abs=0.43)
    assert estimator.fused_std == pytest.approx(PAPER_FUSED_STD)
    assert estimator.weight_radar == pytest.approx(36 / 49)


def test_kalman_filter_beats_every_sensor_and_the_fusion_by_a_wide_margin(paper):
    """Eq. (15) accuracy over the flight (after the first 10 s): the KF is better than the
    weighted fusion by more than a factor 10 (0.30 m against 8.5 m for this seed)."""
    errors, _, _ = paper
    kf = float(np.sqrt(np.mean(errors["kf"][1000:] ** 2)))
    fused = float(np.sqrt(np.mean(errors["fused"] ** 2)))
    assert kf < 0.1 * fused
    assert fused < min(float(np.sqrt(np.mean(errors[s] ** 2))) for s in ("gps", "baro", "radar"))


def test_kalman_filter_std_is_honest_within_a_factor_of_two(paper):
    errors, variance, _ = paper
    ratio = math.sqrt(np.mean(errors["kf"][1000:] ** 2) / np.mean(variance[1000:]))
    assert 0.5 < ratio < 2.0


def test_time_unification_brings_delayed_samples_to_the_benchmark_time():
    """Noise-free climb at 12 m/s over terrain at 100 m: GPS stamped 50 ms and the baro 5 ms
    before the radar's sample time. Eq. (5) is exact for linear motion, so the fusion equals
    the true height at the radar's time; unaligned samples would be off by up to 0.6 m."""
    estimator = YangFusionKF(YangParams(terrain_h=100.0), step_size=0.01)
    feeder = StreamFeeder(estimator)

    def height(t):
        return 500.0 + 12.0 * t

    for k in range(200):
        t = 0.01 * (k + 1)
        samples = {"baro": {"baro_h": height(t - 0.005), "baro_time": t - 0.005}}
        if (k + 1) % 10 == 0:
            samples["gps"] = {"gps_h": height(t - 0.05), "gps_vz": 12.0, "gps_time": t - 0.05}
        if (k + 1) % 20 == 0:
            samples["radar"] = {"radar_h": height(t) - 100.0, "radar_time": t}
        feeder.step(**samples)
        if "radar" in samples and k > 20:
            assert estimator.h_fused == pytest.approx(height(t), abs=1e-9)
            assert estimator.weight_gps > 0.0 and estimator.weight_baro > 0.0


def test_fusion_falls_back_to_gps_and_baro_while_the_radar_is_out():
    rng = np.random.default_rng(2)
    estimator = YangFusionKF(step_size=0.01)
    feeder = StreamFeeder(estimator)
    for k in range(2000):
        radar_valid = k < 1000
        samples = {"baro": {"baro_h": 300.0 + 20.0 * rng.standard_normal()}}
        if (k + 1) % 10 == 0:
            samples["gps"] = {"gps_h": 300.0 + 30.0 * rng.standard_normal(), "gps_vz": 0.0}
        if (k + 1) % 20 == 0:
            samples["radar"] = {"radar_h": 300.0 + 10.0 * rng.standard_normal(),
                                "radar_valid": radar_valid}
        feeder.step(**samples)
        if k == 999:
            assert estimator.weight_radar > 0.7
    assert estimator.weight_radar == 0.0
    assert estimator.fused_std == pytest.approx((1 / 900 + 1 / 400) ** -0.5)   # 16.6 m
    assert estimator.h_est == pytest.approx(300.0, abs=3.0 * estimator.h_std)


def test_a_height_sample_far_from_the_prediction_is_rejected_and_noted():
    rng = np.random.default_rng(4)
    estimator = YangFusionKF(step_size=0.01)
    feeder = StreamFeeder(estimator)
    for k in range(1000):
        feeder.step(baro={"baro_h": 300.0 + 20.0 * rng.standard_normal()},
                    radar={"radar_h": 300.0 + 10.0 * rng.standard_normal()}
                    if (k + 1) % 20 == 0 else None)
    estimator.take_notes()
    feeder.step(baro={"baro_h": 300.0}, radar={"radar_h": 1300.0})
    assert estimator.n_rejected == 1
    assert any("radar: sample rejected" in note for note in estimator.take_notes())
    assert estimator.h_est == pytest.approx(300.0, abs=5.0)


def test_samples_without_time_stamps_are_noted_once_and_cannot_fuse():
    """A radar whose radar_time input is left unconnected (0): its samples are too old to
    take part; one note says why, and the fusion goes on with the live sensors. (Readings
    that change by a millimetre: repeated bit for bit they would be stuck.)"""
    estimator = YangFusionKF(step_size=0.01)
    feeder = StreamFeeder(estimator)
    for k in range(300):
        samples = {"baro": {"baro_h": 300.0 + 0.001 * k}}
        if (k + 1) % 20 == 0:
            samples["radar"] = {"radar_h": 300.0 + 0.001 * k, "radar_time": 0.0}
        feeder.step(**samples)
    notes = [n for n in estimator.take_notes() if "radar_time" in n]
    assert len(notes) == 1
    assert estimator.weight_radar == 0.0 and estimator.weight_baro == 1.0


@pytest.mark.parametrize(("params", "name"), [
    (YangParams(R_radar=0.0), "R_radar"),
    (YangParams(jerk_psd=0.0), "jerk_psd"),
    (YangParams(max_sample_age=-0.1), "max_sample_age"),
])
def test_invalid_parameters_are_rejected_by_name(params, name):
    with pytest.raises(ParameterError, match=f"'{name}'"):
        YangFusionKF(params)


def _mems_flight(fault_detection: bool, noise: float = 0.05, **params,
                 ) -> tuple[float, YangFusionKF]:
    """Issue 15's lock-out: a gentle 50-250 m climb over 150 s with a realistic MEMS
    accelerometer (bias 0.02 m/s², noise ``noise``, 0.05 m/s² by default) fused with the
    paper's σ_a = 0.01, a 1 m baro and a 2 m GPS (10 Hz, vertical speed 0.2 m/s); returns
    the final error."""
    estimator = YangFusionKF(YangParams(R_gps=4.0, R_baro=1.0, fault_detection=fault_detection,
                                        **params), step_size=0.01)
    feeder = StreamFeeder(estimator)
    rng = np.random.default_rng(1)
    for k in range(15000):
        phase = math.pi * (k + 1) * 0.01 / 150.0
        h = 150.0 - 100.0 * math.cos(phase)
        vz = 100.0 * math.pi / 150.0 * math.sin(phase)
        az = 100.0 * (math.pi / 150.0) ** 2 * math.cos(phase)
        samples = {"acc": {"acc_z": az + 0.02 + noise * rng.standard_normal()},
                   "baro": {"baro_h": h + rng.standard_normal()}}
        if k % 10 == 9:
            samples["gps"] = {"gps_h": h + 2.0 * rng.standard_normal(),
                              "gps_vz": vz + 0.2 * rng.standard_normal(), "gps_fix": True}
        feeder.step(**samples)
    return estimator.h_est - h, estimator


def test_an_overconfident_prediction_that_locks_the_heights_out_is_recovered():
    """The accelerometer's noise as told (0.01), its 0.02 m/s² bias unknown: the paper's
    filter (fault_detection false) drifts out of its own 5σ gate and rejects every height
    sample from then on (tens of metres off at the end). With fault_detection but neither
    bias state (an offset walk would take the drift up as a baro offset) the health
    machinery recovers it and the final error is at least 5x smaller: the GPS still agrees
    with the drifting prediction at times, so the baro is isolated and re-admitted with an
    offset (base's re-referencing) rather than the height reset (measured: 42.9 m against
    2.5 m)."""
    locked, paper = _mems_flight(False, noise=0.01)
    error, estimator = _mems_flight(True, noise=0.01, P0_acc_bias=0.0, acc_bias_psd=0.0,
                                    baro_bias_psd=0.0)
    assert paper.n_height_resets == 0 and abs(locked) > 20.0
    assert paper.acc_bias == 0.0 == paper.baro_bias
    assert estimator.baro_bias != 0.0       # no prior, no walk: only a re-reference moves d
    assert abs(error) < abs(locked) / 5.0


def test_an_accelerometer_noisier_than_told_is_measured_from_its_scatter():
    """The MEMS accelerometer's 0.05 m/s² against the paper's σ_a = 0.01: with
    fault_detection the IMU row uses the noise its samples' scatter shows (the median
    estimate over 100 samples is within ±25 % of the truth 19 times in 20: 1.96 x its
    1.2/√100 relative standard error), flagged in status, and the prediction, no longer
    overconfident, never locks the heights out, even without the bias states (measured:
    0.047 m/s², no rejection, 0.67 m off at the end against the paper's 38 m)."""
    locked, _ = _mems_flight(False)
    error, estimator = _mems_flight(True, P0_acc_bias=0.0, acc_bias_psd=0.0, baro_bias_psd=0.0)
    assert estimator.acc_check.noise == pytest.approx(0.05, rel=0.25)
    assert estimator.status & Status.BAD_ACC_VERTICAL
    assert estimator.n_rejected == 0 and estimator.n_height_resets == 0
    assert abs(error) < abs(locked) / 5.0


def test_the_accelerometer_bias_state_learns_the_bias_and_keeps_the_heights_in():
    """With fault_detection the accelerometer-bias state (PX4's, not in the paper) learns the
    0.02 m/s² bias from the GPS vertical speed: within 3 of its own standard deviations
    (measured: 0.0165 ± 0.0074), no height sample is ever rejected, no reset is needed and
    the final error lies within 3 h_std (measured: 0.06 m, h_std 0.13 m)."""
    error, estimator = _mems_flight(True)
    assert abs(estimator.acc_bias - 0.02) <= 3.0 * math.sqrt(estimator.P[3][3])
    assert estimator.n_rejected == 0 and estimator.n_height_resets == 0
    assert abs(error) <= 3.0 * estimator.h_std


def _offset_hover(fault_detection: bool, baro_drift: float = 0.0, gps_step: float = 0.0,
                  **params) -> tuple[np.ndarray, YangFusionKF]:
    """Section 4.2's sensors at 20 Hz (radar 5 Hz, GPS 10 Hz) over a 100 m hover of 400 s
    whose barometer drifts by ``baro_drift`` over 100 s from t = 100 s and whose GPS steps
    by ``gps_step`` at t = 100 s, both staying off; returns the height errors of the last
    100 s."""
    estimator = YangFusionKF(YangParams(fault_detection=fault_detection, **params),
                             step_size=0.05)
    feeder = StreamFeeder(estimator)
    rng = np.random.default_rng(3)
    errors = []
    for k in range(8000):
        t = 0.05 * (k + 1)
        drift = baro_drift * min(max(t - 100.0, 0.0), 100.0) / 100.0
        samples = {"baro": {"baro_h": 100.0 + drift + 20.0 * rng.standard_normal()},
                   "acc": {"acc_z": 0.01 * rng.standard_normal()}}
        if k % 2 == 1:
            samples["gps"] = {"gps_h": 100.0 + (gps_step if t > 100.0 else 0.0)
                              + 30.0 * rng.standard_normal(),
                              "gps_vz": 0.2 * rng.standard_normal(), "gps_fix": True}
        if k % 4 == 3:
            samples["radar"] = {"radar_h": 100.0 + 10.0 * rng.standard_normal(),
                                "radar_valid": True}
        feeder.step(**samples)
        if t > 300.0:
            errors.append(estimator.h_est - 100.0)
    return np.array(errors), estimator


def test_the_baro_offset_state_takes_up_a_drifting_barometer():
    """The paper's weighted fusion passes a 10 m baro drift into the height with the baro's
    weight 9/49 (1.8 m, four times the filter's own h_std of 0.48 m); with fault_detection
    the baro-offset state (PX4's baro bias, not in the paper) takes it up from the baro's
    disagreement with GPS and radar: over the last 100 s the mean error is below half the
    paper filter's (measured: 0.60 m against 2.24 m, the rest the offset's lag behind the
    drift at PX4's slow random walk), and the offset estimate lies within 3 of its standard
    deviations of the 10 m (measured: 10.7 ± 1.1 m)."""
    paper_errors, paper = _offset_hover(False, baro_drift=10.0)
    errors, estimator = _offset_hover(True, baro_drift=10.0)
    assert paper.baro_bias == 0.0 and abs(paper_errors.mean()) > 1.0
    assert abs(errors.mean()) < abs(paper_errors.mean()) / 2.0
    assert abs(estimator.baro_bias - 10.0) <= 3.0 * math.sqrt(estimator.P[4][4])


def test_a_gps_offset_state_takes_up_a_gps_step_the_radar_contradicts():
    """The fault suite's all_fail GNSS part: the GPS 10 m off from t = 100 s, a third of one
    sample's 30 m noise (no gate or bias test sees it). As an absolute height (gps_bias_psd
    0, the default) it enters the height with its weight against the radio altimeter; with
    a GPS offset state (gps_bias_psd at the baro offset's PX4 rate) the offset takes it up.
    Same seeded samples in both runs, so their difference is the step's share alone: over
    the last 100 s the height moves by more than 0.5 m less (measured 0.78 m here, 0.77-0.84
    m over seeds 1-6, whose noise moves either run's own mean by ±0.7 m), and the offset
    lies within 3 of its standard deviations of the 10 m (measured: 9.0 ± 1.3 m)."""
    absolute_errors, absolute = _offset_hover(True, gps_step=10.0)
    errors, estimator = _offset_hover(True, gps_step=10.0,
                                      gps_bias_psd=YangParams().baro_bias_psd)
    assert absolute.gps_bias == 0.0
    assert np.mean(absolute_errors - errors) > 0.5
    assert abs(estimator.gps_bias - 10.0) <= 3.0 * math.sqrt(estimator.P[5][5])


def test_a_gps_delay_fuses_the_gps_speed_at_its_measurement_instant():
    """A GNSS whose samples measure the vehicle gps_delay (0.1 s) before their stamp, as under
    a Jacobi or ECOS master, at a take-off's accelerations: a(t) = 10 sin(πt) m/s² for 20 s,
    GNSS (30 m, 0.2 m/s) every 0.1 s, baro 20 m and accelerometer 0.01 m/s² every 10 ms.
    Not told, the GPS speed is up to 1 m/s (δ·a) off the filter's speed: its gate rejects it
    (82 samples) and the speed error grows from 0.026 to 0.91 m/s RMS (asserted beyond 10x).
    Told, the speed is fused against v(s) = v - δ·a: no rejection and the on-time accuracy,
    up to the jerk term δ²/2·j ≤ 0.16 m/s neglected on each sample (0.030 m/s; asserted
    within 1.5x)."""
    def run(sampled_before: float, gps_delay: float) -> tuple[float, int]:
        estimator = YangFusionKF(YangParams(gps_delay=gps_delay), step_size=0.01)
        feeder, rng, errors = StreamFeeder(estimator), np.random.default_rng(5), []

        def speed(t: float) -> float:
            return 10.0 / math.pi * (1.0 - math.cos(math.pi * t))

        def height(t: float) -> float:
            return 10.0 / math.pi * (t - math.sin(math.pi * t) / math.pi)

        for n in range(2000):
            stamp = estimator.clock.time(n + 1)
            samples = {"baro": {"baro_h": height(stamp) + 20.0 * rng.standard_normal()},
                       "acc": {"acc_z": 10.0 * math.sin(math.pi * stamp)
                               + 0.01 * rng.standard_normal()}}
            if n % 10 == 9:
                instant = stamp - sampled_before
                samples["gps"] = {"gps_h": height(instant) + 30.0 * rng.standard_normal(),
                                  "gps_vz": speed(instant) + 0.2 * rng.standard_normal(),
                                  "gps_time": stamp}
            feeder.step(**samples)
            errors.append(estimator.vz_est - speed(stamp))
        return float(np.sqrt(np.mean(np.square(errors[500:])))), estimator.gps_vz_rejected

    (on_time, _), (told, told_rejected), (not_told, not_told_rejected) = (
        run(0.0, 0.0), run(0.1, 0.1), run(0.1, 0.0))
    assert told_rejected == 0 and told <= 1.5 * on_time
    assert not_told_rejected > 0 and not_told > 10.0 * on_time

