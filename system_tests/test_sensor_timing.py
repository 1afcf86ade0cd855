"""Sensor timing through fmpy: counts, time stamps, latency and outages over one hour at a
0.01 s base step, with each sensor stepped at its own period and at the base step."""

import numpy as np
import pytest

from altfusion.cosim import CosimError, Simulation
from altfusion.systems.spec import ComponentSpec, SystemSpec

HOUR = 3600.0
INTERVAL = 0.2
"""Recording interval: the air-data period, so every air-data sample is seen."""

SIGNALS = ("baro_count", "baro_time", "baro_h", "gps_count", "gps_time", "gps_h", "gps_fix")


def hour_system() -> SystemSpec:
    """The same AirDataModule and GnssReceiver (same seeds) twice: stepped at their own
    periods (0.2 s, 1 s) and at the 0.01 s base step. Unconnected inputs stay at their
    defaults (ISA sea level, at rest): every sample differs only by its noise."""
    components = (
        ComponentSpec("air_slow", "AirDataModule", 0.2, {"seed": 11}),
        ComponentSpec("gnss_slow", "GnssReceiver", 1.0, {"seed": 12}),
        ComponentSpec("air_fast", "AirDataModule", 0.01, {"seed": 11}),
        ComponentSpec("gnss_fast", "GnssReceiver", 0.01, {"seed": 12}),
    )
    record = tuple(f"{c.name}.{s}" for c in components for s in SIGNALS
                   if s.startswith("baro") == (c.fmu == "AirDataModule"))
    return SystemSpec(name="sensor_hour", description="air data and GNSS for one hour",
                      components=components, connections=(), stop_time=HOUR,
                      output_interval=INTERVAL, record=record)


@pytest.fixture(scope="module")
def hour(fmus):
    """One hour without and with latency (air data 0.4 s, GNSS 2 s) and a 30 s outage."""
    with Simulation(hour_system(), fmus) as simulation:
        prompt = simulation.run()
        late = simulation.run(parameters={
            "air_slow.latency": 0.4, "air_fast.latency": 0.4,
            "gnss_slow.latency": 2.0, "gnss_fast.latency": 2.0,
            "gnss_slow.outage_windows": "1000 1030", "gnss_fast.outage_windows": "1000 1030",
        })
    return prompt, late


@pytest.mark.parametrize("pace", ["slow", "fast"])
def test_one_hour_gives_exact_counts_and_exact_time_stamps(hour, pace):
    results, _ = hour
    rows = np.arange(len(results.time))  # row k is t = k·0.2 s
    assert np.array_equal(results.time, rows / 5)
    air, gnss = f"air_{pace}", f"gnss_{pace}"
    assert results[f"{air}.baro_count"][-1] == HOUR / 0.2 == 18000
    assert results[f"{gnss}.gps_count"][-1] == HOUR / 1.0 == 3600
    assert np.array_equal(results[f"{air}.baro_count"], rows)
    assert np.array_equal(results[f"{air}.baro_time"], rows / 5)  # k/5 correctly rounded
    assert np.array_equal(results[f"{gnss}.gps_count"], rows // 5)
    assert np.array_equal(results[f"{gnss}.gps_time"], (rows // 5).astype(float))


def test_the_communication_step_does_not_change_any_sample(hour):
    for results in hour:
        for signal in SIGNALS:
            prefix = "air" if signal.startswith("baro") else "gnss"
            slow, fast = results[f"{prefix}_slow.{signal}"], results[f"{prefix}_fast.{signal}"]
            assert np.array_equal(slow, fast), signal


@pytest.mark.parametrize("pace", ["slow", "fast"])
def test_latency_shifts_every_sample_by_exactly_the_latency(hour, pace):
    prompt, late = hour
    for prefix, signals, latency in (("air", ("baro_count", "baro_time", "baro_h"), 0.4),
                                     ("gnss", ("gps_count", "gps_time", "gps_h"), 2.0)):
        shift = round(latency / INTERVAL)
        for signal in signals:
            name = f"{prefix}_{pace}.{signal}"
            if prefix == "gnss":  # compare before the outage of the late run
                window = slice(shift, round(1000 / INTERVAL))
                shifted = slice(0, window.stop - shift)
            else:
                window, shifted = slice(shift, None), slice(0, -shift)
            assert np.array_equal(late[name][window], prompt[name][shifted]), name
        assert np.all(late[f"{prefix}_{pace}.{signals[0]}"][:shift] == 0)


@pytest.mark.parametrize("pace", ["slow", "fast"])
def test_a_thirty_second_outage_removes_exactly_thirty_gnss_samples(hour, pace):
    prompt, late = hour
    t = late.time
    count, fix = late[f"gnss_{pace}.gps_count"], late[f"gnss_{pace}.gps_fix"]
    # 3600 fixes, less the 30 in the window, less the 2 taken in the last 2 s (still in flight)
    assert prompt[f"gnss_{pace}.gps_count"][-1] == 3600 and count[-1] == 3600 - 30 - 2
    # the samples taken in [1000, 1030) are missing, each delivered 2 s late
    no_fix = (t >= 1002) & (t < 1032)
    assert np.array_equal(fix == 0, no_fix | (t < 3))
    held = count[no_fix]
    assert np.all(held == held[0]) and held[0] == 999
    assert np.all(late[f"gnss_{pace}.gps_time"][no_fix] == 999.0)
    # after the outage the noise realization is the one without outage, 2 s later
    after = t >= 1032
    shifted = np.flatnonzero(after) - 10
    assert np.array_equal(late[f"gnss_{pace}.gps_h"][after],
                          prompt[f"gnss_{pace}.gps_h"][shifted])


@pytest.mark.parametrize(("component", "parameters", "message"), [
    ("gnss_slow", {"gnss_slow.sample_period": 1.5},
     r"'sample_period' = 1\.5: must be a multiple of the step size 1\.0 s"),
    ("air_slow", {"air_slow.sample_period": 0.0}, r"'sample_period' = 0\.0: must be > 0"),
    ("air_fast", {"air_fast.latency": 0.005},
     r"'latency' = 0\.005: must be a multiple of the step size 0\.01 s"),
    ("gnss_fast", {"gnss_fast.user_range_error": -1.0},
     r"'user_range_error' = -1\.0: must be >= 0\.0"),
    ("air_fast", {"air_fast.height_noise_std": -0.5},
     r"'height_noise_std' = -0\.5: must be >= 0\.0"),
])
def test_bad_parameters_fail_initialization_naming_the_parameter(fmus, component, parameters,
                                                                 message):
    with Simulation(hour_system(), fmus) as simulation:
        with pytest.raises(CosimError, match=rf"'{component}'.*{message}"):
            simulation.run(stop_time=1.0, parameters=parameters)
        good = simulation.run(stop_time=1.0)  # the instances survive
    assert good["air_slow.baro_count"][-1] == 5
