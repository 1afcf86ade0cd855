"""The accelerometer checked against the height sources (PX4 EKF2's bad_acc_vertical) and by
its own scatter: the checks on hand-made evidence, then AltitudeEKF on a hover whose
accelerometer is 40x noisier than it is told (the hover of tests/test_altitude_ekf.py)."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from altfusion.estimators import accelerometer_check as check
from altfusion.estimators.accelerometer_check import AccelerometerCheck
from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.health import Status

sys.path.insert(0, str(Path(__file__).parent))
from test_altitude_ekf import STEP, TRUE_H, Flight  # noqa: E402

DT = 0.02


def judge(name: str, mean: float, sigma: float, now: float = 0.0) -> AidSource:
    """An aid source gated at ``now`` whose bias window holds 25 innovations of mean
    ``mean`` with a standard deviation of that mean of ``sigma``."""
    source = AidSource(name)
    variance = 25.0 * sigma**2           # the mean of 25 samples: S/25 = sigma²
    for k in range(25):
        source.window.add(now - 0.1 * (24 - k), mean, variance, 2.5)
    source.innovation, source.variance, source.last_gated = mean, variance, now
    return source


def run(judges: tuple[AidSource, ...], seconds: float, acc: AccelerometerCheck,
        start: float = 0.0) -> float:
    """Step ``acc`` for ``seconds`` with ``judges`` as they are (gated at every step)."""
    acc.judges = judges
    now = start
    for _ in range(round(seconds / DT)):
        now += DT
        for source in judges:
            source.last_gated = now
        acc.step(now)
    return now


def test_two_height_sources_off_on_one_side_inflate_the_noise_and_flag_it():
    """Baro and GNSS means 10 standard deviations off, the same side: after WINDOW·ln 2
    (the fraction's exponential average passes 1/2) the noise is GROWTH x the stated, and
    GROWTH again ESCALATION later while the evidence stays."""
    acc = AccelerometerCheck(0.05, ())
    judges = (judge("baro", 1.0, 0.1), judge("gps", 2.0, 0.2))
    run(judges, 0.6, acc)
    assert acc.noise == 0.05 and not acc.bad                 # 0.6 s < ln 2 = 0.69 s
    run(judges, 0.2, acc, 0.6)
    assert acc.noise == pytest.approx(0.05 * check.GROWTH, rel=1e-3)   # decaying since
    assert acc.bad and acc.suspect
    run(judges, check.ESCALATION, acc, 0.8)
    assert acc.noise == pytest.approx(0.05 * check.GROWTH**2, rel=1e-2)   # 3 s of decay


@pytest.mark.parametrize("judges", [
    (("baro", 1.0, 0.1), ("gps", -2.0, 0.2)),                # opposite sides: a source is off
    (("radar", 1.0, 0.1), ("laser", 1.0, 0.01), ("baro", 0.5, 3.0)),   # a terrain step
    (("baro", 1.0, 0.1), ("gps", 2.0, 0.2), ("laser", 0.0, 0.01)),     # the laser agrees
    (("baro", 1.0, 0.1),),                                    # one source alone
], ids=["opposite-sides", "rangefinders-are-one-judge", "a-precise-source-agrees",
        "one-source"])
def test_disagreements_that_do_not_point_at_the_accelerometer(judges):
    acc = AccelerometerCheck(0.05, ())
    run(tuple(judge(*j) for j in judges), 10.0, acc)
    assert acc.noise == 0.05 and not acc.bad and not acc.suspect


def test_the_gnss_speed_counts_whatever_its_sign_and_the_coarse_gnss_cannot_clear():
    """Baro 10σ off and the GNSS speed 5σ off the other way: two judges (a noisy
    accelerometer's speed and height errors need not share a sign); a 30 m GNSS that sees
    nothing does not pin the height to better than the baro's 1 m."""
    acc = AccelerometerCheck(0.05, ())
    speed = AidSource("gps_vz")
    speed.innovation, speed.variance = -0.5, 0.01
    run((judge("baro", 1.0, 0.1), judge("gps", 0.0, 6.0), speed), 1.0, acc)
    assert acc.bad


def test_the_inflation_decays_to_the_stated_noise():
    """Consistent again: the inflation (noise - stated) decays with the time constant DECAY,
    and the flag clears below BAD x the stated noise."""
    acc = AccelerometerCheck(0.05, ())
    run((judge("baro", 1.0, 0.1), judge("gps", 2.0, 0.2)), 1.0, acc)
    inflated = acc.noise
    now = run((judge("baro", 0.0, 0.1), judge("gps", 0.0, 0.2)), 30.0, acc, 1.0)
    expected = 0.05 + (inflated - 0.05) * math.exp(-30.0 / check.DECAY)
    assert acc.noise == pytest.approx(expected, rel=1e-3) and acc.bad
    seconds = check.DECAY * math.log((inflated - 0.05) / (0.05 * (check.BAD - 1.0)))
    run((judge("baro", 0.0, 0.1), judge("gps", 0.0, 0.2)), seconds - 30.0 + 1.0, acc, now)
    assert not acc.bad


def scattered(acc: AccelerometerCheck, values: np.ndarray) -> AccelerometerCheck:
    """Feed ``values`` to ``acc`` as samples every DT (no judges), checking at every one."""
    for k, value in enumerate(values):
        acc.sample(float(value))
        acc.step((k + 1) * DT)
    return acc


def test_the_scatter_measures_a_white_noise_larger_than_told():
    """0.5 m/s² of white noise against a told 0.05: the median estimate over 100 second
    differences, within ±25 % of the truth 19 times in 20 (1.96 x its relative standard
    error 1.2/√100), is the noise used, and it is flagged; 1e5 m/s² is clipped at the
    accelerometer's clipping level."""
    rng = np.random.default_rng(3)
    acc = scattered(AccelerometerCheck(0.05, ()), 0.5 * rng.standard_normal(300))
    assert acc.noise == pytest.approx(0.5, rel=0.25) and acc.bad
    acc = scattered(AccelerometerCheck(0.05, ()), 1e5 * rng.standard_normal(300))
    assert acc.noise == check.ACC_CLIP


def test_the_scatter_leaves_an_accelerometer_as_told_and_its_manoeuvres_alone():
    """Noise as told (0.05 m/s²) on a flight of acceleration steps of ±5 m/s² every second
    and a steady jerk of 2 m/s³ in between: a steady jerk cancels in the second difference
    and each step makes two outliers of 100, which the median ignores; an estimate within
    ±12 % (one relative standard error) stays under MARGIN = 1.5x. The noise stays the stated
    one, exactly, at every check."""
    rng = np.random.default_rng(4)
    t = DT * np.arange(1500)
    flight = 5.0 * np.sign(np.sin(np.pi * t)) + 2.0 * (t % 1.0)
    acc = AccelerometerCheck(0.05, ())
    for k, value in enumerate(flight + 0.05 * rng.standard_normal(t.size)):
        acc.sample(float(value))
        acc.step((k + 1) * DT)
        assert acc.noise == 0.05 and not acc.bad, k
    assert acc.scatter == pytest.approx(0.05, rel=0.25)


def test_a_noise_not_stated_is_raised_by_the_scatter_of_the_first_samples():
    """Not stated (starting at the typical 0.35 m/s²), a logged multicopter's accelerometer
    scattering 7 m/s²: from EARLY_SAMPLES = 10 second differences on (1.4 s at 8.6 Hz, where
    100 take 11.6 s) its noise is the scatter's, within the estimate's 99.9 % band over 10
    differences (0.21-2.7x, simulated); and stays so. An accelerometer quieter than typical
    (0.2 m/s²) stays at the starting value until 100 differences are in: the early scatter
    only raises."""
    rng = np.random.default_rng(5)
    acc = AccelerometerCheck(0.35, (), stated=False)
    for k, value in enumerate(7.0 * rng.standard_normal(40)):
        acc.sample(float(value))
        acc.step((k + 1) / 8.6)
        if k + 1 < check.EARLY_SAMPLES + 2:         # two samples before the first difference
            assert acc.noise == 0.35, k
        else:
            assert 0.21 * 7.0 <= acc.noise <= 2.7 * 7.0 and acc.stated == acc.noise, k
    quiet = AccelerometerCheck(0.35, (), stated=False)
    for k, value in enumerate(0.2 * rng.standard_normal(check.SCATTER_SAMPLES + 1)):
        quiet.sample(float(value))
        quiet.step((k + 1) * DT)
        assert quiet.noise == 0.35, k


def hover(acc_std: float, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """AltitudeEKF told an accelerometer of 0.05 m/s² hovering 130 s on one of ``acc_std``
    (baro every step, GNSS at 10 Hz: tests/test_altitude_ekf.py's sensors); per step of the
    last 120 s: the height error, h_std, status."""
    flight = Flight(seed=seed)
    rows = []
    for k in range(round(130.0 / STEP)):
        r = flight.rng.standard_normal(4)
        samples = {"acc": {"acc_z": acc_std * r[0]},
                   "baro": {"baro_h": TRUE_H + 0.5 * r[1], "baro_p": 1e5, "baro_T": 288.0}}
        if k % 5 == 4:
            samples["gps"] = {"gps_h": TRUE_H + 0.3 * r[2], "gps_vz": 0.1 * r[3],
                              "gps_vdop": 1.0, "gps_nsat": 10, "gps_fix": True}
        flight.feed.step(**samples)
        assert flight.ekf.h_valid
        if k >= round(10.0 / STEP):
            rows.append((flight.ekf.h_est - TRUE_H, flight.ekf.h_std, flight.ekf.status))
    error, std, status = (np.array(c) for c in zip(*rows, strict=True))
    return error, std, status.astype(np.int64)


SEEDS = range(1, 8)


def test_an_accelerometer_40x_noisier_than_told_is_flagged_and_the_height_stays_honest():
    """2 m/s² against a told 0.05, seeds 1-7. Before the check: RMS 0.47-2.85 m, |e| <= 2
    h_std 17 % of the time over the seeds together; with the height sources' judgement alone
    0.76 (first found 0-31 s in). With the samples' scatter the noise is measured within
    the first second: the condition is in status from then on, the RMS is the nominal
    hover's (0.05 m as told; measured 0.050-0.059 m) and |e| <= 2 h_std 0.93-0.97 of the time
    per seed (the issue's target: 0.80). Bounds: the spec's honest band, 85-99.5 %, for
    every seed; the RMS within 1.5x the nominal 0.05 m."""
    for seed in SEEDS:
        error, std, status = hover(2.0, seed)
        assert (status & Status.BAD_ACC_VERTICAL).all(), seed
        assert np.sqrt(np.mean(error**2)) <= 1.5 * 0.05, seed
        assert 0.85 <= np.mean(np.abs(error) <= 2.0 * std) <= 0.995, seed


def test_an_accelerometer_as_told_is_never_flagged():
    for seed in SEEDS:
        _, _, status = hover(0.05, seed)
        assert not (status & Status.BAD_ACC_VERTICAL).any(), seed
