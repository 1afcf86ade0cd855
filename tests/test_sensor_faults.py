"""SensorFaults (the fault suite's injector) stepped directly, and with_fault's rewiring."""

import math
from dataclasses import replace

import pytest

from altfusion.errors import ParameterError
from altfusion.sensors.faults import (
    PASSED_SIGNALS,
    WILD_PROBES,
    SensorFaults,
    SensorFaultsParams,
    hypsometric_pressure,
)
from altfusion.systems.faults import FAULTS, fault_flight, with_fault
from altfusion.systems.yang2020 import yang2020

STEP = 0.1


class Feed:
    """A SensorFaults stepped at 0.1 s, fed every step with one new sample of each stream:
    baro 100 m (89875 Pa, 281.65 K), GPS 101 m, acc 0.1 m/s², radar 99 m, laser 10 m (valid),
    each stamped with the step's end time; truth h = 100 m, thrust 20 N."""

    def __init__(self, **params):
        self.faults = SensorFaults(SensorFaultsParams(**params), step_size=STEP)
        self.n = 0

    def step(self) -> SensorFaults:
        f, self.n = self.faults, self.n + 1
        t = self.n * STEP
        values = {"baro_h": 100.0, "baro_p": 89875.0, "baro_T": 281.65, "gps_h": 101.0,
                  "gps_vz": 0.5, "gps_vdop": 1.0, "gps_nsat": 8, "gps_fix": True,
                  "acc_z": 0.1, "radar_h": 99.0, "radar_valid": True, "laser_h": 10.0,
                  "laser_valid": True}
        for prefix in ("baro", "gps", "acc", "radar", "laser"):
            values[f"{prefix}_count"] = self.n
            values[f"{prefix}_time"] = t
        for name, value in values.items():
            setattr(f, f"raw_{name}", value)
        f.h, f.thrust = 100.0, 20.0
        f.do_step((self.n - 1) * STEP, STEP)
        return f

    def until(self, t: float) -> SensorFaults:
        while self.n * STEP < t - 1e-9:
            self.step()
        return self.faults


def test_scenario_none_passes_every_signal_through_unchanged():
    f = Feed().until(5.0)
    for name in PASSED_SIGNALS:
        assert getattr(f, name) == getattr(f, f"raw_{name}"), name
    assert not f.fault_active


def test_baro_step_moves_height_and_pressure_consistently_from_fault_start():
    feed = Feed(scenario="baro_step", fault_start=1.0)
    before = feed.until(0.9)
    assert before.baro_h == 100.0
    after = feed.until(1.0)
    assert after.baro_h == 300.0
    assert after.baro_p == pytest.approx(hypsometric_pressure(89875.0, 281.65, 200.0))
    assert after.baro_p < 89875.0 * 0.98     # 200 m higher: about 2.4 % less pressure
    assert after.gps_h == 101.0 and after.fault_active


def test_silent_freezes_every_count_and_holds_every_value():
    feed = Feed(scenario="silent", fault_start=1.0)
    held = {name: getattr(feed.until(0.95), name) for name in PASSED_SIGNALS}
    f = feed.until(3.0)
    assert {name: getattr(f, name) for name in PASSED_SIGNALS} == held
    assert f.raw_baro_count == 30 and f.baro_count == 9


def test_failover_stops_gnss_then_baro_then_range_sensors():
    feed = Feed(scenario="failover", fault_start=1.0, failover_interval=1.0)
    f = feed.until(2.5)
    assert f.gps_count == 9 and f.baro_count == 19 and f.radar_count == 25
    f = feed.until(3.5)
    assert (f.baro_count, f.radar_count, f.laser_count, f.acc_count) == (19, 29, 29, 35)


def test_gnss_outage_drops_the_fix_then_returns_off():
    feed = Feed(scenario="gnss_outage_return_off", fault_start=2.0, gps_outage=1.0)
    f = feed.until(1.5)
    assert not f.gps_fix and f.gps_count == 9
    f = feed.until(2.0)
    assert f.gps_fix and f.gps_count == 10 and f.gps_h == 151.0


