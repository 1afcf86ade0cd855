"""PX4 topics -> contract streams, on plain arrays (``topic -> field -> numpy array``).

This is the whole translation from PX4's uORB messages to the signal contract; reading the
file (:mod:`altfusion.replay.ulog`) only fills the dictionary. What each output means:

* ``baro`` from ``vehicle_air_data``: ``baro_h`` = ``baro_alt_meter``, PX4's barometric
  altitude, MSL by PX4's standard-atmosphere conversion with its QNH (``SENS_BARO_QNH``), *not*
  launch-calibrated; ``baro_p`` = ``baro_pressure_pa``; ``baro_T`` = ``baro_temp_celcius`` +
  273.15 (the sensor's own temperature, not the air's).
* ``gps`` from ``vehicle_gps_position``: ``gps_h`` = ``altitude_msl_m`` (m) or ``alt`` (mm,
  converted); ``gps_vz`` = -``vel_d_m_s``; ``gps_vdop``; ``gps_nsat`` = ``satellites_used``;
  ``gps_epv`` = ``epv``; ``gps_fix`` = ``fix_type`` >= 3 (3-D fix).
* ``acc`` from ``sensor_combined``: ``acc_z``, vertical acceleration, positive up (below).
* ``laser`` or ``radar`` from ``distance_sensor``, the downward-facing sensor; ``type`` 3
  (radar) feeds ``radar_*``, the others (laser, ultrasound, infrared) ``laser_*``. Height =
  range x cos(tilt) where attitude is logged; valid within [``min_distance``,
  ``max_distance``] and ``signal_quality`` != 0.
* ``ekf`` from ``vehicle_local_position``: ``ekf_h`` = ``ref_alt`` - ``z`` (z is down, relative
  to the origin at ``ref_alt``), ``ekf_vz`` = -``vz``; ``ekf_valid`` = ``z_valid`` and
  ``z_global`` and a finite ``ref_alt``.

Vertical acceleration: the accelerometer measures the specific force f = a - g in the body
frame (FRD; at rest level f = (0, 0, -g)). Rotated to NED with the attitude interpolated at the
accelerometer's time stamp, a_down = f_down + g, so acc_z = -(f_down + g) with g = 9.80665 m/s²
(positive up, gravity removed). Where no attitude covers a sample, the body z-axis is taken as
vertical (f_down ~ f_z, exact only in level flight) and the report says for how many samples.

Sample times are ``timestamp_sample`` where the topic has it and it is plausible (at most 1 s
before ``timestamp``), else ``timestamp``; for ``sensor_combined`` the accelerometer's own
``timestamp + accelerometer_timestamp_relative``.
"""

from dataclasses import dataclass, field

import numpy as np

from altfusion.constants import G0
from altfusion.replay.attitude import down_row, interpolate_quaternions
from altfusion.replay.streams import (
    LogProblem,
    SampleStream,
    clean_order,
    drop_non_finite,
    find_gaps,
    hold_invalid,
    outlier_stamps,
)

AIR_DATA = "vehicle_air_data"
GNSS = "vehicle_gps_position"
IMU = "sensor_combined"
ATTITUDE = "vehicle_attitude"
RANGE = "distance_sensor"
LOCAL_POSITION = "vehicle_local_position"
TOPICS = (AIR_DATA, GNSS, IMU, ATTITUDE, RANGE, LOCAL_POSITION)
EKF_PREFIX = "ekf"
"""The stream of PX4's own estimate (a reference, not a sensor)."""

MAX_SAMPLE_AGE_US = 1_000_000
RELATIVE_TIMESTAMP_INVALID = 2_147_483_647
ROTATION_DOWNWARD_FACING = 25
DISTANCE_SENSOR_RADAR = 3
FIX_3D = 3
KELVIN = 273.15

Fields = dict[str, np.ndarray]


@dataclass
class FlightLog:
    """The streams of one log, times in s after ``start_us`` (the log's microsecond clock)."""

    start_us: int
    duration: float
    streams: dict[str, SampleStream]
    problems: list[LogProblem] = field(default_factory=list)
    source: str = ""

    def stream(self, prefix: str) -> SampleStream | None:
        return self.streams.get(prefix)

    def report(self) -> list[str]:
        """Every finding, one line each: the log-level ones, then each stream's."""
        lines = [str(p) for p in self.problems]
        for stream in self.streams.values():
            lines += [str(p) for p in stream.problems]
        return lines


