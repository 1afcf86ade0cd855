"""The sampling mechanism every sensor shares: schedule, latency, count, time stamp, seeds."""

import copy
import math
from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest
from sensor_runs import Z999, run

from altfusion.errors import ParameterError
from altfusion.sensors import (
    Accelerometer,
    AirDataModule,
    GnssReceiver,
    LaserRangefinder,
    RadioAltimeter,
)
from altfusion.sensors.sampling import NORMAL_BATCH, NormalDraws

SENSORS = (AirDataModule, GnssReceiver, Accelerometer, RadioAltimeter, LaserRangefinder)


def make(cls, step=0.01, start_time=0.0, **params):
    return cls(cls.Params(**params), step_size=step, start_time=start_time)


def deliveries(sensor, steps):
    """(count, time stamp) after every step."""
    prefix = sensor.prefix
    series = run(sensor, steps, (f"{prefix}_count", f"{prefix}_time"))
    return series["time"], series[f"{prefix}_count"], series[f"{prefix}_time"]


@pytest.mark.parametrize("cls", SENSORS)
def test_default_period_gives_the_exact_count_and_exact_time_stamps(cls):
    sensor = make(cls)
    period = Fraction(repr(cls.Params().sample_period))
    steps = 6000  # 60 s at the 0.01 s base step
    t, count, stamp = deliveries(sensor, steps)
    assert count[-1] == Fraction(60) / period
    # after step n (t = n/100) the k-th sample, k = floor(t/period), was taken at k·period
    expected_k = [int(Fraction(n + 1, 100) / period) for n in range(steps)]
    assert list(count) == expected_k
    assert all(s == float(k * period) for s, k in zip(stamp, expected_k, strict=True))


def test_before_the_first_sample_the_count_is_zero_and_the_stamp_is_the_start_time():
    sensor = make(RadioAltimeter, start_time=2.0)
    assert (sensor.radar_count, sensor.radar_time, sensor.radar_valid) == (0, 2.0, False)
    assert sensor.radar_h == 0.0
    run(sensor, 19, ())
    assert (sensor.radar_count, sensor.radar_time) == (0, 2.0)
    run(sensor, 1, ())
    assert (sensor.radar_count, sensor.radar_time) == (1, 2.2)


def test_samples_fall_on_offset_plus_multiples_of_the_period_strictly_after_the_start():
    # offset 0.05 s, period 0.2 s, start 0.45 s: 0.45 itself is not a sampling instant;
    # the first is 0.65 s = 0.05 + 3·0.2
    sensor = make(AirDataModule, start_time=0.45, sample_offset=0.05)
    t, count, stamp = deliveries(sensor, 400)
    new = np.flatnonzero(np.diff(np.concatenate([[0], count])))
    assert t[new[0]] == 0.65
    assert all(stamp[i] == float(Fraction(1, 20) + Fraction(2 * k + 6, 10))
               for k, i in enumerate(new))
    # a start time on a sampling instant: the first sample is one period later
    on_grid = make(AirDataModule, start_time=0.4)
    run(on_grid, 20, ())
    assert (on_grid.baro_count, on_grid.baro_time) == (1, 0.6)


def test_the_communication_step_does_not_change_the_samples():
    fine = make(AirDataModule, step=0.01, seed=4)
    coarse = make(AirDataModule, step=0.2, seed=4)
    names = ("baro_count", "baro_time", "baro_h", "baro_p", "baro_T")
    fine_run = run(fine, 3000, names)
    coarse_run = run(coarse, 150, names)
    for name in names:
        assert np.array_equal(fine_run[name][19::20], coarse_run[name]), name


@pytest.mark.parametrize(("latency", "step"), [(0.05, 0.01), (0.5, 0.01), (1.0, 0.2)])
def test_latency_delays_every_sample_by_exactly_the_latency(latency, step):
    names = ("baro_count", "baro_time", "baro_h")
    steps = round(30 / step)
    prompt = run(make(AirDataModule, step=step, seed=9), steps, names)
    late = run(make(AirDataModule, step=step, seed=9, latency=latency), steps, names)
    shift = round(latency / step)
    for name in names:
        assert np.array_equal(late[name][shift:], prompt[name][:-shift]), name
    assert np.all(late["baro_count"][:shift] == 0)
    # the time stamp is the sampling instant, delivered latency later
    delivered = np.flatnonzero(np.diff(late["baro_count"])) + 1
    assert np.allclose(late["time"][delivered] - late["baro_time"][delivered], latency,
                       rtol=0, atol=1e-12)


@pytest.mark.parametrize("cls", SENSORS)
@pytest.mark.parametrize(("params", "message"), [
    ({"sample_period": 0.015}, "'sample_period' = 0.015: must be a multiple of the step size"),
    ({"sample_period": 0.0}, "'sample_period' = 0.0: must be > 0"),
    ({"latency": 0.005}, "'latency' = 0.005: must be a multiple of the step size"),
    ({"latency": -0.01}, "'latency' = -0.01: must be >= 0.0"),
    ({"sample_offset": 0.004}, "'sample_offset' = 0.004: minus the start time"),
    ({"seed": -1}, "'seed' = -1: must be >= 0"),
])
def test_bad_sampling_parameters_are_rejected_naming_the_parameter(cls, params, message):
    with pytest.raises(ParameterError) as error:
        make(cls, **params)
    assert message in str(error.value)


