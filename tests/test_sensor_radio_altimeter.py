"""RadioAltimeter: height above the terrain with noise, invalid beyond its range (yang2020)."""

import numpy as np
from sensor_runs import mean_tolerance, run, std_tolerance

from altfusion.sensors import RadioAltimeter, RadioAltimeterParams

OUTPUTS = ("radar_h", "radar_valid", "radar_count", "radar_time")


def altimeter(**params) -> RadioAltimeter:
    return RadioAltimeter(RadioAltimeterParams(**params), step_size=0.2)


def test_noise_has_the_stated_sigma_above_sloping_terrain():
    sigma, n = 10.0, 20000
    series = run(altimeter(seed=1), n, OUTPUTS,
                 lambda t: {"h": 800.0, "terrain_h": 100.0 + 0.01 * t})
    error = series["radar_h"] - (700.0 - 0.01 * series["time"])
    assert abs(error.mean()) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)
    assert np.all(series["radar_valid"]) and series["radar_count"][-1] == n


def test_beyond_the_maximum_range_the_reading_holds_and_is_invalid():
    def climb(t):  # 0.2 s steps: above 1000 m from t = 100.2 s to 200 s
        return {"h": 1500.0 if 100.0 < t <= 200.0 else 900.0, "terrain_h": 0.0}

    series = run(altimeter(max_range=1000.0, seed=2), 1500, OUTPUTS, climb)
    t = series["time"]
    out = (t > 100.0) & (t <= 200.0)
    assert np.array_equal(series["radar_valid"], ~out)
    first, last = np.flatnonzero(out)[[0, -1]]
    for name in ("radar_h", "radar_count", "radar_time"):
        assert np.all(series[name][first:last + 1] == series[name][first - 1]), name
    assert series["radar_time"][last] == 100.0
    assert series["radar_count"][-1] == 1500 - out.sum()
    assert series["radar_time"][last + 1] == t[last + 1]


def test_below_the_terrain_there_is_no_measurement():
    series = run(altimeter(), 5, OUTPUTS, lambda t: {"h": 10.0, "terrain_h": 20.0})
    assert not series["radar_valid"].any() and series["radar_count"][-1] == 0