def sample_times_us(fields: Fields, topic: str) -> tuple[np.ndarray, list[LogProblem]]:
    """Sample times (µs): ``timestamp_sample`` if usable, else ``timestamp``."""
    stamp = np.asarray(fields["timestamp"], dtype=np.int64)
    if "timestamp_sample" not in fields:
        return stamp, []
    sampled = np.asarray(fields["timestamp_sample"], dtype=np.int64)
    age = stamp - sampled
    bad = (age < 0) | (age > MAX_SAMPLE_AGE_US)
    if not bad.any():
        return sampled, []
    return stamp, [LogProblem(topic, "time stamp",
                              f"timestamp_sample is zero or implausible in {int(bad.sum())} of "
                              f"{len(bad)} samples; the topic's timestamp is used instead")]


def accelerometer_times_us(fields: Fields) -> tuple[np.ndarray, list[LogProblem]]:
    """``timestamp + accelerometer_timestamp_relative`` where the offset is valid."""
    stamp = np.asarray(fields["timestamp"], dtype=np.int64)
    relative = fields.get("accelerometer_timestamp_relative")
    if relative is None:
        return stamp, []
    relative = np.asarray(relative, dtype=np.int64)
    invalid = relative == RELATIVE_TIMESTAMP_INVALID
    problems = []
    if invalid.any():
        problems.append(LogProblem(IMU, "time stamp",
                                   f"accelerometer_timestamp_relative invalid in "
                                   f"{int(invalid.sum())} samples; timestamp used there"))
    return stamp + np.where(invalid, 0, relative), problems


def missing_fields(fields: Fields, names: tuple[str, ...], topic: str) -> list[LogProblem]:
    absent = [n for n in names if n not in fields]
    return [LogProblem(topic, "missing field", f"no field {', '.join(absent)}; stream not "
                                               f"replayed")] if absent else []


def finish_stream(prefix: str, topic: str, time_us: np.ndarray, start_us: int,
                  values: dict[str, np.ndarray], problems: list[LogProblem],
                  valid: np.ndarray | None = None, valid_name: str | None = None,
                  invalid_value: dict[str, float] | None = None,
                  integer: tuple[str, ...] = ()) -> SampleStream:
    """Validity, order, duplicates, gaps and held values: the stream as it will be replayed.

    Non-finite values make a sample invalid where the stream has a validity flag, otherwise
    the sample is dropped. Invalid samples keep the last valid values (``invalid_value`` names
    values that are set to a constant instead, e.g. the laser's 0)."""
    if valid is None:
        keep, found = drop_non_finite(values, topic)
        problems += [LogProblem(p.topic, p.kind, p.message + "; sample dropped") for p in found]
    else:
        finite, found = drop_non_finite(values, topic)
        problems += [LogProblem(p.topic, p.kind, p.message + f"; {valid_name} false")
                     for p in found]
        valid = np.asarray(valid, dtype=bool) & finite
        keep = np.ones(len(time_us), dtype=bool)
    plausible, found = outlier_stamps(time_us, topic)
    problems += found
    keep = keep & plausible
    time_us = np.asarray(time_us, dtype=np.int64)[keep]
    values = {n: np.asarray(v)[keep] for n, v in values.items()}
    order, found = clean_order(time_us, topic)
    problems += found
    time_s = (time_us[order] - start_us) / 1e6
    problems += find_gaps(time_s, topic)
    values = {n: v[order] for n, v in values.items()}
    if valid is not None:
        valid = valid[keep][order]
        if not valid.all():
            problems.append(LogProblem(topic, "invalid", f"{int((~valid).sum())} of "
                                                         f"{len(valid)} samples have "
                                                         f"{valid_name} false"))
        constants = invalid_value or {}
        values = {n: np.where(valid, v, constants[n]) if n in constants
                  else hold_invalid(v, valid) for n, v in values.items()}
    values = {n: v.astype(np.int64) if n in integer else v.astype(float)
              for n, v in values.items()}
    return SampleStream(prefix, topic, time_s, values, valid, valid_name, problems)


# ------------------------------------------------------------------------- the streams
def baro_stream(fields: Fields, start_us: int) -> SampleStream | None:
    problems = missing_fields(fields, ("baro_alt_meter", "baro_pressure_pa",
                                       "baro_temp_celcius"), AIR_DATA)
    if problems:
        return SampleStream("baro", AIR_DATA, np.empty(0), {}, problems=problems)
    time_us, problems = sample_times_us(fields, AIR_DATA)
    celsius = np.asarray(fields["baro_temp_celcius"], dtype=float)
    problems.append(LogProblem(AIR_DATA, "unit", "baro_temp_celcius (°C) + 273.15 -> baro_T (K)"))
    if len(celsius) and np.all(celsius == 0.0):
        problems.append(LogProblem(AIR_DATA, "not measured",
                                   "baro_temp_celcius is 0 in every sample (no temperature "
                                   "sensor, e.g. SITL): baro_T = 273.15 K is not a measurement"))
    values = {"baro_h": fields["baro_alt_meter"], "baro_p": fields["baro_pressure_pa"],
              "baro_T": celsius + KELVIN}
    return finish_stream("baro", AIR_DATA, time_us, start_us, values, problems)