@pytest.mark.parametrize(("cls", "name"), [
    (AirDataModule, "height_noise_std"), (AirDataModule, "temperature_noise_std"),
    (GnssReceiver, "user_range_error"), (GnssReceiver, "velocity_noise_std"),
    (Accelerometer, "noise_std"), (RadioAltimeter, "noise_std"), (LaserRangefinder, "noise_std"),
])
def test_a_negative_standard_deviation_is_rejected_naming_the_parameter(cls, name):
    with pytest.raises(ParameterError, match=f"'{name}' = -1.0: must be >= 0.0"):
        make(cls, **{name: -1.0})


@pytest.mark.parametrize(("cls", "name"), [
    (AirDataModule, "p_static"), (AirDataModule, "T_air"), (AirDataModule, "wind_speed"),
    (GnssReceiver, "h"), (GnssReceiver, "vz"), (Accelerometer, "az"),
    (RadioAltimeter, "h"), (RadioAltimeter, "terrain_h"), (LaserRangefinder, "terrain_h"),
])
def test_a_non_finite_input_is_a_clear_error_and_never_a_nan_output(cls, name):
    sensor = make(cls, sample_period=0.01)
    run(sensor, 3, ())
    before = copy.deepcopy(vars(sensor))
    setattr(sensor, name, math.nan)
    with pytest.raises(ValueError, match=f"input {name} = nan is not finite"):
        sensor.do_step(sensor.time, sensor.dt)
    for key, value in vars(sensor).items():
        if key.startswith(sensor.prefix):
            assert value == before[key], key


@pytest.mark.parametrize("cls", SENSORS)
def test_the_same_seed_gives_identical_outputs_and_another_seed_different_ones(cls):
    names = tuple(k for k in vars(make(cls)) if k.startswith(cls.prefix))
    params = {"sample_period": 0.01}
    inputs = {LaserRangefinder: {"h": 10.0}}.get(cls, {})
    first = run(make(cls, seed=5, **params), 200, names, lambda t: inputs)
    again = run(make(cls, seed=5, **params), 200, names, lambda t: inputs)
    other = run(make(cls, seed=6, **params), 200, names, lambda t: inputs)
    assert all(np.array_equal(first[n], again[n]) for n in names)
    assert any(not np.array_equal(first[n], other[n]) for n in names)


def test_different_sensors_with_the_same_seed_draw_independent_noise():
    n = 20000
    radar = run(make(RadioAltimeter, sample_period=0.01, noise_std=1.0), n, ("radar_h",))
    laser = run(make(LaserRangefinder, sample_period=0.01, noise_std=1.0, max_range=1e3),
                n, ("laser_h",), lambda t: {"h": 100.0})
    radar_noise, laser_noise = radar["radar_h"], laser["laser_h"] - 100.0
    correlation = np.corrcoef(radar_noise, laser_noise)[0, 1]
    # sample correlation of independent series: 99.9 % interval ±z/√N
    assert abs(correlation) < Z999 / math.sqrt(n)


def test_a_restored_copy_continues_identically():
    sensor = make(GnssReceiver, sample_period=0.1, gm_std=2.0, outage_rate=0.05,
                  dop_mode="random", latency=0.3)
    run(sensor, 500, ())
    saved = copy.deepcopy(sensor)
    names = ("gps_h", "gps_count", "gps_time", "gps_nsat", "gps_fix")
    assert all(np.array_equal(a, b) for a, b in zip(run(sensor, 500, names).values(),
                                                    run(saved, 500, names).values(),
                                                    strict=True))


def test_params_of_every_sensor_extend_the_shared_sampling_params():
    for cls in SENSORS:
        fields = list(vars(cls.Params()))
        assert fields[:4] == ["seed", "sample_period", "sample_offset", "latency"], cls
        assert replace(cls.Params(), seed=3).seed == 3


@pytest.mark.parametrize("host_step", [0.001, 0.03, 0.25, 1.0])
def test_any_host_step_gives_the_same_samples_and_the_count_rises_by_the_number_taken(
        host_step):
    """A GNSS on a 0.01 s tick sampling every 0.1 s at a constant height: whatever the host's
    step, after a step ending at t the count is the number of instants k·0.1 <= t, the stamp
    the last of them and the held value the fixed-step sensor's for that sample, draw for draw
    (a step of 0.25 s takes two or three samples at once)."""
    reference = make(GnssReceiver, sample_period=0.1)
    reference.h = 100.0
    samples = {}
    for n in range(300):
        reference.do_step(n * 0.01, 0.01)
        samples[reference.gps_count] = (reference.gps_time, reference.gps_h)
    sensor = make(GnssReceiver, sample_period=0.1)
    sensor.h = 100.0
    time = 0.0
    while time < 3.0 - 1e-9:
        sensor.do_step(time, host_step)
        time += host_step
        assert sensor.gps_count == math.floor(time / 0.1 + 1e-9)
        assert (sensor.gps_time, sensor.gps_h) == samples[sensor.gps_count]
    assert sensor.gps_count == 30


def test_normal_draws_are_numpys_scalar_draws_bit_for_bit():
    """NormalDraws hands out exactly the numbers of one standard_normal() call each, across
    batch boundaries (a batch of 7 here, the sensors' 256) and for several seeds."""
    for seed in (0, 1, 12345):
        for batch in (7, NORMAL_BATCH):
            draws = NormalDraws(np.random.default_rng(seed), batch)
            scalar = np.random.default_rng(seed)
            for _ in range(3 * batch + 2):
                expected = scalar.standard_normal()
                drawn = draws.draw()
                assert type(drawn) is float and drawn == expected