def test_early_late_samples_shift_the_stamps_only():
    f = Feed(scenario="early_late_samples", fault_start=0.0).until(1.0)
    assert f.gps_time == pytest.approx(1.1) and f.radar_time == pytest.approx(1.1)
    assert f.baro_time == pytest.approx(0.98) and f.acc_time == pytest.approx(0.98)
    assert (f.gps_h, f.baro_h) == (101.0, 100.0)


def test_wild_sample_sends_each_probe_once_in_turn():
    feed = Feed(scenario="wild_sample", fault_start=1.0, wild_interval=1.0)
    seen = []
    for _ in range(int((1.0 + len(WILD_PROBES)) / STEP)):
        f = feed.step()
        seen += [(name, value) for name, value in WILD_PROBES
                 if getattr(f, name) == value and (not seen or seen[-1] != (name, value))]
    assert seen == list(WILD_PROBES)


def test_range_terrain_box_then_stuck_then_low():
    feed = Feed(scenario="range_terrain", fault_start=1.0, range_phase=1.0)
    assert feed.until(1.5).laser_h == 7.0 and feed.faults.radar_h == 96.0
    assert feed.until(2.5).laser_h == 10.0                  # gap
    assert feed.until(3.5).laser_h == 10.0                  # stuck at the gap's reading
    f = feed.until(5.5)
    assert f.laser_h == 0.05 and f.laser_valid


def test_prop_wash_and_ground_effect_follow_thrust_and_height():
    assert Feed(scenario="prop_wash", fault_start=0.0).until(1.0).baro_h == \
        pytest.approx(100.0 + 7.0 * 20.0 / 40.0)
    ground = Feed(scenario="ground_effect", fault_start=0.0, ground_h=99.5).until(1.0)
    assert ground.baro_h == pytest.approx(102.0)             # take-off: within 1 m, +2 m


def test_acc_bias_is_drawn_in_its_range_from_the_seed():
    biases = {Feed(scenario="acc_bias", fault_start=0.0, seed=s).until(0.5).acc_z - 0.1
              for s in range(5)}
    assert len(biases) == 5 and all(0.1 <= b <= 0.4 for b in biases)


def test_unknown_scenario_is_refused_naming_the_parameter():
    with pytest.raises(ParameterError, match="scenario"):
        SensorFaults(SensorFaultsParams(scenario="gremlins"))


def test_with_fault_reroutes_every_sensor_output_through_the_fault_component():
    spec = fault_flight(("BaselineKF", "XuSHAEKF"))
    faulty = with_fault(spec, "baro_step")
    assert faulty.name == "fault_flight+baro_step"
    sensors = {"air_data", "gnss", "accelerometer", "radar", "laser"}
    for connection in faulty.connections:
        if connection.end.partition(".")[0] in ("BaselineKF", "XuSHAEKF"):
            assert connection.start.partition(".")[0] not in sensors, connection
    assert faulty.component("fault").parameters["fault_start"] == FAULTS["baro_step"].start


def test_with_fault_refuses_unknown_names_and_missing_sensors():
    with pytest.raises(ValueError, match="known: baro_step"):
        with_fault(fault_flight(("BaselineKF",)), "gremlins")
    with pytest.raises(ValueError, match="needs the laser sensor"):
        with_fault(yang2020(), "range_terrain")
    with pytest.raises(ValueError, match="needs controller.thrust"):
        with_fault(replace(yang2020(), components=tuple(
            c for c in yang2020().components if c.name != "controller")), "prop_wash")


def test_fault_suite_is_the_spec_table_in_order():
    assert list(FAULTS) == [
        "baro_step", "baro_drift", "gnss_step", "gnss_outage_return_off", "failover",
        "all_fail", "silent", "wild_sample", "acc_bias", "ground_effect", "prop_wash",
        "range_terrain", "weather_front", "early_late_samples"]
    assert all(math.isfinite(f.start) and f.transient >= 0 for f in FAULTS.values())
