"""The ULog extraction layer on small synthetic topics: order, duplicates, gaps, missing
topics and fields, non-finite values, units, validity, and the vertical acceleration."""

import math

import numpy as np
import pytest

from altfusion.constants import G0
from altfusion.replay.extract import extract_streams
from altfusion.replay.streams import clean_order, find_gaps, hold_invalid


def kinds(log) -> set[tuple[str, str]]:
    problems = log.problems + [p for s in log.streams.values() for p in s.problems]
    return {(p.topic, p.kind) for p in problems}


def air_data(t_us, h, temperature=20.0):
    n = len(t_us)
    return {"timestamp": np.array(t_us, dtype=np.uint64), "baro_alt_meter": np.array(h, float),
            "baro_pressure_pa": np.full(n, 95000.0), "baro_temp_celcius": np.full(n, temperature)}


def gnss(t_us, alt_mm, fix=3, **extra):
    n = len(t_us)
    fields = {"timestamp": np.array(t_us, dtype=np.uint64), "alt": np.array(alt_mm, np.int32),
              "vel_d_m_s": np.full(n, -1.0), "vdop": np.full(n, 1.1), "epv": np.full(n, 0.7),
              "satellites_used": np.full(n, 12, np.uint8), "fix_type": np.full(n, fix, np.uint8)}
    fields.update(extra)
    return fields


def test_samples_out_of_order_are_sorted_and_of_duplicates_the_later_is_kept():
    index, problems = clean_order(np.array([10, 30, 20, 30, 40]), "topic")
    assert index.tolist() == [0, 2, 3, 4]  # the second 30 (log index 3) wins
    assert {p.kind for p in problems} == {"non-monotonic", "duplicate"}


def test_a_gap_longer_than_five_median_intervals_is_reported_with_its_length():
    time = np.array([0.0, 0.2, 0.4, 0.6, 2.8, 3.0])
    (gap,) = find_gaps(time, "topic")
    assert "longest 2.2 s after t = 0.6 s" in gap.message
    assert find_gaps(np.arange(10) * 0.2, "topic") == []


def test_invalid_samples_hold_the_last_valid_value_and_zero_before_any():
    held = hold_invalid(np.array([5.0, 6.0, 7.0, 8.0]), np.array([False, True, False, True]))
    assert held.tolist() == [0.0, 6.0, 6.0, 8.0]


def test_an_empty_log_and_missing_topics_are_reported_not_crashed_on():
    log = extract_streams({})
    assert log.streams == {} and log.duration == 0.0
    assert ("vehicle_air_data", "missing topic") in kinds(log)
    only_baro = extract_streams({"vehicle_air_data": air_data([0, 100_000], [10.0, 11.0])})
    assert set(only_baro.streams) == {"baro"}
    missing = {t for t, k in kinds(only_baro) if k == "missing topic"}
    assert missing == {"vehicle_gps_position", "sensor_combined", "vehicle_attitude",
                       "distance_sensor", "vehicle_local_position"}


def test_a_missing_field_drops_only_its_stream_and_says_which_field():
    fields = air_data([0, 100_000], [10.0, 11.0])
    del fields["baro_temp_celcius"]
    log = extract_streams({"vehicle_air_data": fields})
    assert len(log.streams["baro"]) == 0
    assert any("baro_temp_celcius" in line for line in log.report())


def test_duplicated_time_stamps_keep_the_later_sample_and_times_are_relative_seconds():
    log = extract_streams({"vehicle_air_data": air_data(
        [1_000_000, 1_200_000, 1_200_000, 1_400_000], [10.0, 11.0, 12.0, 13.0])})
    baro = log.streams["baro"]
    assert baro.time.tolist() == [0.0, 0.2, 0.4]
    assert baro.values["baro_h"].tolist() == [10.0, 12.0, 13.0]
    assert baro.values["baro_T"][0] == pytest.approx(293.15)
    assert ("vehicle_air_data", "duplicate") in kinds(log)


