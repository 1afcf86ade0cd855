"""GnssReceiver: noise scaled by VDOP and satellites, Gauss-Markov error, geometry modes,
scheduled and random outages."""

import math

import numpy as np
import pytest
from sensor_runs import Z999, mean_tolerance, run, std_tolerance

from altfusion.errors import ParameterError
from altfusion.sensors import GnssParams, GnssReceiver

OUTPUTS = ("gps_h", "gps_vz", "gps_vdop", "gps_nsat", "gps_fix", "gps_count", "gps_time")


def receiver(step: float = 1.0, **params) -> GnssReceiver:
    return GnssReceiver(GnssParams(**{"sample_period": step, **params}), step_size=step)


def moving(t: float) -> dict[str, float]:
    return {"h": 500.0 + 3.0 * t, "vz": 3.0}


def fixes(series: dict[str, np.ndarray]) -> np.ndarray:
    """Indices of the steps at which a new fix was delivered."""
    return np.flatnonzero(np.diff(np.concatenate([[0], series["gps_count"]])))


def test_height_noise_is_uere_times_vdop_with_the_stated_bias():
    uere, vdop, bias, n = 3.0, 2.0, -1.5, 20000
    series = run(receiver(user_range_error=uere, vdop=vdop, height_bias=bias, seed=1), n,
                 OUTPUTS, moving)
    error = series["gps_h"] - (500.0 + 3.0 * series["time"])
    sigma = uere * vdop
    assert abs(error.mean() - bias) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)
    assert np.all(series["gps_vdop"] == vdop) and np.all(series["gps_nsat"] == 10)
    assert np.all(series["gps_fix"])


def test_height_noise_grows_when_satellites_fall_below_the_reference_count():
    uere, vdop, n = 2.0, 1.5, 20000
    series = run(receiver(user_range_error=uere, vdop=vdop, nsat=4, nsat_reference=6,
                          seed=2), n, OUTPUTS, moving)
    error = series["gps_h"] - (500.0 + 3.0 * series["time"])
    sigma = uere * vdop * math.sqrt(6 / 4)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)


def test_vertical_velocity_noise_has_the_stated_sigma():
    sigma, n = 0.2, 20000
    series = run(receiver(seed=3), n, OUTPUTS, moving)
    error = series["gps_vz"] - 3.0
    assert abs(error.mean()) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)


def test_scheduled_vdop_and_satellites_set_the_noise_of_each_segment():
    uere, n = 2.0, 30000
    series = run(receiver(user_range_error=uere, dop_mode="scheduled",
                          vdop_schedule="0 1; 10000 3", nsat_schedule="0 10; 20000 5",
                          seed=4), n, OUTPUTS, moving)
    t = series["time"]
    error = series["gps_h"] - (500.0 + 3.0 * t)
    segments = [(t < 10000, 1.0, 10, uere), ((t >= 10000) & (t < 20000), 3.0, 10, 3 * uere),
                (t >= 20000, 3.0, 5, 3 * uere * math.sqrt(6 / 5))]
    for window, vdop, nsat, sigma in segments:
        assert np.all(series["gps_vdop"][window] == vdop)
        assert np.all(series["gps_nsat"][window] == nsat)
        count = int(window.sum())
        assert abs(error[window].std(ddof=1) - sigma) < std_tolerance(sigma, count)


def test_fewer_than_four_satellites_means_no_fix():
    series = run(receiver(dop_mode="scheduled", nsat_schedule="0 8; 100 3; 200 8"), 300,
                 OUTPUTS, moving)
    t = series["time"]
    no_fix = (t >= 100) & (t < 200)
    assert np.array_equal(series["gps_fix"], ~no_fix)
    assert series["gps_count"][-1] == 200


def test_random_geometry_stays_in_bounds_and_vdop_follows_the_satellite_count():
    series = run(receiver(dop_mode="random", vdop=1.2, nsat=8, nsat_min=5, nsat_max=11,
                          nsat_change_time=20.0, seed=5), 20000, OUTPUTS, moving)
    nsat = series["gps_nsat"]
    assert nsat.min() == 5 and nsat.max() == 11
    assert np.all(np.abs(np.diff(nsat)) <= 1)
    # the receiver computes this very formula: rounding only (a few ε = 2.2e-16 relative)
    assert np.allclose(series["gps_vdop"], 1.2 * np.sqrt(8 / nsat), rtol=1e-12)
    # a ±1 step with probability 1 - exp(-1/20) per sample, held at the bounds: at most that
    # many changes (binomial, 99.9 % upper bound)
    p = -math.expm1(-1 / 20)
    changes = np.count_nonzero(np.diff(nsat))
    assert changes < 20000 * p + Z999 * math.sqrt(20000 * p * (1 - p))