def gps_altitude(fields: Fields) -> tuple[np.ndarray | None, list[LogProblem]]:
    """MSL altitude in m from ``altitude_msl_m`` (m) or ``alt`` (int, mm)."""
    if "altitude_msl_m" in fields:
        return np.asarray(fields["altitude_msl_m"], dtype=float), [
            LogProblem(GNSS, "unit", "gps_h from altitude_msl_m (m)")]
    if "alt" in fields:
        return np.asarray(fields["alt"], dtype=float) / 1000.0, [
            LogProblem(GNSS, "unit", "gps_h from alt (mm) / 1000")]
    return None, [LogProblem(GNSS, "missing field", "neither altitude_msl_m nor alt; stream "
                                                    "not replayed")]


def gps_stream(fields: Fields, start_us: int) -> SampleStream | None:
    height, problems = gps_altitude(fields)
    missing = missing_fields(fields, ("vel_d_m_s", "vdop", "epv", "satellites_used",
                                      "fix_type"), GNSS)
    if height is None or missing:
        return SampleStream("gps", GNSS, np.empty(0), {}, problems=problems + missing)
    time_us, found = sample_times_us(fields, GNSS)
    problems += found
    vdop = np.asarray(fields["vdop"], dtype=float)
    if len(vdop) and np.all(vdop == 0.0):
        problems.append(LogProblem(GNSS, "not measured", "vdop is 0 in every sample (not "
                                                         "reported by this receiver/simulator)"))
    values = {"gps_h": height, "gps_vz": -np.asarray(fields["vel_d_m_s"], dtype=float),
              "gps_vdop": vdop, "gps_nsat": fields["satellites_used"], "gps_epv": fields["epv"]}
    valid = np.asarray(fields["fix_type"]) >= FIX_3D
    return finish_stream("gps", GNSS, time_us, start_us, values, problems, valid, "gps_fix",
                         integer=("gps_nsat",))


