"""The plant and the five sensor FMUs through fmpy: the sensors_yang2020 system."""

import math
from statistics import NormalDist

import numpy as np
import pytest
from state_restore import assert_restores_identically

from altfusion.cosim import CosimError, Simulation, simulate
from altfusion.cosim.instances import FmuInstance, fmu_info
from altfusion.systems import build_system
from altfusion.systems.sensors import SEED_003_SENSORS, SENSORS

Z999 = 3.29
"""Two-sided 99.9 % normal quantile: sample σ of N normal values lies within σ ± z·σ/√(2N)."""


@pytest.fixture(scope="module")
def yang(fmus):
    return simulate(build_system("sensors_yang2020"), fmus)


def test_every_sensor_counts_its_samples_over_the_420_s_flight(yang):
    assert yang["air_data.baro_count"][-1] == 420 / 0.01
    assert yang["gnss.gps_count"][-1] == 420 / 0.1
    assert yang["radar.radar_count"][-1] == 420 / 0.2


@pytest.mark.parametrize(("measured", "truth", "sigma", "period"), [
    ("air_data.baro_h", "plant.h", SEED_003_SENSORS["air_data"]["height_noise_std"], 0.1),
    ("gnss.gps_h", "plant.h", SEED_003_SENSORS["gnss"]["user_range_error"], 0.1),
    ("gnss.gps_vz", "plant.vz", SEED_003_SENSORS["gnss"]["velocity_noise_std"], 0.1),
    ("radar.radar_h", "plant.h", SEED_003_SENSORS["radar"]["noise_std"], 0.2),
    ("accelerometer.acc_z", "plant.az", SEED_003_SENSORS["accelerometer"]["noise_std"], 0.1),
])
def test_each_sensor_error_has_seed_003s_sigma_in_flight(yang, measured, truth, sigma, period):
    """yang2020 Section 4.2's error levels, seen on the recorded samples taken at the
    recording instants (so no sampling lag enters the error): the barometer's 20 m is a
    height noise, independent of the altitude."""
    every = round(period / 0.1)
    rows = np.arange(every, len(yang.time), every)  # recording instants on the sample grid
    error = yang[measured][rows] - yang[truth][rows]
    n = len(rows)
    assert abs(error.std(ddof=1) - sigma) < Z999 * sigma / math.sqrt(2 * n)
    assert abs(error.mean()) < Z999 * sigma / math.sqrt(n)


def test_the_laser_is_valid_only_below_25_m_and_reads_zero_above(yang):
    h, valid, laser_h = yang["plant.h"], yang["laser.laser_valid"], yang["laser.laser_h"]
    settled = yang.time > 0  # the first frame comes at 0.01 s
    assert np.array_equal(valid[settled] == 1, (h[settled] >= 0.1) & (h[settled] <= 25.0))
    assert np.all(laser_h[valid == 0] == 0.0)
    error = laser_h[valid == 1] - h[valid == 1]
    # the largest of n |N(0, σ²)| values stays below z·σ with 99.9 % for 2n·Φ(-z) = 0.001
    z = NormalDist().inv_cdf(1 - 0.001 / (2 * len(error)))
    assert len(error) > 100 and np.max(np.abs(error)) < z * 0.005


def test_fmu_run_equals_the_core_objects_stepped_directly(fmus, yang):
    direct = simulate(build_system("sensors_yang2020"), fmus, backend="core")
    for name, values in yang.columns.items():
        assert np.array_equal(values, direct[name]), name


def test_changing_one_sensor_seed_changes_only_that_sensor(fmus):
    system = build_system("sensors_yang2020")
    with Simulation(system, fmus) as simulation:
        first = simulation.run(stop_time=20.0)
        again = simulation.run(stop_time=20.0)
        reseeded = simulation.run(stop_time=20.0, parameters={"air_data.seed": 77})
    for name in first.columns:
        assert np.array_equal(first[name], again[name]), name
        if name.startswith("air_data.baro_h"):
            assert not np.array_equal(first[name], reseeded[name]), name
        elif not name.startswith("air_data."):
            assert np.array_equal(first[name], reseeded[name]), name


def test_every_sensor_has_its_own_default_seed():
    seeds = [wiring.seed for wiring in SENSORS.values()]
    assert len(set(seeds)) == len(seeds)
    system = build_system("sensors_yang2020")
    assert [system.component(name).parameters["seed"] for name in SENSORS] == seeds


def test_a_non_finite_input_is_a_clear_error_not_a_nan(fmus):
    info = fmu_info(fmus["AirDataModule"])
    instance = FmuInstance("air_data", info)
    try:
        instance.initialize({"sample_period": 0.01}, 0.01, 0.0, 1.0)
        instance.exit_initialization()
        instance.set("Real", [info.variables["p_static"].value_reference], [math.inf])
        expected = r"component 'air_data': doStep.*ValueError: input p_static = inf"
        with pytest.raises(CosimError, match=expected):
            instance.do_step(0.0, 0.01)
        outputs = [info.variables[n].value_reference for n in ("baro_p", "baro_h", "baro_T")]
        assert all(math.isfinite(v) for v in instance.get("Real", outputs))
    finally:
        instance.free()


def test_fmu_state_save_and_restore_continue_bit_identically(fmus):
    info = fmu_info(fmus["GnssReceiver"])
    instance = FmuInstance("gnss", info)
    outputs = [info.variables[n].value_reference for n in ("gps_h", "gps_vz", "gps_vdop")]
    counts = [info.variables[n].value_reference for n in ("gps_count", "gps_nsat")]
    h = info.variables["h"].value_reference

    def advance(start, count):
        values = []
        for n in range(start, start + count):
            instance.set("Real", [h], [100.0 + n])
            instance.do_step(n * 0.1, 0.1)
            values.append((instance.get("Real", outputs), instance.get("Integer", counts)))
        return values

    try:
        instance.initialize({"sample_period": 0.1, "dop_mode": "random", "gm_std": 3.0,
                             "outage_rate": 0.05, "latency": 0.3, "seed": 4}, 0.1, 0.0, 100.0)
        instance.exit_initialization()
        advance(0, 50)
        assert_restores_identically(instance, lambda: advance(50, 100))
    finally:
        instance.free()
