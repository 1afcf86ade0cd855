"""Each source's stated noise checked against its innovations (noise_check): the check on
hand-made innovations, then AltitudeEKF on the hover of tests/test_altitude_ekf.py told every
noise five times too small, and told it right."""

import sys
from pathlib import Path

import numpy as np
import pytest

from altfusion.estimators import noise_check
from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.hajiyev import HajiyevAdaptiveEstimator
from altfusion.estimators.health import SourceBit, source_bit
from altfusion.estimators.noise_check import NoiseCheck, ShownNoise
from altfusion.estimators.whang import WhangGAEstimator
from altfusion.estimators.xu import XuSHAEKF

sys.path.insert(0, str(Path(__file__).parent))
from stream_feeder import StreamFeeder  # noqa: E402
from test_altitude_ekf import NOISE, TRUE_H, Flight  # noqa: E402


def checked(scale: float, samples: int, seed: int = 1, bias: float = 0.0,
            maximum: float = 100.0) -> NoiseCheck:
    """A check of window 100 fed ``samples`` innovations whose noise variance is ``scale``
    times the stated R = 1 (S = f·R: the prediction's variance negligible), plus ``bias``."""
    check = NoiseCheck(AidSource("baro"), 100.0, maximum)
    noise = np.random.default_rng(seed).standard_normal(samples) * np.sqrt(scale)
    for value in noise:
        check.gated(bias + value, check.factor, check.factor)
    return check


def test_a_noise_as_stated_is_not_inflated_beyond_a_few_tenths_and_never_flagged():
    """10 000 pairs of a source as told: m is the mean of about 200 χ² ratios of one degree
    (the window of 100 pairs, exponential): standard deviation √(2/199) = 0.10, so m stays
    below 1.6 (6 standard deviations) and the flag (factor > 4) is never set."""
    source = AidSource("baro")
    check = NoiseCheck(source, 100.0, 100.0)
    noise = np.random.default_rng(3).standard_normal(10_000)
    factors = []
    for value in noise:
        check.gated(value, check.factor, check.factor)
        factors.append(check.factor)
        assert not source.bits & source.inflated_mask
    assert max(factors[100:]) < 1.6


@pytest.mark.parametrize("scale", [9.0, 25.0])
def test_a_noise_stated_too_small_is_inflated_to_its_true_variance(scale):
    """Innovations of 9x and 25x the stated variance (σ 3x and 5x): after 2000 pairs the
    factor is the true ratio within 35 % (the window's spread is 10 %, and its fixed point
    lies a few percent low: the clipped ratios and the product of m with its own noise) and
    the source is flagged."""
    check = checked(scale, 2000)
    assert check.factor == pytest.approx(scale, rel=0.35)
    assert check.source.bits & source_bit("baro", SourceBit.NOISE_INFLATED)


def test_a_bias_is_not_read_as_noise():
    """A constant offset of 10 standard deviations on the innovations cancels in their
    differences: the factor stays that of the noise alone (below 1.6 as above)."""
    assert checked(1.0, 2000, bias=10.0).factor < 1.6


def test_the_inflation_is_bounded_and_forgetting_starts_a_new_pair():
    check = checked(10_000.0, 2000, maximum=50.0)
    assert check.factor == 50.0
    pairs = check.pairs
    check.forget()
    check.gated(1e6, 1.0, 1.0)               # no previous sample: no pair
    assert check.pairs == pairs


def test_the_flag_waits_for_its_pairs():
    check = checked(25.0, noise_check.MIN_PAIRS - 1)
    assert check.factor > noise_check.FLAGGED
    assert not check.source.bits & check.source.inflated_mask