def test_non_finite_baro_samples_are_dropped_and_reported():
    log = extract_streams({"vehicle_air_data": air_data([0, 1, 2], [10.0, math.nan, 12.0])})
    assert log.streams["baro"].values["baro_h"].tolist() == [10.0, 12.0]
    assert any("1 sample(s) with non-finite baro_h; sample dropped" in line
               for line in log.report())


def test_gps_altitude_in_millimetres_is_converted_and_no_fix_holds_the_last_fixed_value():
    log = extract_streams({"vehicle_gps_position": gnss(
        [0, 200_000, 400_000], [428_924, 500_000, 429_100], fix=3)
        | {"fix_type": np.array([3, 0, 3], np.uint8)}})
    gps = log.streams["gps"]
    assert gps.values["gps_h"].tolist() == [428.924, 428.924, 429.1]
    assert gps.valid.tolist() == [True, False, True]
    assert gps.values["gps_vz"][0] == 1.0  # -vel_d
    assert any("alt (mm) / 1000" in line for line in log.report())


def test_altitude_msl_m_is_preferred_and_a_zero_timestamp_sample_falls_back_to_timestamp():
    fields = gnss([1_000_000, 1_052_000], [0, 0])
    fields["altitude_msl_m"] = np.array([487.99, 488.01])
    fields["timestamp_sample"] = np.zeros(2, np.uint64)
    log = extract_streams({"vehicle_gps_position": fields})
    assert log.streams["gps"].values["gps_h"].tolist() == [487.99, 488.01]
    assert log.streams["gps"].time.tolist() == [0.0, 0.052]
    assert ("vehicle_gps_position", "time stamp") in kinds(log)


def ekf_topic(ref_alt, z, z_valid):
    n = len(z)
    return {"timestamp": np.arange(n, dtype=np.uint64) * 100_000, "z": np.array(z, float),
            "vz": np.full(n, 0.5), "ref_alt": np.array(ref_alt, float),
            "z_valid": np.array(z_valid, np.uint8)}


def test_ekf_height_is_ref_alt_minus_z_and_invalid_before_the_origin_is_set():
    log = extract_streams({"vehicle_local_position": ekf_topic(
        [math.nan, 419.9, 419.9], [0.0, -6.5, -7.0], [1, 1, 1])})
    ekf = log.streams["ekf"]
    assert ekf.valid.tolist() == [False, True, True]
    assert ekf.values["ekf_h"].tolist() == [0.0, pytest.approx(426.4), pytest.approx(426.9)]
    assert ekf.values["ekf_vz"].tolist() == [0.0, -0.5, -0.5]  # held, as h is
    assert all(np.isfinite(ekf.values["ekf_h"]))


def rangefinder(distance, kind=0, orientation=25):
    n = len(distance)
    return {"timestamp": np.arange(n, dtype=np.uint64) * 100_000,
            "current_distance": np.array(distance, float), "min_distance": np.full(n, 0.05),
            "max_distance": np.full(n, 25.0), "signal_quality": np.full(n, -1, np.int8),
            "type": np.full(n, kind, np.uint8), "orientation": np.full(n, orientation, np.uint8)}


def test_a_laser_out_of_range_is_invalid_with_zero_height_and_a_radar_feeds_radar():
    laser = extract_streams({"distance_sensor": rangefinder([5.0, 30.0, 6.0])})
    stream = laser.streams["laser"]
    assert stream.valid.tolist() == [True, False, True]
    assert stream.values["laser_h"].tolist() == [5.0, 0.0, 6.0]  # no attitude: range as is
    radar = extract_streams({"distance_sensor": rangefinder([5.0, 6.0], kind=3)})
    assert set(radar.streams) == {"radar"}
    sideways = extract_streams({"distance_sensor": rangefinder([5.0], orientation=0)})
    assert sideways.streams == {}


def attitude_topic(t_us, roll):
    half = np.asarray(roll, float) / 2
    return {"timestamp": np.array(t_us, dtype=np.uint64), "q[0]": np.cos(half),
            "q[1]": np.sin(half), "q[2]": np.zeros(len(half)), "q[3]": np.zeros(len(half))}


