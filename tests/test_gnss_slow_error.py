"""AltitudeEKF's height is as uncertain as the GNSS datum it stands on: a receiver's height
error wanders over minutes, and averaging its samples does not reduce it (``gps_slow_error``
and the noise check's unshown share, ``AltitudeEKF._slow_variance``)."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from altfusion.estimators.altitude_ekf import AltitudeEKF

sys.path.insert(0, str(Path(__file__).parent))
from gnss_flights import (  # noqa: E402
    SLOW,
    WHITE,
    Flight,
    nmea_receiver_hover,
    wave_flight,
)

SEEDS = range(12)
"""The flights' error is the slow error, correlated over 60 s: 12 flights of 280 s hold about
12·280/120 = 28 independent values of it, so a coverage of 95 % is measured within
√(0.95·0.05/28) = 0.04 (1σ)."""

DATASHEET = math.hypot(WHITE, SLOW)
"""The receiver's σ as a datasheet gives it, the whole error: 1.53 m."""


def flight(seed: int, seconds: float = 300.0, slow_std: float = SLOW, white: float = WHITE,
           **params) -> tuple[Flight, list[float]]:
    """AltitudeEKF (``params``; unless they say otherwise, the baro's 0.5 m and the
    accelerometer's 0.05 m/s² told) on
    ``gnss_flights.wave_flight``: the flight and the variance of the GNSS datum's error
    (``_slow_variance`` once the GNSS's first sample is in) at each step after its first
    20 s; h_std is asserted to be √(P_hh + that variance) at every step."""
    ekf = AltitudeEKF(AltitudeEKF.Params(**({"baro_noise": 0.5, "acc_noise": 0.05} | params)),
                      step_size=0.1)
    datum = []

    def each_step(estimator: AltitudeEKF) -> None:
        on_gnss = estimator.params.height_ref == "gps" and estimator._reference_seen
        variance = estimator._slow_variance() if on_gnss else 0.0
        assert estimator.h_std == math.sqrt(estimator.P[0][0] + variance)
        datum.append(variance)

    result = wave_flight(ekf, seed, seconds, slow_std, white, each_step)
    return result, datum[-len(result.errors):]


def coverage(**params) -> float:
    """The fraction of steps with |e| <= 2 h_std over the flights of :data:`SEEDS`."""
    flights = [flight(seed, **params)[0] for seed in SEEDS]
    assert all(all(f.valid) for f in flights)
    return float(np.mean([f.coverage() for f in flights]))


def test_a_datasheet_noise_over_a_slowly_wandering_error_is_the_datum_s_uncertainty():
    """Told the receiver's σ as a datasheet gives it (√(0.3² + 1.5²) = 1.53 m) the filter
    takes it as white and averages it: before, |e| <= 2 h_std 28 % of the time (h_std
    0.28 m at the median, errors of 1.59 m RMS: the slow error's). Successive innovations
    show a twentieth of that variance; the rest is the datum's error, added to h_std:
    covered at least 85 % (the lower bound of an honest estimate in the evaluation;
    measured 94 %, h_std 1.47 m at the median). The error inferred is the datasheet's
    variance less twice the shown share's bound, √(1.53²·(1 - 2·1.23·0.042)) = 1.45 m:
    within 10 % of the true 1.5 m (the shown share's own spread, 10 %, moves it by 1 %)."""
    assert coverage(gps_noise=DATASHEET) >= 0.85
    datum = flight(0, gps_noise=DATASHEET)[1]
    assert math.sqrt(datum[-1]) == pytest.approx(SLOW, rel=0.1)


def test_told_nothing_a_typical_receiver_s_error_is_taken_as_slow_unless_shown():
    """Told nothing, the GNSS noise is measured from successive innovations, which show the
    white 0.3 m only: before, |e| <= 2 h_std 5-20 % of the time (h_std 0.12 m at the
    median). The typical receiver's 3 m the estimator assumes is now read as a statement:
    what its samples do not show of it is slow, and h_std holds it (measured: 100 %, h_std
    2.96 m over errors of 1.75 m RMS; cautious, and honest)."""
    flights = [flight(seed, baro_noise=0.0, acc_noise=0.0)[0] for seed in SEEDS[:6]]
    assert np.mean([f.coverage() for f in flights]) >= 0.85


def test_a_slow_error_stated_beside_the_white_noise_is_the_datum_s_and_weighs_each_sample():
    """Told the white noise and the slow error apart (``gps_noise`` 0.3 m,
    ``gps_slow_error`` 1.5 m), the coverage is that of a Gaussian error within twice its
    σ, 95 %, within 0.1 (2.5σ of the measurement above) and at most the evaluation's
    99.5 %, and each sample is weighted by its whole error, the slow one in (Schmidt's
    gain): the height errs no more than told the white noise alone, which follows the
    receiver's wander as precisely measured and whose coverage is below one half
    (measured: 94.8 % and 1.59 m RMS; 10.5 % and 1.66 m told 0.3 m alone)."""
    told = [flight(seed, gps_noise=WHITE, gps_slow_error=SLOW)[0] for seed in SEEDS]
    white = [flight(seed, gps_noise=WHITE)[0] for seed in SEEDS]
    assert 0.85 <= np.mean([f.coverage() for f in told]) <= 0.995
    assert np.mean([f.coverage() for f in white]) < 0.5

    def rms(flights: list[Flight]) -> float:
        return float(np.sqrt(np.mean(np.concatenate([f.errors for f in flights]) ** 2)))

    assert rms(told) <= rms(white)


@pytest.mark.parametrize("told", [{}, {"gps_noise": 0.05, "gps_slow_error": 0.5,
                                        "baro_noise": 0.1, "acc_noise": 0.05}],
                         ids=["nothing", "white_and_slow"])
def test_a_receiver_wandering_within_its_slow_error_is_neither_rejected_nor_isolated(told):
    """A smooth receiver hovering (``gnss_flights.nmea_receiver_hover`` with a 0.5 m / 30 s
    Gauss-Markov error: 0.02 m white noise read to 0.1 m, a 0.1 m baro at 50 Hz) wanders
    further than its samples' scatter, and its innovations' mean over the bias test's
    window moves with it. Told nothing (its typical 3 m read as mostly slow, its samples
    scattering by centimetres) or told its white noise and slow error, its gate, bias test
    and gains now hold the slow error: seeds 0-3, no sample rejected. Before, the bias test
    and the gate took the wander for a fault: 206-624 of 1200 samples rejected and isolated
    6.4-47.5 s of 120 s told nothing, 516-775 and 33.6-67.2 s told both."""
    for seed in range(4):
        hover = nmea_receiver_hover(AltitudeEKF(AltitudeEKF.Params(**told), step_size=0.01),
                                    seed, wander=0.5, tau=30.0)
        assert (hover.rejected, hover.isolated) == (0, 0.0)


def test_a_white_gnss_told_right_gets_nothing_added():
    """The same flight with a white GNSS of 1.53 m told right: its successive innovations
    show all of its variance, nothing is added to h_std."""
    assert not any(flight(0, slow_std=0.0, white=DATASHEET, gps_noise=DATASHEET)[1])


def test_only_a_gnss_that_defines_the_datum_adds_its_slow_error():
    """With the baro as the datum (``height_ref`` baro), the GNSS's slow error is in its
    offset state g, not in the datum: h_std does not take it."""
    assert not any(flight(0, 60.0, gps_noise=WHITE, gps_slow_error=SLOW,
                          height_ref="baro")[1])
