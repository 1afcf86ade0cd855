"""yang2020 Section 4 (Yang et al. 2020) flown closed loop: the default system.

* Trajectory: profile ``yang2020`` (climb, cruise at 1440 m, descent; 420 s), flown by the
  FlightController on the estimator's output (``estimator.h_est`` and ``estimator.vz_est`` are
  its feedback), so the estimator's errors show up as tracking errors of the true altitude.
* Sensors (Section 4.2, :data:`~altfusion.systems.sensors.SEED_003_SENSORS`): GPS 30 m and
  0.2 m/s every 100 ms, baro 20 m every 10 ms (no scale-factor error, no drift), radio
  altimeter 10 m every 200 ms over flat terrain at 0 m, accelerometer 0.01 m/s² every 10 ms.
* ``estimator``: YangFusionKF with its defaults (Section 4.2's variances), stepped at 10 ms.

Every component is stepped at the 0.01 s base step except the GPS receiver (100 ms) and the
radio altimeter (200 ms), which are stepped at their sample periods. Signals are recorded
every 0.1 s.

``yang2020_baseline`` is the same loop flown on BaselineKF (baro and GPS only, yang2020's variances,
the acceleration PSD of its loop: :data:`BASELINE`), ``yang2020_altitude_ekf`` on AltitudeEKF (every
sensor, yang2020's noises); the same run of a campaign gives these systems identical weather and
sensor noise.
"""

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.yang import YangFusionKF
from altfusion.systems.error_models import SENSOR_ERRORS
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import SEED_003_SENSORS, sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

BASE_STEP = 0.01
STOP_TIME = 420.0
SENSOR_NAMES = ("air_data", "gnss", "accelerometer", "radar")
SENSOR_STEPS = {"gnss": 0.1, "radar": 0.2}

BASELINE = {"R_baro": 400.0, "R_gps": 900.0, "accel_psd": 50.0}
"""BaselineKF given yang2020's baro and GPS variances (20 m and 30 m), and the acceleration
PSD of the loop it flies: on its default 0.5 m²/s³ the filter lags the vehicle it steers,
which swings by ±20 m/s (acceleration PSD 240 m²/s³ at 0.05-0.2 Hz: RMS 12.5 m, coverage of
|e| <= 2 h_std 0.23); with 50 the loop flies calmly and its measured acceleration PSD over
0.05-1 Hz is 57-74 m²/s³, the model's own order (RMS 4.0 m, coverage 0.93)."""

ALTITUDE_EKF_NOISES = {"baro_noise": 20.0, "gps_noise": 30.0, "gps_vz_noise": 0.2,
                       "acc_noise": 0.01, "radar_noise": 10.0}
"""yang2020's sensor noises (Section 4.2) by their contract names."""

ALTITUDE_EKF = {**ALTITUDE_EKF_NOISES, **SENSOR_ERRORS["yang2020"]}
"""AltitudeEKF given yang2020's sensors (Section 4.2): the noises and the error models of
:data:`~altfusion.systems.error_models.SENSOR_ERRORS` (a barometer calibrated at launch
without drift or scale error, the terrain known flat at 0 m, eq. 6's Q_sealevel; an
accelerometer without bias)."""

RECORD = ("plant.h", "plant.vz", "plant.az", "controller.h_ref", "controller.thrust",
          "air_data.baro_h", "gnss.gps_h", "gnss.gps_vz", "radar.radar_h",
          "accelerometer.acc_z", "estimator.h_est", "estimator.vz_est", "estimator.h_std")

METRICS = (Metric("estimate error", "estimator.h_est", "plant.h"),
           Metric("tracking error", "plant.h", "controller.h_ref"),
           Metric("baro_h error", "air_data.baro_h", "plant.h"),
           Metric("gps_h error", "gnss.gps_h", "plant.h"),
           Metric("radar_h error", "radar.radar_h", "plant.h"))


def closed_loop(name: str, description: str, estimator: type, parameters: dict,
                record: tuple[str, ...] = ()) -> SystemSpec:
    """yang2020's loop flown on ``estimator`` (an Estimator class; its FMU has the class's
    name) with ``parameters``, recording :data:`RECORD` and ``record``."""
    components = (
        plant_components("yang2020", step=BASE_STEP)
        + sensor_components(SENSOR_NAMES, step=BASE_STEP, parameters=SEED_003_SENSORS,
                            steps=SENSOR_STEPS)
        + (ComponentSpec("estimator", estimator.__name__, BASE_STEP, parameters),)
    )
    return SystemSpec(
        name=name, description=description, components=components,
        connections=(plant_connections("estimator.h_est", "estimator.vz_est")
                     + sensor_connections(SENSOR_NAMES)
                     + estimator_connections(estimator, sensors=SENSOR_NAMES)),
        stop_time=STOP_TIME, base_step=BASE_STEP, output_interval=0.1,
        record=RECORD + record, metrics=METRICS,
    )


def yang2020() -> SystemSpec:
    """yang2020's scenario flown on YangFusionKF's estimate (the default system)."""
    return closed_loop(
        "yang2020",
        "yang2020 Section 4: climb/cruise/descend flown closed loop on YangFusionKF's "
        "estimate; GPS 30 m / 0.2 m/s at 100 ms, baro 20 m at 10 ms, radio altimeter 10 m at "
        "200 ms, accelerometer 0.01 m/s² at 10 ms",
        YangFusionKF, {},
        ("estimator.h_fused", "estimator.fused_std", "estimator.n_rejected"),
    )


def yang2020_baseline() -> SystemSpec:
    """The loop of :func:`yang2020` flown on BaselineKF (baro and GPS)."""
    return closed_loop(
        "yang2020_baseline",
        "yang2020's scenario (see yang2020) flown closed loop on BaselineKF (baro 20 m, "
        "GPS 30 m)",
        BaselineKF, BASELINE,
    )


def yang2020_altitude_ekf() -> SystemSpec:
    """The loop of :func:`yang2020` flown on AltitudeEKF (every sensor, yang2020's noises)."""
    return closed_loop(
        "yang2020_altitude_ekf",
        "yang2020's scenario (see yang2020) flown closed loop on AltitudeEKF with yang2020's "
        "sensor noises (baro 20 m, GPS 30 m / 0.2 m/s, radio altimeter 10 m, accelerometer "
        "0.01 m/s²)",
        AltitudeEKF, ALTITUDE_EKF,
        ("estimator.acc_bias", "estimator.baro_bias", "estimator.terrain_est",
         "estimator.n_rejected", "estimator.h_valid"),
    )