def test_gauss_markov_error_has_the_stated_sigma_and_correlation_time():
    """AR(1) with φ = exp(-Δt/τ): the least-squares φ̂ has standard deviation √((1-φ²)/N);
    the sample variance of N correlated samples has standard deviation
    σ²·√(2(1+φ²)/((1-φ²)N)), hence the tolerance on the standard deviation below."""
    sigma, tau, n = 5.0, 100.0, 40000
    series = run(receiver(user_range_error=0.0, gm_std=sigma, gm_time_constant=tau, seed=6),
                 n, OUTPUTS, moving)
    error = series["gps_h"] - (500.0 + 3.0 * series["time"])
    phi = math.exp(-1.0 / tau)
    phi_hat = np.dot(error[:-1], error[1:]) / np.dot(error[:-1], error[:-1])
    assert abs(phi_hat - phi) < Z999 * math.sqrt((1 - phi**2) / n)
    inflation = math.sqrt((1 + phi**2) / (1 - phi**2))
    assert abs(error.std() - sigma) < Z999 * sigma * inflation / math.sqrt(2 * n)


def test_a_scheduled_outage_holds_the_outputs_and_removes_exactly_its_samples():
    series = run(receiver(outage_windows="100 130; 500 500.5"), 1000, OUTPUTS, moving)
    t = series["time"]
    outage = ((t >= 100) & (t < 130)) | (t == 500)
    assert np.array_equal(series["gps_fix"], ~outage)
    assert series["gps_count"][-1] == 1000 - 31
    for first, last in ((99, 128), (499, 499)):  # step i ends at t = i + 1 s
        for name in ("gps_h", "gps_vz", "gps_time", "gps_count", "gps_vdop", "gps_nsat"):
            assert np.all(series[name][first:last + 1] == series[name][first - 1]), name
    assert series["gps_time"][128] == 99.0
    assert series["gps_time"][130] == 131.0 and series["gps_count"][130] == 101


def test_random_outages_have_the_stated_rate_and_mean_duration():
    """Alternating renewal: up times exponential with mean 1/rate, outages exponential with
    mean D, observed on 1 s samples. An observed duration is the number of missing samples:
    its mean is D (uniform phase) and its variance at most D² + 1/4. Two outages merge when an
    up time is below 1 s (probability 1 - exp(-rate·1 s) = 0.5 %): a bias of about 0.1 s on
    the mean duration, far inside the tolerance."""
    rate, duration, n = 1 / 200, 20.0, 200000
    series = run(receiver(outage_rate=rate, outage_mean_duration=duration, seed=7), n,
                 ("gps_fix",))
    fix = series["gps_fix"].astype(int)
    edges = np.diff(fix)
    starts, ends = np.flatnonzero(edges == -1) + 1, np.flatnonzero(edges == 1) + 1
    if ends[0] < starts[0]:
        ends = ends[1:]
    outages = (ends - starts[:len(ends)]).astype(float)
    ups = (starts[1:len(ends)] - ends[:-1]).astype(float) if len(ends) > 1 else np.array([])
    count = len(outages)
    assert abs(outages.mean() - duration) < mean_tolerance(math.sqrt(duration**2 + 0.25), count)
    assert abs(ups.mean() - 1 / rate) < mean_tolerance(math.sqrt((1 / rate) ** 2 + 0.25),
                                                       len(ups))


def test_outages_do_not_shift_the_noise_of_later_fixes():
    clean = run(receiver(seed=9), 300, OUTPUTS, moving)
    broken = run(receiver(seed=9, outage_windows="50 80", outage_rate=0.02), 300, OUTPUTS,
                 moving)
    valid = broken["gps_fix"]
    assert np.array_equal(broken["gps_h"][valid], clean["gps_h"][valid])


def test_before_the_first_fix_the_receiver_reports_no_solution():
    sensor = receiver(step=0.01)
    assert (sensor.gps_fix, sensor.gps_count, sensor.gps_nsat, sensor.gps_vdop) == (
        False, 0, 0, 99.99)


@pytest.mark.parametrize(("params", "message"), [
    ({"dop_mode": "sometimes"}, "'dop_mode' = 'sometimes': must be one of"),
    ({"vdop_schedule": "0 1; 10 2"}, "'dop_mode' = 'constant': must be 'scheduled' exactly"),
    ({"dop_mode": "scheduled"}, "'dop_mode' = 'scheduled': must be 'scheduled' exactly"),
    ({"dop_mode": "scheduled", "nsat_schedule": "0 7.5"}, "'nsat_schedule' = '0 7.5'"),
    ({"dop_mode": "scheduled", "vdop_schedule": "0 0"}, "VDOP values must be > 0"),
    ({"dop_mode": "random", "nsat": 3}, "'nsat' = 3: must lie in [nsat_min, nsat_max]"),
    ({"outage_windows": "100 90"}, "each window must end after it starts"),
    ({"outage_windows": "100"}, "'outage_windows' = '100': each row needs 2 numbers"),
    ({"gm_time_constant": 0.0}, "'gm_time_constant' = 0.0: must be > 0"),
])
def test_bad_gnss_parameters_are_rejected_naming_the_parameter(params, message):
    with pytest.raises(ParameterError) as error:
        receiver(**params)
    assert message in str(error.value)