def hover(scale: float, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """AltitudeEKF told every noise of the hover's sensors times ``scale`` (baro, GNSS,
    accelerometer, laser), flown 70 s: the height error, h_std and status of the last
    60 s."""
    flight = Flight(seed=seed, **{name: value * scale for name, value in NOISE.items()})
    flight.fly(10.0, laser=0.0)
    rows = []
    flight.fly(60.0, laser=0.0, record=rows)
    assert all(r[3] for r in rows)
    error = np.array([r[1] - TRUE_H for r in rows])
    std = np.array([r[2] for r in rows])
    return error, std, np.array([r[4] for r in rows], dtype=np.int64)


SEEDS = range(1, 5)
INFLATED = (source_bit("baro", SourceBit.NOISE_INFLATED)
            | source_bit("gps", SourceBit.NOISE_INFLATED)
            | source_bit("laser", SourceBit.NOISE_INFLATED))


def test_noise_told_five_times_too_small_is_inflated_and_the_height_stays_honest():
    """Every noise told 0.2x: the baro, GNSS and laser are flagged by the end of each run
    and |e| <= 2 h_std at least 80 % of the time over the seeds together (issue 29's target).
    Measured 0.97, 0.98, 1.00, 0.94 per seed, 0.97 together; without the check 0.00-0.12,
    0.06 together; with the check but a GNSS rejected and isolated by the bias test while its
    noise was still being learnt (before ``noisy`` sources were spared) 0.41 on seed 1. The
    per-seed spread (0.03) puts 0.80 far below the measured figure: the test fails if the
    check stops inflating or the fault layer shuts the GNSS out again."""
    covered = []
    for seed in SEEDS:
        error, std, status = hover(0.2, seed)
        assert status[-1] & INFLATED == INFLATED, seed
        covered.append(np.abs(error) <= 2.0 * std)
    assert np.mean(covered) >= 0.80


def test_noise_as_told_is_never_flagged():
    for seed in SEEDS:
        _, _, status = hover(1.0, seed)
        assert not (status & INFLATED).any(), seed


@pytest.mark.parametrize("scale", [0.01, 100.0])
def test_a_noise_not_stated_is_measured_both_ways_and_never_flagged(scale):
    """No statement: innovations of 0.01x and 100x the typical variance (σ a tenth and
    tenfold). The factor starts pessimistic, falls by at most FALL per pair, and settles at
    the true ratio times the upper bound of its one-sided 97.5 % interval over the window,
    upper_bound_factor(199) = 1.23, within 35 % as above; the source is never flagged and is
    spared by the fault layer only during its first window of pairs."""
    source = AidSource("baro")
    check = NoiseCheck(source, 100.0, 100.0, stated=False)
    assert check.factor == noise_check.UNSTATED_START
    noise = np.random.default_rng(5).standard_normal(2000) * np.sqrt(scale)
    previous = check.factor
    for k, value in enumerate(noise):
        check.gated(value, check.factor, check.factor)
        assert check.factor >= previous / noise_check.FALL
        assert source.noisy == (0 < k < 100)
        previous = check.factor
        assert not source.bits & source.inflated_mask
    assert check.factor == pytest.approx(scale * noise_check.upper_bound_factor(199), rel=0.35)


def test_the_rise_is_the_factor_over_its_earlier_peak():
    """A noise not stated: each gated sample's ``rise`` is the factor over the largest
    earlier one when it exceeds it, else 1; the product of the rises is the peak over the
    starting factor."""
    check = NoiseCheck(AidSource("baro"), 100.0, 100.0, stated=False)
    noise = np.random.default_rng(7).standard_normal(300) * np.concatenate(
        [np.full(150, 0.1), np.full(150, 50.0)])
    product, peak = 1.0, check.factor
    for value in noise:
        check.gated(value, check.factor, check.factor)
        assert check.rise == (check.factor / peak if check.factor > peak else 1.0)
        peak = max(peak, check.factor)
        product *= check.rise
    assert check.peak == peak > noise_check.UNSTATED_START
    assert product == pytest.approx(peak / noise_check.UNSTATED_START, rel=1e-12)


def test_a_stated_noise_rises_as_far_as_shown():
    """A stated noise, seeds 0-7: 150 samples as told, then 5x the noise (a variance ratio
    of 25). The first 150 tell no rise, though their factor exceeds FLAGGED in some seeds
    (the first pairs scatter; asserted, so that the case is exercised); after them each
    rise takes the peak to the lower bound of the ratio's 97.5 % interval, m·k/χ²_k(0.975)
    with k = min(n, 2·window - 1), from the statement on: the rises multiply to the peak,
    beyond FLAGGED and below the factor's largest value."""
    largest_as_told = 1.0
    for seed in range(8):
        check = NoiseCheck(AidSource("baro"), 100.0, 100.0)
        noise = np.random.default_rng(seed).standard_normal(300) * np.concatenate(
            [np.full(150, 1.0), np.full(150, 5.0)])
        product, largest = 1.0, 1.0
        for k, value in enumerate(noise):
            check.gated(value, check.factor, check.factor)
            largest = max(largest, check.factor)
            if k < 150:
                assert check.rise == 1.0
                largest_as_told = max(largest_as_told, check.factor)
            elif check.rise > 1.0:
                shown = check.ratio * noise_check.lower_bound_factor(min(check.pairs, 199))
                assert check.peak == pytest.approx(min(shown, check.factor), rel=1e-12)
            product *= check.rise
        assert noise_check.FLAGGED < check.peak < largest
        assert product == pytest.approx(check.peak, rel=1e-12)
    assert largest_as_told > noise_check.FLAGGED


def test_the_bounds_are_the_chi2_quantiles():
    """The factors from m to its 97.5 % bounds against scipy's χ² quantiles: exact for one
    and two degrees of freedom; above, Wilson-Hilferty's upper bound within 5 % from 5
    degrees on and 19 % at 3, on the cautious side (higher), its lower bound within 0.3 %."""
    from scipy.stats import chi2
    for dof in (1, 2, 3, 5, 10, 50, 199):
        upper, lower = dof / chi2.ppf(0.025, dof), dof / chi2.ppf(0.975, dof)
        tolerance = 1e-12 if dof <= 2 else 0.05 if dof >= 5 else 0.19
        assert noise_check.upper_bound_factor(dof) == pytest.approx(upper, rel=tolerance)
        assert noise_check.upper_bound_factor(dof) >= upper * (1.0 - 1e-12)
        assert noise_check.lower_bound_factor(dof) == pytest.approx(
            lower, rel=1e-12 if dof <= 2 else 0.003)


def test_a_stated_noise_is_never_deflated():
    assert checked(0.01, 2000).factor == 1.0


def test_a_noise_as_stated_shows_itself_whole():
    """100 000 innovations of a source as told: from its 20th pair on the upper bound of the
    shown share w is below one half only if the mean of 20 χ² ratios is below 0.24 (χ²_20
    below 4.8: 2·10⁻⁴), rarer with every pair after: nothing of it is taken as slow."""
    check = NoiseCheck(AidSource("gps"), 100.0, 100.0)
    for value in np.random.default_rng(4).standard_normal(100_000):
        check.gated(value, check.factor, check.factor)
        assert check.unshown() == 0.0


def test_an_error_that_wanders_slowly_is_the_share_of_the_noise_its_samples_do_not_show():
    """A GNSS at 5 Hz stated σ = 1.53 m: white 0.3 m on a Gauss-Markov error of 1.5 m and
    120 s. Successive samples show w = (0.3² + 2·1.5²·(1 - e^(-0.2/120)))/1.53² = 0.042 of
    the stated variance (window of 100 pairs: standard deviation 10 % of it); the bound
    takes it x1.23 (199 degrees of freedom): unshown 1 - 2·1.23·0.042 = 0.90, within 0.03
    (three standard deviations, 2·1.23·0.1·0.042 = 0.01). Stated 0.3 m (the white noise
    alone): nothing unshown. Not stated, with 1.53 m its typical value: read alike."""
    rng = np.random.default_rng(5)
    decay = np.exp(-0.2 / 120.0)
    slow, white, stated = 1.5 * rng.standard_normal(), 0.3, np.hypot(0.3, 1.5)
    errors = []
    for _ in range(3000):
        slow = decay * slow + 1.5 * np.sqrt(1.0 - decay**2) * rng.standard_normal()
        errors.append(slow + white * rng.standard_normal())
    shown = (white**2 + 2.0 * 1.5**2 * (1.0 - decay)) / stated**2
    slow = 1.0 - 2.0 * 1.23 * shown
    for sigma, stated_noise, expected in ((stated, True, slow), (white, True, 0.0),
                                          (stated, False, slow)):
        check = NoiseCheck(AidSource("gps"), 100.0, 100.0, stated_noise)
        for error in errors:
            check.gated(error, sigma**2 * check.factor, sigma**2 * check.factor)
        assert check.unshown() == pytest.approx(expected, abs=0.03)


def test_altitude_ekf_told_nothing_is_as_accurate_and_honest_as_told_the_noise():
    """The hover with no noise stated (every ``<source>_noise`` 0: measured from typical
    starting values 4-35x off the sensors': baro 2 m for 0.5, GNSS 3 m for 0.3, laser 0.1 m
    for 0.01, accelerometer 0.35 for 0.05 m/s²) against the same runs told the noise: seeds
    1-5 measured coverage 0.79-1.00 (0.96 together) and RMS 0.013-0.032 m, told 0.59-1.00
    and 0.012-0.034 m. Issue 29's targets: coverage at least 0.85 over the seeds together,
    RMS at most twice the told-noise RMS."""
    told_nothing = [hover(0.0, seed) for seed in range(1, 6)]
    told = [hover(1.0, seed) for seed in range(1, 6)]
    coverage = np.mean([np.abs(e) <= 2.0 * s for e, s, _ in told_nothing])
    assert coverage >= 0.85
    rms = np.sqrt(np.mean([e**2 for e, _, _ in told_nothing]))
    assert rms <= 2.0 * np.sqrt(np.mean([e**2 for e, _, _ in told]))


def test_a_source_found_noisy_is_spared_by_the_fault_layer_only_while_its_noise_is_learnt():
    """A source 5x noisier than stated: ``noisy`` (not isolated, not bias-tested) once its
    ratio passes NOISY, until its first window of pairs is in; then its gate and bias test
    are sized by the learnt noise and a fault (a GNSS step) is judged as usual."""
    check = checked(25.0, 50)
    assert check.source.noisy
    check = checked(25.0, 101)
    assert check.factor > noise_check.NOISY and not check.source.noisy


def coarse_gnss_hover(told: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """whang2008's sensors on a 300 s hover at 1000 m, no accelerometer: a baro calibrated at
    the start (σ 5 m, every 0.2 s: its offset's prior, 0 ± 10 m, is right) and a GNSS of σ
    70 m (every 1 s, the height reference), told ``told`` times their noise (0: not stated).
    The errors and ``h_std`` at every step after the first GNSS sample."""
    ekf = AltitudeEKF(AltitudeEKF.Params(baro_noise=5.0 * told, gps_noise=70.0 * told,
                                         gps_vz_noise=0.5 * told), step_size=0.2)
    feed = StreamFeeder(ekf)
    rng = np.random.default_rng(seed)
    errors, stds = [], []
    for n in range(1500):
        gps = None
        if n % 5 == 4:
            gps = {"gps_h": 1000.0 + 70.0 * rng.standard_normal(), "gps_vdop": 1.0,
                   "gps_vz": 0.5 * rng.standard_normal(), "gps_nsat": 10, "gps_fix": True}
        feed.step(baro={"baro_h": 1000.0 + 5.0 * rng.standard_normal(), "baro_p": 9e4,
                        "baro_T": 281.0}, gps=gps)
        if n >= 4:
            errors.append(ekf.h_est - 1000.0)
            stds.append(ekf.h_std)
    return np.array(errors), np.array(stds)


@pytest.mark.parametrize("told", [0.2, 0.0])
def test_the_datum_is_as_uncertain_as_the_noise_found_in_its_samples(told):
    """A 70 m GNSS told 14 m (x0.2) or nothing (started at 3 m x 10): its first samples,
    weighted as far more precise than they are, set the height's datum; once the noise check
    finds the noise, the height's variance grows with it, and a first sample far off the
    baro's datum moves the height with the sample's variance, not the height's old one.
    Seeds 1-5 together: coverage measured 0.99 (x0.2) and 1.00 (nothing), RMS 11.8 and
    7.6 m, against 5.2 m told the noise; before (the datum as certain as the first samples
    were weighted), 0.50 and 0.20, two and four seeds at 22-58 m RMS with coverage 0. Issue
    29's targets: coverage at least 0.80 told x0.2 and 0.85 told nothing, whose RMS at most
    twice the told-noise RMS."""
    runs = [coarse_gnss_hover(told, seed) for seed in range(1, 6)]
    coverage = np.mean([np.abs(e) <= 2.0 * s for e, s in runs])
    assert coverage >= (0.80 if told else 0.85)
    if not told:
        told_rms = np.sqrt(np.mean([e**2 for e, _ in (coarse_gnss_hover(1.0, seed)
                                                      for seed in range(1, 6))]))
        assert np.sqrt(np.mean([e**2 for e, _ in runs])) <= 2.0 * told_rms


def shown(scale: float, samples: int, seed: int = 1) -> ShownNoise:
    """A paper filter's check fed ``samples`` innovations of ``scale`` times the variance
    S = 1 its filter computes."""
    check = ShownNoise(AidSource("baro"))
    for value in np.random.default_rng(seed).standard_normal(samples) * np.sqrt(scale):
        check.gated(value, 1.0)
    return check


def test_a_paper_filter_told_its_noise_keeps_its_gate_and_h_std_exactly():
    """100 000 innovations as the filter computes them: the factor stays exactly 1 (the gate
    and the published h_std are the filter's to the bit) and the source is never flagged:
    shown needs the ratio's 97.5 % lower bound beyond SHOWN = 2, for the window's m (spread
    0.10) beyond 2.4, 14 standard deviations."""
    check = ShownNoise(AidSource("baro"))
    for value in np.random.default_rng(2).standard_normal(100_000):
        check.gated(value, 1.0)
        assert check.factor == 1.0
        assert not check.source.bits & check.source.inflated_mask


@pytest.mark.parametrize("scale", [4.0, 25.0])
def test_a_paper_filter_told_too_small_a_noise_shows_it(scale):
    """Innovations of 4x and 25x the filter's S: after 2000 pairs m is the true ratio within
    35 % (as NoiseCheck's above), the factor its 97.5 % lower bound (m·199/χ²_199(0.975),
    0.83·m) and the source is flagged; before MIN_PAIRS pairs nothing is shown."""
    assert shown(scale, noise_check.MIN_PAIRS - 1).factor == 1.0
    check = shown(scale, 2000)
    assert check.ratio == pytest.approx(scale, rel=0.35)
    assert check.factor == check.ratio * noise_check.lower_bound_factor(199)
    assert check.source.bits & check.source.inflated_mask


def paper_hover(cls, told: float, seed: int, fault_detection: bool = True):
    """A paper estimator at 100 m for 300 s, baro every 0.2 s and GPS every 1 s with the
    noises of its defaults (R_baro, R_gps), told ``told`` times their σ: the errors, h_std
    and status after the first 10 s."""
    defaults = cls.Params()
    estimator = cls(cls.Params(R_baro=defaults.R_baro * told**2, R_gps=defaults.R_gps * told**2,
                               fault_detection=fault_detection), step_size=0.2)
    feed, rng = StreamFeeder(estimator), np.random.default_rng(seed)
    rows = []
    for n in range(1500):
        gps = {"gps_h": 100.0 + np.sqrt(defaults.R_gps) * rng.standard_normal()} \
            if n % 5 == 4 else None
        feed.step(baro={"baro_h": 100.0 + np.sqrt(defaults.R_baro) * rng.standard_normal(),
                        "baro_T": 287.5}, gps=gps, inputs={"gps_fix": True})
        if n >= 50:
            rows.append((estimator.h_est - 100.0, estimator.h_std, estimator.status))
    return np.array(rows)


PAPER_INFLATED = source_bit("baro", SourceBit.NOISE_INFLATED) | source_bit(
    "gps", SourceBit.NOISE_INFLATED)


@pytest.mark.parametrize("cls", [BaselineKF, HajiyevAdaptiveEstimator, WhangGAEstimator])
def test_a_paper_estimator_told_five_times_too_small_a_noise_stays_honest_and_says_so(cls):
    """Every noise told 0.2x (a variance 0.04x; the paper's equations unchanged): with the
    fault layer each estimator's published h_std takes the noise its innovations show, the
    baro or the GPS is flagged, and |e| <= 2 h_std holds at least 80 % of the time over
    seeds 1-4 together (faults.md: told wrong, stay honest or say so). Measured together:
    BaselineKF 0.97, HajiyevAdaptiveEstimator 0.88, WhangGAEstimator 0.89 (per seed within
    0.04 of these); without the fault layer (the paper's code path: h_std as the filter
    computes it) 0.19, 0.25, 0.31, asserted below 0.5 so that the test fails if the check
    stops showing (with pairs clipped at 25·S rather than 25·f·S, m settled at half the
    true ratio and Hajiyev's coverage at 0.80-0.85)."""
    honest, paper = [], []
    for seed in range(1, 5):
        rows = paper_hover(cls, 0.2, seed)
        assert rows[-1, 2].astype(np.int64) & PAPER_INFLATED, seed
        honest.append(np.abs(rows[:, 0]) <= 2.0 * rows[:, 1])
        rows = paper_hover(cls, 0.2, seed, fault_detection=False)
        paper.append(np.abs(rows[:, 0]) <= 2.0 * rows[:, 1])
    assert np.mean(honest) >= 0.80
    assert np.mean(paper) < 0.5


@pytest.mark.parametrize("cls, own, plain", [
    (AltitudeEKF, {"adaptive_noise": True}, {"adaptive_noise": False}),
    (XuSHAEKF, {"adaptive": True}, {"adaptive": False}),
])
def test_an_estimator_without_its_own_check_gets_the_fault_layers(cls, own, plain):
    """AltitudeEKF and XuSHAEKF check their noises themselves only with their adaptation on;
    without it (and with ``fault_detection``) their sources get the fault layer's check as
    the paper filters' do, and without ``fault_detection`` nothing is checked."""
    def checked(**params) -> set[str]:
        estimator = cls(cls.Params(**params))
        return {source.name for source in estimator.aid_sources if source.shown is not None}
    assert not checked(**own)
    assert checked(**plain) == set(cls.sources()) - {"acc"}
    assert not checked(**plain, fault_detection=False)
