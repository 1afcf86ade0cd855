"""The on-ground range (altfusion.estimators.ground_range) in AltitudeEKF: a laser's invalid
frames read as the vehicle on the ground only where they can mean that.

The flights: the estimator stepped every 0.01 s over flat ground at 0 m (told: terrain_h 0,
P0_terrain 1e-8, as the evaluation tells the site); accelerometer every step (σ 0.05 m/s²),
baro every step (σ 0.5 m, 3 m off: its calibration at launch, not told), GNSS every 0.2 s
(σ 3 m), laser frames every step (σ 5 mm), as in xu2016_hover15. Seeds fixed.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from altfusion.errors import ParameterError
from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.health import SourceBit, source_bit

sys.path.insert(0, str(Path(__file__).parent))
from stream_feeder import StreamFeeder  # noqa: E402

STEP = 0.01
TOLD = {"baro_noise": 0.5, "gps_noise": 3.0, "acc_noise": 0.05, "laser_noise": 0.005,
        "terrain_h": 0.0, "P0_terrain": 1e-8, "terrain_psd": 0.0}
LASER_FUSED = source_bit("laser", SourceBit.FUSED)


def fly(ekf: AltitudeEKF, feed: StreamFeeder, rng, seconds: float, h: float,
        laser_valid: bool) -> list[tuple[float, float, int]]:
    """``seconds`` at the true height ``h`` (standing still); (error, h_std, status) per
    step."""
    rows = []
    for _ in range(round(seconds / STEP)):
        r = rng.standard_normal(4)
        samples = {"acc": {"acc_z": 0.05 * r[0]},
                   "baro": {"baro_h": h + 3.0 + 0.5 * r[1], "baro_p": 1e5, "baro_T": 288.0},
                   "laser": {"laser_h": h + 0.005 * r[2] if laser_valid else 0.0,
                             "laser_valid": laser_valid}}
        if feed.n % 20 == 19:
            samples["gps"] = {"gps_h": h + 3.0 * r[3], "gps_vz": 0.0, "gps_vdop": 0.0,
                              "gps_nsat": 0, "gps_fix": True}
        feed.step(**samples)
        rows.append((ekf.h_est - h, ekf.h_std, ekf.status))
    return rows


def standing(seed: int, **params) -> np.ndarray:
    """10 s standing on the ground (the laser below its minimum range: invalid frames);
    (error, h_std, status) of the last 9 s."""
    ekf = AltitudeEKF(AltitudeEKF.Params(**{**TOLD, **params}), step_size=STEP)
    feed, rng = StreamFeeder(ekf), np.random.default_rng(seed)
    return np.array(fly(ekf, feed, rng, 10.0, 0.0, False)[100:])


def test_on_the_ground_the_invalid_frames_pin_the_height():
    """Without the readings the height is the GNSS's average (3 m at 5 Hz: ~0.6 m after 5 s)
    and the baro's, measured RMS 0.5-1.5 m per seed; with them it lies in the laser's
    [0, 0.1 m] about its middle, at most the 0.05 m half-width off plus the few mm the other
    sources pull (asserted: below 0.1 m), its h_std at the reading's half-width 0.05 m: a
    truth anywhere in [0, 0.1 m] within 2 h_std of the estimate while the other sources keep
    it within 0.05 m of the middle (measured 100 % of the steps per seed): asserted, the
    fault suite's 85 %.
    Seeds 1-4."""
    for seed in range(1, 5):
        on, off = standing(seed), standing(seed, laser_min_range=0.0)
        assert np.sqrt(np.mean(off[:, 0] ** 2)) > 0.3
        assert np.abs(on[:, 0]).max() < 0.1
        assert np.mean(np.abs(on[:, 0]) <= 2 * on[:, 1]) >= 0.85
        assert (on[:, 2].astype(np.int64) & LASER_FUSED).any()


def test_a_laser_dropping_out_in_flight_does_not_pull_the_height_down():
    """A hover at 10 m, the laser reading for 10 s, then only invalid frames for 10 s: the
    ground reading fails the gate (10 m against h_std of millimetres), the ground is refuted
    and no frame is read as it; the height stays on the hover (the baro and GNSS carry it:
    within 0.5 m, and within 2 h_std)."""
    ekf = AltitudeEKF(AltitudeEKF.Params(**TOLD), step_size=STEP)
    feed, rng = StreamFeeder(ekf), np.random.default_rng(1)
    fly(ekf, feed, rng, 10.0, 10.0, True)
    last_reading = ekf.aid["laser"].last_fused
    rows = np.array(fly(ekf, feed, rng, 10.0, 10.0, False))
    assert ekf.aid["laser"].last_fused == last_reading
    assert np.abs(rows[:, 0]).max() < 0.5
    assert (np.abs(rows[:, 0]) <= 2 * rows[:, 1]).all()
    assert ekf.ground_range.refuted


SITE = {key: TOLD[key] for key in ("terrain_h", "P0_terrain", "terrain_psd")}
"""Told nothing but the site: every noise measured from its typical value."""


def standing_at(seed: int, h: float, **params) -> tuple[int | None, np.ndarray]:
    """10 s standing at ``h`` with every laser frame invalid: the step of the first laser
    fusion (None: never) and (error, h_std, status) per step."""
    ekf = AltitudeEKF(AltitudeEKF.Params(**params), step_size=STEP)
    feed, rng = StreamFeeder(ekf), np.random.default_rng(seed)
    rows = np.array(fly(ekf, feed, rng, 10.0, h, False))
    fused = np.flatnonzero(rows[:, 2].astype(np.int64) & LASER_FUSED)
    return (int(fused[0]) if fused.size else None), rows


def test_told_nothing_the_ground_is_presumed_and_read_from_the_start():
    """Told nothing, the height is known to ~10 m in the first seconds (the baro offset's
    prior, the first GNSS pairs' bounds): at 5σ the vehicle might be beyond the laser's
    25 m, and the ground was read only after 1.2-1.6 s, the height meanwhile following the
    GNSS's first samples (measured: 2.1-3.3 m off at most in 0.3-2 s). Presumed on the
    ground (PX4's land detector boots landed), at 2σ, it is read within 0.06 s (measured
    0.04-0.06 s) and the height stays within 0.12-0.29 m: asserted, the first fusion within
    0.1 s and the height within 0.5 m over 0.3-2 s, against beyond 1 m without the
    presumption. Seeds 1-8."""
    for seed in range(1, 9):
        first, rows = standing_at(seed, 0.0, **SITE)
        assert first is not None and first <= 10
        assert np.abs(rows[30:200, 0]).max() < 0.5
        first, rows = standing_at(seed, 0.0, **SITE, starts_on_ground=False)
        assert first is not None and first > 100
        assert np.abs(rows[30:200, 0]).max() > 1.0


def test_an_airborne_start_beyond_the_reach_is_not_read_as_the_ground():
    """Started hovering at 26 m and 40 m, just beyond the laser's 25 m and within the gate's
    reach of the ground reading (5σ of 10 m told nothing), every frame invalid: the height
    is never within 2σ of the reach, no frame is read as the ground, and the height stays
    on the hover (measured within 1.5 m after 9 s, told the noise or nothing; asserted
    2 m). Seeds 1-4."""
    for h in (26.0, 40.0):
        for told in (TOLD, SITE):
            for seed in range(1, 5):
                first, rows = standing_at(seed, h, **told)
                assert first is None
                assert np.abs(rows[-100:, 0]).max() < 2.0


def test_a_first_gnss_sample_far_off_leaves_the_height_on_the_told_ground():
    """Standing on the ground told (its invalid frames read as the ground from the start),
    the GNSS (the reference) told 0.6 m for its 3 m, as the evaluation's x0.2, its first
    sample 6 m high (10σ of the told): the told terrain is in the GNSS's datum, so the
    height tied to it is known there already and the sample is gated as any other, not
    taken as the datum. Measured: the height within 0.07-0.38 m of the ground from 1 s on
    (asserted: 1 m); before, the datum moved onto the sample, the terrain with it, and the
    height stood 4.4-6.3 m off. Seeds 1-4."""
    for seed in range(1, 5):
        ekf = AltitudeEKF(AltitudeEKF.Params(**{**TOLD, "gps_noise": 0.6}), step_size=STEP)
        feed, rng = StreamFeeder(ekf), np.random.default_rng(seed)
        heights = []
        for k in range(1000):
            r = rng.standard_normal(3)
            samples = {"acc": {"acc_z": 0.05 * r[0]},
                       "baro": {"baro_h": 3.0 + 0.5 * r[1], "baro_p": 1e5, "baro_T": 288.0},
                       "laser": {"laser_h": 0.0, "laser_valid": False}}
            if k % 20 == 19:
                samples["gps"] = {"gps_h": 6.0 if k == 19 else 3.0 * r[2], "gps_vz": 0.0,
                                  "gps_vdop": 0.0, "gps_nsat": 0, "gps_fix": True}
            feed.step(**samples)
            heights.append(ekf.h_est)
        assert np.abs(heights[100:]).max() < 1.0


def test_a_minimum_range_beyond_the_maximum_height_is_refused():
    with pytest.raises(ParameterError, match="laser_min_range"):
        AltitudeEKF(AltitudeEKF.Params(laser_min_range=30.0), step_size=STEP)
