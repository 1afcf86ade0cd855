"""The signal contract (``docs/signals.md``) as data: name -> (type, unit, meaning).

Adapters declare contract signals from this table, so a signal has one unit and one
description in every FMU that carries it.
"""

SIGNALS: dict[str, tuple[type, str | None, str]] = {
    "baro_p": (float, "Pa", "Static pressure measured by the barometer"),
    "baro_T": (float, "K", "Air temperature measured by the air-data module"),
    "baro_h": (float, "m", "Barometric altitude from the launch calibration (MSL)"),
    "baro_count": (int, None, "Number of air-data samples taken so far"),
    "baro_time": (float, "s", "Time the held air-data sample was taken"),
    "gps_h": (float, "m", "GNSS altitude (MSL)"),
    "gps_vz": (float, "m/s", "GNSS vertical speed, positive up"),
    "gps_vdop": (float, "1", "GNSS vertical dilution of precision"),
    "gps_nsat": (int, None, "Number of satellites used in the GNSS fix"),
    "gps_fix": (bool, None, "GNSS fix valid (false during outages)"),
    "gps_count": (int, None, "Number of GNSS samples delivered so far"),
    "gps_time": (float, "s", "Time the held GNSS sample was taken"),
    "gps_epv": (float, "m", "GNSS receiver's own vertical accuracy estimate (1 sigma)"),
    "acc_z": (float, "m/s2", "Vertical acceleration (gravity removed), positive up"),
    "acc_count": (int, None, "Number of accelerometer samples taken so far"),
    "acc_time": (float, "s", "Time the held accelerometer sample was taken"),
    "radar_h": (float, "m", "Radio-altimeter height above terrain"),
    "radar_valid": (bool, None, "Radio-altimeter sample valid (within range)"),
    "radar_count": (int, None, "Number of radio-altimeter samples taken so far"),
    "radar_time": (float, "s", "Time the held radio-altimeter sample was taken"),
    "laser_h": (float, "m", "Laser range to the terrain (0 when out of range)"),
    "laser_valid": (bool, None, "Laser sample valid (0.1 m to 25 m)"),
    "laser_count": (int, None, "Number of laser samples taken so far"),
    "laser_time": (float, "s", "Time the held laser sample was taken"),
    "ekf_h": (float, "m", "Reference altitude estimate of another navigation filter (MSL), "
                          "e.g. PX4 EKF2's in a replayed log"),
    "ekf_vz": (float, "m/s", "Reference vertical-speed estimate, positive up"),
    "ekf_valid": (bool, None, "Reference estimate valid (its filter reports a valid height)"),
    "ekf_count": (int, None, "Number of reference-estimate samples delivered so far"),
    "ekf_time": (float, "s", "Time the held reference-estimate sample was taken"),
    "wind_speed": (float, "m/s", "Wind speed at the vehicle"),
    "h_est": (float, "m", "Altitude estimate (MSL)"),
    "vz_est": (float, "m/s", "Vertical-speed estimate, positive up"),
    "h_std": (float, "m", "The filter's own standard deviation of h_est"),
    "h_valid": (bool, None, "h_est valid: the estimator is initialized and fused a height "
                            "sample within aiding_timeout (and a required source, XuSHAEKF's "
                            "accelerometer, delivered within it)"),
    "status": (int, None, "Estimator status bit field (docs/estimator_health.md)"),
    "n_rejected": (int, None, "Samples rejected by the gates so far, all sources"),
    "n_ignored": (int, None, "Invalid, non-finite or absurdly stamped samples ignored so far"),
    "n_height_resets": (int, None, "Height resets so far (every height source disagreed with "
                                   "the prediction)"),
}

LOG_STREAMS: dict[str, tuple[tuple[str, ...], str | None]] = {
    "baro": (("baro_h", "baro_p", "baro_T"), None),
    "gps": (("gps_h", "gps_vz", "gps_vdop", "gps_nsat", "gps_epv"), "gps_fix"),
    "acc": (("acc_z",), None),
    "laser": (("laser_h",), "laser_valid"),
    "radar": (("radar_h",), "radar_valid"),
    "ekf": (("ekf_h", "ekf_vz"), "ekf_valid"),
}
"""The streams LogReplay delivers from a flight log (:mod:`altfusion.replay.component`): per
stream prefix, its values and its validity flag (None: always valid)."""

LOG_OUTPUTS: tuple[str, ...] = tuple(
    name for prefix, (values, valid) in LOG_STREAMS.items()
    for name in (*values, *((valid,) if valid else ()), f"{prefix}_count", f"{prefix}_time")
)
"""Every output of LogReplay, contract names, in declaration order."""
