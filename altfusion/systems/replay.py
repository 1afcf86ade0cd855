"""Replay systems: LogReplay feeding estimators, each connected by contract names.

An estimator gets exactly the inputs it declares, each from the LogReplay output of the same
name; LogReplay outputs nobody declares stay unconnected, and a declared input LogReplay does
not provide is listed by :func:`replay_system` so the caller can warn. The catalog systems
take each estimator's declared inputs from its core class (the FMU declares the same, see
``estimator_variables``; a system test checks them against the built FMUs); ``altfusion
replay`` reads them from the FMUs it is given.

Replay tuning (:data:`REPLAY_TUNING`): the estimators' defaults are their papers' simulation
values (a 70 m GPS, a launch-calibrated barometer), which do not describe a PX4 vehicle. The
replay runs them with noises from the logged sensors instead:

* GPS height σ 0.8 m: the receivers' own ``epv`` (0.70-0.83 m on the Auterion flight, 0.4 m
  in SITL once fixed);
* baro height σ 0.6 m: the sample-to-sample scatter of ``baro_alt_meter`` on the Auterion
  flight, std(Δh)/√2 = 0.59 m;
* baro offset prior σ 200 m: PX4's baro altitude is referenced to its QNH setting, not to the
  launch site, so the offset to GPS altitude is unknown up to the QNH error (±25 hPa ≈ ±200 m;
  the Auterion log has -155 m). BaselineKF and Whang learn it as their bias state.
* Whang's launch calibration (H0, T0) is taken at the log's start: H0 = the first valid GPS
  altitude, T0 = the first baro temperature
  (:func:`altfusion.replay.calibration.launch_calibration`). With H0 = 0 (PX4's QNH datum)
  the scale factor would act on a 430 m lever and turn the 1.5 K temperature noise into ~2 m
  of height noise; from the start of the log it acts on the height flown. Its bias
  random walk is (0.05 m)² per air-data step, and its alpha-beta process noise is that of a
  multicopter, not the paper's aircraft: Q_h = q_a Δt^B = 0.5 m²/s³ x 0.2 s = 0.1 m²/s² (q_a
  as BaselineKF's); with the paper's 39.69 m²/s² the rate state follows the baro noise
  (±4 m/s) and coasts 4 m through the Auterion log's 2.2 s air-data gap.

AltitudeEKF takes the same GPS and baro σ (the GPS σ from epv, so not scaled by VDOP), the
baro offset prior, the vibration-dominated accelerometer noise as its ``acc_noise`` and, as
Yang and Xu, the log's ground height ``terrain_h`` (σ 0.1 m, constant): without it the
terrain is learnt from GPS during the flight and h - range drifts by 1 m while it converges.

Hajiyev's filter has no bias state: its adaptive factor (eq. 30) sees the 155 m residual and
turns the gain to ~1, so it follows GPS and the baro only interpolates between GPS samples.
Estimators not listed run with their defaults.
"""

from dataclasses import dataclass, field
from typing import Any

from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.signals import LOG_OUTPUTS
from altfusion.systems.spec import ComponentSpec, Connection, SystemSpec

REPLAY = "replay"
"""Name of the LogReplay component in every replay system."""

BASE_STEP = 0.01
"""Step of LogReplay and of every estimator, s: finer than the fastest logged height sensor
(20 Hz), so each baro and GPS sample reaches the estimators in a step of its own."""

GPS_SIGMA, BARO_SIGMA, BARO_OFFSET_SIGMA = 0.8, 0.6, 200.0
UNREFERENCED_BARO_SIGMA = 1000.0
"""Yang's fusion has no bias state: a QNH-referenced baro gets (almost) no weight."""
TERRAIN_SIGMA = 0.1
"""AltitudeEKF's terrain prior around the log's ground height (its launch calibration): the
median of GPS altitude minus rangefinder height over the flight."""
ACC_VIBRATION_SIGMA = 9.0
"""Vertical acceleration noise of the logged, vibration-dominated accelerometer, m/s²."""

