"""The GNSS height reference handed over to a rangefinder over a known terrain
(altfusion.estimators.reference_handover) in AltitudeEKF.

The flight: the fault suite's all_fail scaled down tenfold. A hover at 10 m over flat ground
told exactly (terrain_h 0, P0_terrain 1e-8), the estimator stepped every 0.05 s, every sensor
told its true noise: accelerometer every step (σ 0.01 m/s²), baro every step (σ 2 m), GNSS
every 0.1 s (σ 3 m, the height reference), laser every 0.2 s (σ 1 m: the rangefinder more
informative than the GNSS, 5 against 1.1 m⁻² per second, as the fault flight's radio
altimeter). From 60 s the GNSS reads 1 m high and the baro 0.5 m: within their noise, and
the GNSS's below the fault layer's bias test (its 2.5 s mean is known to 0.6 m: 1.7σ).
Seeds 1-8, fixed.
"""

import sys
from pathlib import Path

import numpy as np

from altfusion.estimators.altitude_ekf import AltitudeEKF

sys.path.insert(0, str(Path(__file__).parent))
from stream_feeder import StreamFeeder  # noqa: E402

STEP = 0.05
TRUE_H = 10.0
SHIFT_AT = 60.0
TOLD = {"baro_noise": 2.0, "gps_noise": 3.0, "gps_vz_noise": 0.2, "acc_noise": 0.01,
        "laser_noise": 1.0, "terrain_h": 0.0, "P0_terrain": 1e-8, "terrain_psd": 0.0}
SEEDS = range(1, 9)


def hover(seed: int, shift: float, seconds: float = 150.0, **params) -> np.ndarray:
    """The hover, the GNSS ``shift`` m and the baro half of it off from :data:`SHIFT_AT`:
    (time, error, h_std, gps_bias) per step."""
    ekf = AltitudeEKF(AltitudeEKF.Params(**{**TOLD, **params}), step_size=STEP)
    feed, rng = StreamFeeder(ekf), np.random.default_rng(seed)
    rows = []
    for k in range(round(seconds / STEP)):
        t = k * STEP
        off = shift if t >= SHIFT_AT else 0.0
        r = rng.standard_normal(5)
        samples = {"acc": {"acc_z": 0.01 * r[0]},
                   "baro": {"baro_h": TRUE_H + off / 2 + 2.0 * r[1], "baro_p": 1e5,
                            "baro_T": 288.0}}
        if k % 2 == 1:
            samples["gps"] = {"gps_h": TRUE_H + off + 3.0 * r[2], "gps_vz": 0.2 * r[3],
                              "gps_vdop": 0.0, "gps_nsat": 0, "gps_fix": True}
        if k % 4 == 3:
            samples["laser"] = {"laser_h": TRUE_H + r[4], "laser_valid": True}
        feed.step(**samples)
        rows.append((t, ekf.h_est - TRUE_H, ekf.h_std, ekf.gps_bias))
    return np.array(rows)


def coverage(rows: np.ndarray, since: float) -> float:
    """Share of the steps from ``since`` with |e| <= 2 h_std."""
    last = rows[rows[:, 0] >= since]
    return float(np.mean(np.abs(last[:, 1]) <= 2.0 * last[:, 2]))


def test_a_gnss_reference_shifted_within_its_noise_hands_the_datum_to_the_terrain():
    """The shift shows over 30 s (the GNSS's mean known to 0.17 m there: 1 m is 5.8σ) while
    the laser agrees with the prediction: the datum goes to the terrain and the GNSS gets its
    offset (``gps_bias`` non-zero: it is frozen at 0 while the GNSS is the reference), 15-45 s
    after the shift (measured; asserted: within 60 s). The last 60 s are then honest:
    |e| <= 2 h_std 88-100 % of the steps per seed (asserted: the fault suite's 85 %), where
    without the hand-over (``gps_handover`` false) the height follows the shifted GNSS at
    its weight under an h_std of the averages, 73-96 % (mean over the seeds 0.97 against
    0.85; asserted: at least 0.05 apart, the seeds' spread of the difference about 0.03)."""
    handed, kept = [], []
    for seed in SEEDS:
        rows = hover(seed, 1.0)
        moved = rows[rows[:, 3] != 0.0, 0]
        assert moved.size and moved[0] - SHIFT_AT <= 60.0
        handed.append(coverage(rows, 90.0))
        assert handed[-1] >= 0.85
        rows = hover(seed, 1.0, gps_handover=False)
        assert not rows[:, 3].any()
        kept.append(coverage(rows, 90.0))
    assert np.mean(handed) - np.mean(kept) >= 0.05


def test_a_gnss_reference_as_told_is_not_handed_over():
    """No shift: over 150 s (four full windows) the GNSS stays the reference in every seed
    (a consistent mean beyond 5σ once in 1.7 million windows)."""
    for seed in SEEDS:
        assert not hover(seed, 0.0)[:, 3].any()
