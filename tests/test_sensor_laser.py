"""LaserRangefinder: ±5 mm at 100 Hz from 0.1 m to 25 m, reading 0 outside (xu2016)."""

import numpy as np
import pytest
from sensor_runs import mean_tolerance, run, std_tolerance

from altfusion.errors import ParameterError
from altfusion.sensors import LaserRangefinder, LaserRangefinderParams

OUTPUTS = ("laser_h", "laser_valid", "laser_count", "laser_time")


def laser(**params) -> LaserRangefinder:
    return LaserRangefinder(LaserRangefinderParams(**params), step_size=0.01)


def test_noise_has_the_stated_sigma_of_five_millimetres():
    sigma, n = 0.005, 20000
    series = run(laser(seed=1), n, OUTPUTS, lambda t: {"h": 112.0, "terrain_h": 100.0})
    error = series["laser_h"] - 12.0
    assert abs(error.mean()) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)


@pytest.mark.parametrize(("height", "valid"), [
    (0.05, False), (0.1, True), (12.0, True), (25.0, True), (25.01, False), (300.0, False),
])
def test_valid_from_0_1_to_25_m_and_zero_outside(height, valid):
    series = run(laser(noise_std=0.0), 10, OUTPUTS, lambda t: {"h": height, "terrain_h": 0.0})
    assert np.all(series["laser_valid"] == valid)
    assert np.all(series["laser_h"] == (height if valid else 0.0))


def test_out_of_range_frames_are_counted_and_time_stamped():
    def profile(t):  # 0.01 s steps: above 25 m during (1, 2] s
        return {"h": 30.0 if 1.0 < t <= 2.0 else 20.0, "terrain_h": 0.0}

    series = run(laser(), 300, OUTPUTS, profile)
    assert np.array_equal(series["laser_count"], np.arange(1, 301))
    assert np.array_equal(series["laser_time"], series["time"])
    out = ~series["laser_valid"]
    assert out.sum() == 100 and np.all(series["laser_h"][out] == 0.0)


def test_an_empty_range_is_rejected():
    with pytest.raises(ParameterError, match="'min_range' = 30.0: must be below max_range"):
        laser(min_range=30.0)