def attitude_down_rows(attitude: Fields | None, time_us: np.ndarray,
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Third row of the body-to-NED rotation at ``time_us`` and where attitude covers it."""
    if attitude is None or not all(f"q[{i}]" in attitude for i in range(4)):
        return np.full((len(time_us), 3), np.nan), np.zeros(len(time_us), dtype=bool)
    att_us, _ = sample_times_us(attitude, ATTITUDE)
    order, _ = clean_order(att_us, ATTITUDE)
    q = np.column_stack([np.asarray(attitude[f"q[{i}]"], dtype=float)[order] for i in range(4)])
    finite = np.all(np.isfinite(q), axis=1) & (np.linalg.norm(q, axis=1) > 0.5)
    quaternions, covered = interpolate_quaternions(att_us[order][finite] / 1e6, q[finite],
                                                   np.asarray(time_us) / 1e6)
    return down_row(np.where(covered[:, None], quaternions, 1.0)), covered


def acc_stream(fields: Fields, attitude: Fields | None, start_us: int) -> SampleStream | None:
    names = tuple(f"accelerometer_m_s2[{i}]" for i in range(3))
    problems = missing_fields(fields, names, IMU)
    if problems:
        return SampleStream("acc", IMU, np.empty(0), {}, problems=problems)
    time_us, problems = accelerometer_times_us(fields)
    force = np.column_stack([np.asarray(fields[n], dtype=float) for n in names])
    rows, covered = attitude_down_rows(attitude, time_us)
    f_down = np.where(covered, np.sum(rows * force, axis=1), force[:, 2])
    if not covered.all():
        problems.append(LogProblem(IMU, "approximation",
                                   f"no attitude for {int((~covered).sum())} of {len(covered)} "
                                   f"samples: body z-axis taken as vertical there"))
    return finish_stream("acc", IMU, time_us, start_us, {"acc_z": -(f_down + G0)}, problems)


def range_streams(fields: Fields, attitude: Fields | None, start_us: int,
                  ) -> list[SampleStream]:
    """The downward-facing rangefinder as ``laser`` or ``radar`` (by its ``type``)."""
    problems = missing_fields(fields, ("current_distance", "min_distance", "max_distance"),
                              RANGE)
    if problems:
        return [SampleStream("laser", RANGE, np.empty(0), {}, problems=problems)]
    down = np.ones(len(fields["timestamp"]), dtype=bool)
    if "orientation" in fields:
        down = np.asarray(fields["orientation"]) == ROTATION_DOWNWARD_FACING
        if not down.all():
            problems.append(LogProblem(RANGE, "skipped", f"{int((~down).sum())} samples of "
                                                         f"sensors not facing down ignored"))
    kind = np.asarray(fields.get("type", np.zeros(len(down))))
    streams = []
    for prefix, selected in (("laser", down & (kind != DISTANCE_SENSOR_RADAR)),
                             ("radar", down & (kind == DISTANCE_SENSOR_RADAR))):
        if not selected.any():
            continue
        sub = {n: np.asarray(v)[selected] for n, v in fields.items()}
        time_us, found = sample_times_us(sub, RANGE)
        distance = np.asarray(sub["current_distance"], dtype=float)
        valid = (distance >= sub["min_distance"]) & (distance <= sub["max_distance"])
        if "signal_quality" in sub:
            valid &= np.asarray(sub["signal_quality"]) != 0
        rows, covered = attitude_down_rows(attitude, time_us)
        height = np.where(covered, distance * rows[:, 2], distance)
        found = list(problems) + found
        if not covered.all():
            found.append(LogProblem(RANGE, "approximation",
                                    f"no attitude for {int((~covered).sum())} samples: range "
                                    f"taken as vertical there"))
        constants = {"laser_h": 0.0} if prefix == "laser" else None
        streams.append(finish_stream(prefix, RANGE, time_us, start_us, {f"{prefix}_h": height},
                                     found, valid, f"{prefix}_valid", constants))
    return streams


def ekf_stream(fields: Fields, start_us: int) -> SampleStream | None:
    problems = missing_fields(fields, ("z", "vz", "ref_alt"), LOCAL_POSITION)
    if problems:
        return SampleStream(EKF_PREFIX, LOCAL_POSITION, np.empty(0), {}, problems=problems)
    time_us, problems = sample_times_us(fields, LOCAL_POSITION)
    valid = np.ones(len(time_us), dtype=bool)
    for flag in ("z_valid", "z_global"):
        if flag in fields:
            valid &= np.asarray(fields[flag]) != 0
    values = {"ekf_h": np.asarray(fields["ref_alt"], dtype=float) - fields["z"],
              "ekf_vz": -np.asarray(fields["vz"], dtype=float)}
    return finish_stream(EKF_PREFIX, LOCAL_POSITION, time_us, start_us, values, problems, valid,
                         "ekf_valid")


def first_sample_us(topics: dict[str, Fields]) -> int | None:
    """The earliest time stamp (µs) of any topic, sample times included."""
    earliest = []
    for topic, fields in topics.items():
        if topic == IMU:
            stamps, _ = accelerometer_times_us(fields)
        else:
            stamps, _ = sample_times_us(fields, topic)
        stamps = stamps[outlier_stamps(stamps, topic)[0]]
        if len(stamps):
            earliest.append(int(np.min(stamps)))
    return min(earliest) if earliest else None


def extract_streams(topics: dict[str, Fields], start_us: int | None = None,
                    source: str = "") -> FlightLog:
    """The contract streams of a log given as ``topic -> field -> array``.

    Times are seconds after ``start_us`` (default: the earliest sample time, so no sample has a
    negative time); the duration runs to the last sensor sample (the replay stops where the
    sensor data stop, whatever the log's last time stamp or EKF2's outputs say). Stamps far from
    their neighbours are dropped (:func:`~altfusion.replay.streams.outlier_stamps`)."""
    problems = [LogProblem(t, "missing topic", "not in the log; its stream is not replayed")
                for t in TOPICS if t not in topics]
    topics = {t: f for t, f in topics.items() if t in TOPICS and len(f.get("timestamp", ()))}
    earliest = first_sample_us(topics)
    if earliest is None:
        return FlightLog(0, 0.0, {}, problems + [LogProblem(source or "log", "missing topic",
                                                            "no samples to replay")], source)
    start_us = earliest if start_us is None else min(start_us, earliest)
    attitude = topics.get(ATTITUDE)
    if ATTITUDE not in topics:
        problems.append(LogProblem(ATTITUDE, "approximation", "no attitude: acceleration and "
                                                              "range taken along body z"))
    streams: list[SampleStream | None] = []
    if AIR_DATA in topics:
        streams.append(baro_stream(topics[AIR_DATA], start_us))
    if GNSS in topics:
        streams.append(gps_stream(topics[GNSS], start_us))
    if IMU in topics:
        streams.append(acc_stream(topics[IMU], attitude, start_us))
    if RANGE in topics:
        streams += range_streams(topics[RANGE], attitude, start_us)
    if LOCAL_POSITION in topics:
        streams.append(ekf_stream(topics[LOCAL_POSITION], start_us))
    by_prefix = {s.prefix: s for s in streams if s is not None}
    ends = [s.time[-1] for p, s in by_prefix.items() if len(s) and p != EKF_PREFIX]
    duration = max(ends, default=0.0)
    return FlightLog(start_us, duration, by_prefix, problems, source)
