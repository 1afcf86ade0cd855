"""A reading repeated bit for bit is stuck (estimators/stuck.py)."""

import math
import sys
from pathlib import Path

import numpy as np

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.health import SourceBit, source_bit
from altfusion.estimators.stuck import StillReceiver, StuckCheck

sys.path.insert(0, str(Path(__file__).parent))
from stream_feeder import StreamFeeder  # noqa: E402


def test_a_reading_is_stuck_from_its_limit_th_repetition_until_it_changes():
    check = StuckCheck(3)
    verdicts = [check.stuck(v) for v in (1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0)]
    assert verdicts == [False, False, False, True, True, False, False]


def test_a_noisy_quantized_reading_is_never_stuck_and_a_limit_of_zero_is_off():
    """A 5 mm laser read to the millimetre at 15 m: 100 000 samples, never ten repeats
    (two successive readings coincide about 6 % of the time)."""
    readings = np.round(15.0 + 0.005 * np.random.default_rng(2).standard_normal(100_000), 3)
    check = StuckCheck(10)
    assert not any(check.stuck(float(v)) for v in readings)
    off = StuckCheck(0)
    assert not any(off.stuck(0.0) for _ in range(100))


def test_a_receiver_is_still_while_its_heights_show_no_slope_beyond_the_gate():
    """The slope of ten 1 Hz heights of 13 m noise has a standard deviation of
    13/√82.5 = 1.43 m/s: a 5σ gate holds 7.2 m/s; 10 m/s is beyond it, a constant and
    1 m/s are within; one sample has no slope."""
    for climb, still in ((0.0, True), (1.0, True), (10.0, False)):
        receiver = StillReceiver()
        for k in range(10):
            receiver.sample(1000.0 + k, 100.0 + climb * k, 0.0)
        assert receiver.still(13.0, 5.0) is still, climb
    receiver = StillReceiver()
    receiver.sample(5.0, 100.0, 0.0)
    assert not receiver.still(13.0, 5.0)
    receiver.sample(6.0, 100.0, 0.0)
    assert receiver.still(13.0, 5.0)
    receiver.sample(7.0, 100.0, 0.01)                # the speed reads other than 0
    assert receiver.n == 0 and not receiver.still(13.0, 5.0)


def gnss_at_rest(seconds: float, climb_after: float = math.inf, frozen_height: bool = False,
                 ) -> tuple[AltitudeEKF, list[bool]]:
    """AltitudeEKF told a 0.5 m baro at 10 Hz and a 1 m GNSS at 5 Hz whose vertical speed
    reads exactly 0.0 (PX4 SITL on the ground; ``frozen_height``: u-blox static hold, the
    height frozen too), the vehicle at rest at 100 m, from ``climb_after`` climbing at
    10 m/s (the speed still reading 0: an unconnected input); seed 1. The estimator and,
    per step, whether gps_vz is isolated."""
    ekf = AltitudeEKF(AltitudeEKF.Params(baro_noise=0.5, gps_noise=1.0, gps_vz_noise=0.3),
                      step_size=0.1)
    feed, rng = StreamFeeder(ekf), np.random.default_rng(1)
    isolated = []
    for k in range(round(seconds / 0.1)):
        t = (k + 1) * 0.1
        h = 100.0 + 10.0 * max(0.0, t - climb_after)
        gps = None
        if k % 2 == 0:
            gps = {"gps_h": 100.0 if frozen_height else h + rng.standard_normal(),
                   "gps_vz": 0.0, "gps_vdop": 1.0, "gps_nsat": 10, "gps_fix": True}
        feed.step(baro={"baro_h": h + 0.5 * rng.standard_normal(), "baro_p": 1e5,
                        "baro_T": 288.0}, gps=gps)
        isolated.append(bool(ekf.status & source_bit("gps_vz", SourceBit.ISOLATED)))
    return ekf, isolated


def test_a_gnss_holding_still_is_not_a_stuck_one():
    """A GNSS at rest reporting a vertical speed of exactly 0.0 (PX4 SITL on the ground:
    before this check every replay of the pyulog sample log isolated gps_vz at 9.7 s and
    counted 257 rejections) or frozen altogether (u-blox static hold): its repeated
    readings are not fused (a repetition adds no information) but neither rejected nor
    isolated, and the log says why once."""
    for frozen in (False, True):
        ekf, isolated = gnss_at_rest(120.0, frozen_height=frozen)
        assert not any(isolated)
        assert ekf.gps_vz_rejected == 0 and ekf.gps_rejected == 0
        assert not ekf.status & (source_bit("gps", SourceBit.REJECTED)
                                 | source_bit("gps_vz", SourceBit.REJECTED))
        assert ekf.h_valid and abs(ekf.h_est - 100.0) < 3.0 * ekf.h_std
        notes = [n for n in ekf.take_notes() if "holds still" in n]
        assert len(notes) == (2 if frozen else 1), notes


def test_a_zero_speed_that_stays_while_the_receiver_climbs_is_stuck():
    """After two minutes at rest the vehicle climbs at 10 m/s and the speed still reads 0:
    the GNSS's heights over the run of zeros take a slope, and the speed is isolated within
    3 s (measured: 1.9 s). The least-squares slope of τ s of a climb at r after T s at rest
    is about 3rτ²/T², and 5 standard deviations of it over 120 s of 1 m heights at 5 Hz are
    5·√(12/(600·120²)) = 0.006 m/s: reached at τ ≈ 1.7 s (a longer rest delays it as T^¼)."""
    _, isolated = gnss_at_rest(130.0, climb_after=120.0)
    first = isolated.index(True)
    assert 120.0 < (first + 1) * 0.1 <= 123.0
