"""bao2017 Section 4.3 (Bao et al. 2017): the one-hour static drift test behind Fig. 8, as a
catalog system.

* Static test: the barometer and the GPS receiver lie side by side on the ground at the test
  site ("placed on a same certain altitude"), which we put at sea level: the plant flies
  profile ``hold`` at 0 m and rests on the ground (ISA atmosphere, no weather change, no
  wind: "the wind disturbance error can be ignored"); 3600 s. The test runs without wind,
  so the estimator's wind correction (eq. 11) is off and its principle-error correction
  (eq. 5) is zero (the weather is the calibration's).
* AirDataModule every 0.2 s with the GPS (Table 1's MS5611 updates at 10 Hz; "Steps" says
  why 5 Hz), calibrated at the site: baro-height noise 0.1 m (Table 1's altitude resolution
  of 10 cm) and the MS5611's pressure resolution of 1.2 Pa (0.1 m), and the drift of
  eq. (6): a random walk with the mean rate of Fig. 1 (+10 m per hour, "drifts upward about
  10 meters in an hour") and the spectral density σ² = 0.03 m²/s the estimator assumes, so
  that the filters differ only in their R (the paper leaves σ² to "the local weather, season
  and time"; its random part alone also wanders about 10 m in an hour).
* GnssReceiver every 0.2 s (u-blox LEA-6H, 5 Hz, Section 4.1.3): σ_G = UERE·VDOP·√max(1,
  N_ref/N) with UERE 2 m and N_ref = 6 (white noise, the model the estimator's η inverts),
  VDOP and satellites scheduled in 10 min phases (:data:`QUALITY`; Fig. 4's VDOP varies over
  the test): nominal, a poor phase (Fig. 8's left ellipse: σ_G 8.8 m), a medium one,
  nominal, a good phase (the right ellipse: σ_G 1.6 m), nominal. Every run sees the same
  schedule and its own noise.
* ``estimator``: BaoDriftEstimator with its defaults, which model this test (drift_psd σ² =
  0.03 m²/s, P(0) = 100 m², the same UERE and N_ref, C = R_worst = 225 m², the worst σ_G of
  15 m it accepts, above the scenario's 8.8 m, so R_k = η_k·C = σ_G², eq. 14), without the
  innovation gate (the paper's filters have none; a gate would make a small constant R
  reject the poor phase's samples). ``adaptive_R`` true is the paper's method; the
  reproduction runs it false with constant R = ``R_gps`` (the "normal Kalman filter") over a
  grid of R.

Steps: the sensors and the estimator at their common sample period of 0.2 s; the vehicle
rests on the ground, so the plant, atmosphere and controller are stepped at 10 s (the plant
integrates exactly for any step and the altitude stays 0 m; the atmosphere's lapse-rate
period of 10 s bounds the step): a run takes about 2.5 s. Signals are recorded every 1 s.
The baro at 5 Hz instead of 10 Hz leaves BaoDriftEstimator's statistics unchanged: its drift
filter uses only the latest baro sample at each GPS sample (eq. 13), and h_est is the latest
corrected baro sample plus the drift, so at the recorded whole seconds, where both rates
sample, the errors have the same distribution; the 10 Hz run costs 1.6 times as much.
"""

from altfusion.estimators.bao import BaoDriftEstimator
from altfusion.sensors.air_data import SECONDS_PER_HOUR
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

BASE_STEP = 0.2
PLANT_STEP = 10.0
SAMPLE_PERIOD = 0.2
STOP_TIME = SECONDS_PER_HOUR
OUTPUT_INTERVAL = 1.0
SENSOR_NAMES = ("air_data", "gnss")

DRIFT_PSD = 0.03
"""σ² of eq. (6), m²/s: the estimator's default drift_psd, given to the simulated drift."""

USER_RANGE_ERROR = 2.0
NSAT_REFERENCE = 6

QUALITY: tuple[tuple[float, float, int], ...] = (
    (0.0, 1.5, 9), (600.0, 4.0, 5), (1200.0, 2.5, 7), (1800.0, 1.5, 9), (2400.0, 0.8, 12),
    (3000.0, 1.5, 9))
"""GPS quality phases (start s, VDOP, satellites): σ_G = 3.0, 8.8, 5.0, 3.0, 1.6, 3.0 m."""

POOR_WINDOW = (600.0, 1200.0)
GOOD_WINDOW = (2400.0, 3000.0)
"""The phases of Fig. 8's left (poor GPS) and right (good GPS) ellipses, (start, end] s."""


def _schedule(column: int) -> str:
    return "; ".join(f"{phase[0]:g} {phase[column]:g}" for phase in QUALITY)


SENSORS = {
    "air_data": {"sample_period": SAMPLE_PERIOD, "height_noise_std": 0.1,
                 "drift_rate": 10.0 / SECONDS_PER_HOUR, "drift_variance_rate": DRIFT_PSD},
    "gnss": {"sample_period": SAMPLE_PERIOD, "user_range_error": USER_RANGE_ERROR,
             "nsat_reference": NSAT_REFERENCE, "dop_mode": "scheduled",
             "vdop": QUALITY[0][1], "nsat": QUALITY[0][2],
             "vdop_schedule": _schedule(1), "nsat_schedule": _schedule(2)},
}
"""Sections 4.1 and 4.3: MS5611 with 0.1 m and 1.2 Pa resolution and the drift of Fig. 1;
LEA-6H at 5 Hz with the quality schedule :data:`QUALITY`."""

ESTIMATOR = {"drift_psd": DRIFT_PSD, "user_range_error": USER_RANGE_ERROR,
             "nsat_reference": NSAT_REFERENCE, "gate_sigma": 0.0, "adaptive_R": True}
"""BaoDriftEstimator: the scenario's drift and GPS error model, no gate, eq. (14)."""

RECORD = ("plant.h", "air_data.baro_h", "air_data.baro_drift", "gnss.gps_h", "gnss.gps_vdop",
          "gnss.gps_nsat", "estimator.h_est", "estimator.h_std", "estimator.drift",
          "estimator.drift_std", "estimator.eta", "estimator.R", "estimator.n_rejected")

METRICS = (Metric("baro error", "air_data.baro_h", "plant.h"),
           Metric("GPS error", "gnss.gps_h", "plant.h"),
           Metric("corrected baro error", "estimator.h_est", "plant.h"))


def bao2017() -> SystemSpec:
    """bao2017 Section 4.3 with BaoDriftEstimator's adaptive R (eq. 14) as ``estimator``."""
    components = (
        plant_components("hold", step=PLANT_STEP)
        + sensor_components(SENSOR_NAMES, parameters=SENSORS,
                            steps=dict.fromkeys(SENSOR_NAMES, SAMPLE_PERIOD))
        + (ComponentSpec("estimator", BaoDriftEstimator.__name__, SAMPLE_PERIOD,
                         ESTIMATOR),)
    )
    return SystemSpec(
        name="bao2017",
        description="bao2017 Section 4.3: 1 h static on the ground, MS5611 baro at 5 Hz "
                    "drifting +10 m/h (random walk 0.03 m²/s), GPS at 5 Hz with scheduled "
                    "VDOP and satellites (σ_G 1.6-8.8 m), BaoDriftEstimator with adaptive R "
                    "(eq. 14)",
        components=components,
        connections=(plant_connections() + sensor_connections(SENSOR_NAMES)
                     + estimator_connections(BaoDriftEstimator)),
        stop_time=STOP_TIME, base_step=BASE_STEP, output_interval=OUTPUT_INTERVAL,
        record=RECORD, metrics=METRICS,
    )
