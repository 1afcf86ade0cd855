"""The bias test of the fault layer against an error every sample of a window shares."""

import math

import pytest

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.fault_detection import BIAS_SIGMAS, bias_test, pin

NOISE = 0.1
"""σ of each innovation, m (S = 0.01 m²)."""
SAMPLES = 20
"""Samples in the window (2 s at 10 Hz; the window spans 5 s)."""


def judged(offset: float, shared: float = 0.0) -> AidSource:
    """A GNSS whose innovations all sit at ``offset``, ``shared`` the variance of the error
    its window's samples share, held in each sample's S too (σ² = :data:`NOISE`² + shared,
    as AltitudeEKF's gate holds its GNSS's slow error), judged against a baro fused at every
    sample whose own window is empty (it agrees with the prediction)."""
    gnss, baro = AidSource("gps"), AidSource("baro")
    gnss.window.shared = shared
    for k in range(SAMPLES):
        now = 0.1 * k
        baro.last_fused = now
        bias_test(gnss, (gnss, baro), now, 5.0, offset, NOISE**2 + shared, 5.0)
    return gnss


def test_a_mean_is_biased_beyond_five_of_its_standard_deviations_with_the_shared_error_in():
    """The mean of n independent innovations is uncertain by √(S/n) (2.2 cm here): an
    offset of 0.2 m is biased. A slow error of 0.5 m shared by every sample (a GNSS's
    wander, ``InnovationWindow.shared``) does not average away: the mean is uncertain by
    √(S/n + 0.25) = 0.51 m, beyond 5 of which lies the single sample's gate, 5·√S =
    2.55 m, to which each innovation is clipped: no offset the gate lets through is biased
    (a larger one is the gate's to reject). Without the shared error in the mean's
    variance, 1.0 m and 2.4 m were."""
    assert judged(0.2).biased
    assert not any(judged(offset, 0.25).biased for offset in (0.2, 1.0, 2.4))


def test_a_source_pins_the_height_no_tighter_than_the_error_its_samples_share():
    """A GNSS of 0.1 m white noise pins the height over its window to its mean plus 5 of
    the mean's standard deviations, 0.11 m; with 0.5 m shared, to 2.6 m."""
    gnss = judged(0.0)
    gnss.gate_width = math.inf
    assert pin(gnss) == pytest.approx(BIAS_SIGMAS * NOISE / math.sqrt(SAMPLES))
    wandering = judged(0.0, 0.25)
    wandering.gate_width = math.inf
    assert pin(wandering) == pytest.approx(
        BIAS_SIGMAS * math.sqrt((NOISE**2 + 0.25) / SAMPLES + 0.25))