def imu(t_us, forces):
    forces = np.atleast_2d(forces)
    return {"timestamp": np.array(t_us, dtype=np.uint64),
            **{f"accelerometer_m_s2[{i}]": forces[:, i] for i in range(3)}}


def test_vertical_acceleration_is_minus_the_rotated_specific_force_minus_g():
    """Climbing at +1 m/s² with a 30° roll: the specific force is R^T (0, 0, -(g + 1)) in FRD.
    Rotated back with the attitude, acc_z = +1; a level vehicle at rest reads 0. Exact up to
    rounding of the ~11 m/s² specific force through a rotation: a few ε·11 m/s² ≈ 1e-14
    (bound 1e-9 with the quaternion interpolation; 1e-12 level, where it is the identity)."""
    roll = math.radians(30)
    force_frd = np.array([0.0, -math.sin(roll), -math.cos(roll)]) * (G0 + 1.0)
    topics = {"sensor_combined": imu([100_000, 200_000], [force_frd, force_frd]),
              "vehicle_attitude": attitude_topic([0, 300_000], [roll, roll])}
    log = extract_streams(topics)
    assert log.streams["acc"].values["acc_z"] == pytest.approx([1.0, 1.0], abs=1e-9)
    at_rest = extract_streams({"sensor_combined": imu([0], [[0.0, 0.0, -G0]]),
                               "vehicle_attitude": attitude_topic([0], [0.0])})
    assert at_rest.streams["acc"].values["acc_z"] == pytest.approx([0.0], abs=1e-12)


def test_without_attitude_the_body_z_axis_is_taken_as_vertical_and_that_is_reported():
    log = extract_streams({"sensor_combined": imu([0, 100_000], [[0.0, 0.0, -G0 - 2.0]] * 2)})
    assert log.streams["acc"].values["acc_z"] == pytest.approx([2.0, 2.0])
    assert ("sensor_combined", "approximation") in kinds(log)


def test_the_range_is_tilt_corrected_with_the_interpolated_attitude():
    """Roll 0 at t = 0 and 60° at 0.2 s; at 0.1 s nlerp gives exactly 30° for a single-axis
    rotation, so a 10 m range is 10 cos 30° above the ground."""
    topics = {"distance_sensor": rangefinder([10.0, 10.0]),
              "vehicle_attitude": attitude_topic([0, 200_000], [0.0, math.radians(60)])}
    topics["distance_sensor"]["timestamp"] = np.array([100_000, 400_000], np.uint64)
    laser = extract_streams(topics).streams["laser"]
    assert laser.values["laser_h"][0] == pytest.approx(10 * math.cos(math.radians(30)))
    assert laser.values["laser_h"][1] == 10.0  # after the last attitude: not covered


@pytest.mark.parametrize("shift_s", [3000, 100_000, -5])
def test_a_stamp_far_from_its_neighbours_is_dropped_and_reported(shift_s):
    """10 s of baro at 10 Hz with one stamp moved: the replay's span stays 9.9 s (not 3000 s,
    not 100000 s; a stamp 5 s early does not move the start)."""
    stamps = list(range(1_000_000, 11_000_000, 100_000))
    stamps[40] += shift_s * 1_000_000
    log = extract_streams({"vehicle_air_data": air_data(stamps, np.arange(100.0))})
    baro = log.streams["baro"]
    assert len(baro) == 99 and 40.0 not in baro.values["baro_h"]
    assert log.duration == pytest.approx(9.9)
    assert ("vehicle_air_data", "bad time stamp") in kinds(log)


def test_the_replay_stops_where_the_sensor_data_stop():
    """PX4 EKF2's outputs run on for 100 s after the last sensor sample at 0.9 s: the replay
    (whose estimators have no data there) ends at 0.9 s."""
    topics = {"vehicle_air_data": air_data(range(0, 1_000_000, 100_000), np.zeros(10)),
              "vehicle_local_position": ekf_topic(np.full(1001, 400.0), np.zeros(1001),
                                                  np.ones(1001))}
    assert extract_streams(topics).duration == pytest.approx(0.9)
