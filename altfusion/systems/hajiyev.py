"""hajiyev Section 5 (Hajiyev, Hacizade, Cilden-Guler): the constant and drift cases as
catalog systems.

* Trajectory: the plant flies profile ``hajiyev``: the altitude whose standard-atmosphere
  pressure rises from 23 kPa (10,893 m; the paper says 10,894 m) by 0.05 kPa per 1 s
  iteration to 99.85 kPa (123 m, reached at 1537 s), then holds; 1560 s, the paper's
  iteration count (docs/papers.md: 1538 samples, the last one held). Iteration k is the sample at
  t = k s. The loop is closed on the true altitude.
* AirDataModule and GnssReceiver sample at the same instants every 1 s: baro-height noise
  σ_B = 9 m (R_B = 81 m²), GPS σ_GPS = 13 m (user range error 13 m × VDOP 1, R_GPS = 169 m²);
  no other sensor error. The barometer is calibrated with the paper's standard atmosphere
  (p0 = 101.325 kPa, T0 = 288.15 K, 0.0065 K/m), which is also the true atmosphere of the
  constant case, so the baro errs by its noise only.
* ``estimator``: HajiyevAdaptiveEstimator with R_B = 81 m², R_GPS = 169 m², stepped with the
  sensors; ``adaptive`` false in ``hajiyev`` (the paper's constant case, Fig. 4, the
  conventional fusion of eqs. 15-19) and true in ``hajiyev_drift`` (Figs. 8, 10, Table 1).
  R_B and R_GPS are bound explicitly so that ``altfusion compare`` hands them to BaselineKF
  too; the gates stay each estimator's default.

Drift case (``hajiyev_drift``). The paper drifts the baro computation's p0(k) and T0(k) by
-0.01 kPa and -0.01 K per iteration from k = 23 while the true atmosphere stays standard
(docs/papers.md). The AirDataModule's launch calibration cannot drift, so the true atmosphere
drifts instead, by the same amounts with the opposite sign: p0 +10 Pa/s and T0 +0.01 K/s
from t = 22 s (the first drifted sample is k = 23). Both make the barometer read low by the
same amount to first order: -77 m at k = 100 either way. The second-order terms differ as
the drift grows to 15 %: at k = 1560 our baro error is -1211 m, the paper's calibration
drift gives -1337 m (10 % more), and -1357 m if its formula p0(k) = p0 - k·0.01 kPa is read
literally, with a step of 0.23 kPa at k = 23. The adaptive estimator's error (GPS level once
|Δ| ≫ σ) does not depend on the drift's size; the non-adaptive one is (1 - K) = 0.676 times
the baro error.

Truth: the paper's actual altitude h(k) at its iterations. The component ``truth`` is a
noise-free GnssReceiver sampling the plant's altitude with the sensors: at every sample it
equals ``plant.h`` exactly, and before the first sample it reads 0 m like the sensors and the
estimator, so the row at t = 0 (no measurement yet) carries no error. Against ``plant.h``
that row would show the 10,893 m between the sensors' placeholders and the aircraft.

Steps: the plant, atmosphere and controller at 0.05 s (the loop tracks the profile within
0.5 m; the sensors sample the plant's own altitude); sensors, truth and estimator at 1 s;
recorded every 1 s.
"""

from altfusion.estimators.hajiyev import HajiyevAdaptiveEstimator
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Connection, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

BASE_STEP = 0.05
SAMPLE_PERIOD = 1.0
STOP_TIME = 1560.0
SENSOR_NAMES = ("air_data", "gnss")
R_BARO, R_GPS = 81.0, 169.0

SENSORS = {
    "air_data": {"sample_period": SAMPLE_PERIOD, "height_noise_std": R_BARO**0.5,
                 "pressure_resolution": 0.0, "drift_rate": 0.0, "drift_variance_rate": 0.0},
    "gnss": {"sample_period": SAMPLE_PERIOD, "user_range_error": R_GPS**0.5, "vdop": 1.0},
}
"""Section 5: R_B = 81 m², R_GPS = 169 m² (eqs. 32-33), both sampled every iteration."""

DRIFT = {"p0_rate": 10.0, "T0_rate": 0.01, "drift_start_time": 22.0}
"""Section 5's 0.01 kPa and 0.01 K per iteration from k = 23, applied to the true atmosphere
with the opposite sign (see the module docstring)."""

RECORD = ("plant.h", "truth.gps_h", "controller.h_ref", "atmosphere.p0_actual",
          "atmosphere.T0_actual", "air_data.baro_h", "gnss.gps_h", "estimator.h_est",
          "estimator.h_std", "estimator.adaptive_factor", "estimator.gain",
          "estimator.normalized_residual", "estimator.n_rejected")

TRUTH = ComponentSpec("truth", "GnssReceiver", SAMPLE_PERIOD,
                      {"sample_period": SAMPLE_PERIOD, "user_range_error": 0.0,
                       "velocity_noise_std": 0.0})
"""The altitude h(k) sampled with the sensors, without error (see the module docstring)."""

METRICS = (Metric("baro error", "air_data.baro_h", "truth.gps_h"),
           Metric("GPS error", "gnss.gps_h", "truth.gps_h"),
           Metric("fused error", "estimator.h_est", "truth.gps_h"))


def _scenario(name: str, description: str, drift: bool, adaptive: bool) -> SystemSpec:
    estimator = ComponentSpec("estimator", HajiyevAdaptiveEstimator.__name__, SAMPLE_PERIOD,
                              {"R_baro": R_BARO, "R_gps": R_GPS, "adaptive": adaptive})
    components = (
        plant_components("hajiyev", step=BASE_STEP, atmosphere=DRIFT if drift else {})
        + sensor_components(SENSOR_NAMES, parameters=SENSORS,
                            steps=dict.fromkeys(SENSOR_NAMES, SAMPLE_PERIOD))
        + (TRUTH, estimator)
    )
    return SystemSpec(
        name=name, description=description, components=components,
        connections=(plant_connections() + sensor_connections(SENSOR_NAMES)
                     + (Connection("plant.h", "truth.h"), Connection("plant.vz", "truth.vz"))
                     + estimator_connections(HajiyevAdaptiveEstimator)),
        stop_time=STOP_TIME, base_step=BASE_STEP, output_interval=SAMPLE_PERIOD,
        record=RECORD, metrics=METRICS,
    )


def hajiyev() -> SystemSpec:
    """hajiyev Section 5, constant p0 and T0: the conventional fusion (eqs. 15-19)."""
    return _scenario(
        "hajiyev",
        "hajiyev Section 5, constant case: descent from 10,893 m to 123 m, 9 m baro and "
        "13 m GPS every 1 s, HajiyevAdaptiveEstimator non-adaptive (eqs. 15-19)",
        drift=False, adaptive=False)


def hajiyev_drift() -> SystemSpec:
    """hajiyev Section 5, p0 and T0 drifting from k = 23: the adaptive fusion (eqs. 26-31)."""
    return _scenario(
        "hajiyev_drift",
        "hajiyev Section 5, drift case: the descent with sea-level pressure and temperature "
        "drifting 0.01 kPa and 0.01 K per second from k = 23, HajiyevAdaptiveEstimator "
        "adaptive (eqs. 26-31)",
        drift=True, adaptive=True)
