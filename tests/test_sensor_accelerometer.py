"""Accelerometer: specific force with bias and noise, gravity removed (yang2020 eq. 4)."""

import math

import numpy as np
from sensor_runs import mean_tolerance, run, std_tolerance

from altfusion.sensors import Accelerometer, AccelerometerParams


def accelerometer(**params) -> Accelerometer:
    return Accelerometer(AccelerometerParams(**params), step_size=0.01)


def manoeuvre(t: float) -> dict[str, float]:
    return {"az": 0.2 * math.sin(t)}


def test_noise_and_bias_have_the_stated_values():
    sigma, bias, n = 0.01, 0.03, 20000
    series = run(accelerometer(noise_std=sigma, bias=bias, seed=1), n, ("acc_z",), manoeuvre)
    error = series["acc_z"] - 0.2 * np.sin(series["time"])
    assert abs(error.mean() - bias) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)


def test_gravity_is_removed_with_its_nominal_value():
    """The sensor feels az + g; subtracting a nominal g that differs from the true one leaves
    the difference in acc_z. Without noise both are exact up to rounding of the ~10 m/s²
    terms: ε·10 m/s² ≈ 2e-15 m/s² (bound 1e-12)."""
    exact = run(accelerometer(noise_std=0.0), 100, ("acc_z",), manoeuvre)
    assert np.allclose(exact["acc_z"], 0.2 * np.sin(exact["time"]), rtol=0, atol=1e-12)
    off = run(accelerometer(noise_std=0.0, gravity=9.81, nominal_gravity=9.80665), 100,
              ("acc_z",), manoeuvre)
    assert np.allclose(off["acc_z"] - exact["acc_z"], 9.81 - 9.80665, rtol=0, atol=1e-12)


def test_turn_on_bias_is_drawn_once_per_run_with_the_stated_sigma():
    bias, bias_std, runs = 0.02, 0.05, 2000
    first = []
    for seed in range(runs):
        sensor = accelerometer(noise_std=0.0, bias=bias, bias_std=bias_std, seed=seed)
        series = run(sensor, 50, ("acc_z",))
        assert np.all(series["acc_z"] == series["acc_z"][0])  # constant within a run
        first.append(series["acc_z"][0])
    first = np.array(first)
    assert abs(first.mean() - bias) < mean_tolerance(bias_std, runs)
    assert abs(first.std(ddof=1) - bias_std) < std_tolerance(bias_std, runs)


def test_the_turn_on_bias_does_not_change_the_noise_realization():
    """The bias has its own random stream: the two runs differ by the constant bias, up to
    rounding of the ~10 m/s² specific force (ε·10 m/s² ≈ 2e-15, bound 1e-12)."""
    plain = run(accelerometer(seed=4), 500, ("acc_z",))
    biased = run(accelerometer(seed=4, bias_std=0.1), 500, ("acc_z",))
    offset = biased["acc_z"] - plain["acc_z"]
    assert np.allclose(offset, offset[0], rtol=0, atol=1e-12) and offset[0] != 0