REPLAY_TUNING: dict[str, dict[str, Any]] = {
    "BaselineKF": {"R_gps": GPS_SIGMA**2, "R_baro": BARO_SIGMA**2,
                   "P0_b": BARO_OFFSET_SIGMA**2},
    "HajiyevAdaptiveEstimator": {"R_gps": GPS_SIGMA**2, "R_baro": BARO_SIGMA**2},
    "WhangGAEstimator": {"R_gps": GPS_SIGMA**2, "R_baro": BARO_SIGMA**2,
                         "P0_b": BARO_OFFSET_SIGMA**2, "Q_b": 0.05**2, "Q_h": 0.5 * 0.2},
    "BaoDriftEstimator": {"R_baro": BARO_SIGMA**2, "P0_drift": BARO_OFFSET_SIGMA**2,
                          "R_gps": GPS_SIGMA**2, "user_range_error": GPS_SIGMA / 1.1,
                          "R_worst": (3 * GPS_SIGMA) ** 2},
    "YangFusionKF": {"R_gps": GPS_SIGMA**2, "R_baro": UNREFERENCED_BARO_SIGMA**2,
                     "R_gps_vz": 0.2**2, "R_acc": ACC_VIBRATION_SIGMA**2},
    "XuSHAEKF": {"R_gps": GPS_SIGMA**2, "R_baro": BARO_SIGMA**2,
                 "baro_bias_std": BARO_OFFSET_SIGMA, "acc_noise_std": ACC_VIBRATION_SIGMA},
    "AltitudeEKF": {"gps_noise": GPS_SIGMA, "gps_dop_scaling": False, "baro_noise": BARO_SIGMA,
                    "P0_offset": BARO_OFFSET_SIGMA**2, "acc_noise": ACC_VIBRATION_SIGMA,
                    "P0_terrain": TERRAIN_SIGMA**2, "terrain_psd": 0.0},
}
"""Parameters of each estimator for replayed PX4 logs (see the module docstring)."""

@dataclass(frozen=True)
class CatalogLog:
    """A bundled log (``resources/flightlogs/<file>`` of LogReplay.fmu) and what the catalog
    system needs from it, checked against the log by the tests."""

    file: str
    stop_time: float
    """The log's duration rounded up to the step, s."""
    calibration: dict[str, float]
    """:func:`~altfusion.replay.calibration.launch_calibration` of the log (rounded)."""
    description: str


LOGS = {
    "replay_auterion": CatalogLog(
        "auterion_esc_status_log.ulg", 43.95, {"H0": 428.924, "T0": 299.88, "terrain_h": 423.953},
        "Real PX4 flight (Auterion, FMU-v3): baro, GPS, accelerometer and lidar"),
    "replay_px4_sitl": CatalogLog(
        "pyulog_sample_px4_events.ulg", 31.14, {"H0": 488.005, "T0": 273.15, "terrain_h": 0.0},
        "PX4 SITL take-off and landing (pyulog sample): baro, GPS, accelerometer"),
}


TUNED_BY_CALIBRATION = {"WhangGAEstimator": ("H0", "T0"), "XuSHAEKF": ("terrain_h",),
                        "YangFusionKF": ("terrain_h",), "AltitudeEKF": ("terrain_h",)}
"""The calibration entries each estimator takes as parameters."""


def replay_tuning(fmu: str, calibration: dict[str, float]) -> dict[str, Any]:
    """The replay parameters of an estimator FMU (empty for estimators not tuned here)."""
    tuning = dict(REPLAY_TUNING.get(fmu, {}))
    tuning.update({key: calibration[key] for key in TUNED_BY_CALIBRATION.get(fmu, ())})
    return tuning


@dataclass(frozen=True)
class EstimatorEntry:
    """One estimator of a replay system: FMU model name, declared inputs, parameters."""

    fmu: str
    inputs: tuple[str, ...]
    parameters: dict[str, Any] = field(default_factory=dict)


def replay_system(name: str, log_file: str, stop_time: float,
                  estimators: list[EstimatorEntry], description: str = "",
                  time_offset: float = 0.0) -> tuple[SystemSpec, dict[str, list[str]]]:
    """The system, and per estimator the declared inputs LogReplay does not provide."""
    components = [ComponentSpec(REPLAY, "LogReplay", BASE_STEP,
                                {"log_file": log_file, "time_offset": time_offset})]
    connections, unconnected = [], {}
    for entry in estimators:
        components.append(ComponentSpec(entry.fmu, entry.fmu, BASE_STEP, dict(entry.parameters)))
        for name_in in entry.inputs:
            if name_in in LOG_OUTPUTS:
                connections.append(Connection(f"{REPLAY}.{name_in}", f"{entry.fmu}.{name_in}"))
            else:
                unconnected.setdefault(entry.fmu, []).append(name_in)
    spec = SystemSpec(name=name, description=description or f"LogReplay of {log_file}",
                      components=tuple(components), connections=tuple(connections),
                      stop_time=stop_time, base_step=BASE_STEP)
    return spec, unconnected


def catalog_replay(name: str) -> SystemSpec:
    """A catalog replay system: a bundled log and the three catalog estimators, each with its
    core's declared inputs and the replay tuning."""
    log = LOGS[name]
    entries = [EstimatorEntry(fmu, core.declared_inputs(),
                              replay_tuning(fmu, log.calibration))
               for fmu, core in ESTIMATOR_CLASSES.items()]
    spec, _ = replay_system(name, f"flightlogs/{log.file}", log.stop_time, entries,
                            f"{log.description}; {', '.join(ESTIMATOR_CLASSES)} with replay "
                            f"tuning")
    return spec
