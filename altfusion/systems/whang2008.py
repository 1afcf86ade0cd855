"""whang2008 Section 3 (Whang & Ra 2008): the simulation behind Fig. 3, as catalog systems.

* Trajectory: Fig. 2 is not in the text (docs/papers.md); the plant flies profile ``whang2008``:
  climb at 10 m/s to 4000 m (0.25 m/s² ramps, reached at 440 s), then cruise; 600 s. The
  flight controller is closed on the true altitude: the paper's figure is about the
  estimator, whose output feeds nothing back.
* Weather: ISA at launch; every 10 s the lapse rate is drawn anew, N(-0.0065, 0.003²) K/m
  (Section 3's °C/km read as K/m, docs/papers.md), and held. A barometer calibrated at launch then
  errs by -δΓ·h²/(2 T0) to first order: 83 m (1σ) at 4000 m, 86 m exactly.
* AirDataModule every Δt^B = 0.2 s, calibrated at launch (H0 = 0, ISA P0 and T0 = the
  atmosphere at t = 0): baro-height noise 5 m (R_B = 5² m²), temperature noise 1.5 K; no
  drift, wind or quantization (the paper has none).
* GnssReceiver every 1 s: σ 70 m (user range error 70 m × VDOP 1; R_GPS = 70² m²).
* ``estimator``: WhangGAEstimator with its defaults, which are Section 3's parameters
  (Q^a = 2e-5, Q^b = 400 m² per air-data step, P^a_00 = 0.2², P^b_00 = 20², Q^h = 39.69,
  P_00 = diag(100, 144), τ = 100 s), stepped at Δt^B.

``whang2008_baseline`` is the same scenario with BaselineKF (its defaults: whang2008's R_B and
R_GPS; its baro-bias random walk that of the paper's filter, :data:`BASELINE`) as ``estimator``;
the same run of a campaign with the same master seed gives both systems identical weather and
sensor noise (seeds derive from component names). It is a system of its own because ``altfusion
compare`` cannot swap in an estimator without ``h_comp``, which the compensated-height metric
needs.

Steps: the plant, atmosphere and controller at 0.05 s (the loop tracks the profile within
1 mm; the errors are taken against the plant's own altitude, which the sensors sample
exactly); each sensor and the estimator at its own period. Signals are recorded every 0.2 s:
at the GPS samples (whole seconds) and in between, where the GPS output holds.
"""

from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.whang import WhangGAEstimator, WhangParams
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

BASE_STEP = 0.05
AIR_DATA_PERIOD = 0.2
GPS_PERIOD = 1.0
STOP_TIME = 600.0
SENSOR_NAMES = ("air_data", "gnss")

ATMOSPHERE = {"lapse_rate_std": 0.003, "lapse_rate_period": 10.0}
"""Section 3: the lapse rate changes randomly every 10 s, σ 0.003 K/m around -0.0065 K/m."""

SENSORS = {
    "air_data": {"sample_period": AIR_DATA_PERIOD, "height_noise_std": 5.0,
                 "temperature_noise_std": 1.5, "pressure_resolution": 0.0,
                 "temperature_resolution": 0.0, "drift_rate": 0.0, "drift_variance_rate": 0.0},
    "gnss": {"sample_period": GPS_PERIOD, "user_range_error": 70.0, "vdop": 1.0},
}
"""Section 3: R_B = 5² m², R_Temperature = 1.5² K², R_GPS = 70² m²; ADM every 0.2 s, GPS
every 1 s."""

SENSOR_RECORD = ("plant.h", "plant.vz", "controller.h_ref", "atmosphere.lapse_rate_actual",
                 "air_data.baro_h", "air_data.baro_T", "gnss.gps_h", "gnss.gps_count")

SENSOR_METRICS = (Metric("baro error", "air_data.baro_h", "plant.h"),
                  Metric("GPS error", "gnss.gps_h", "plant.h"))


BASELINE = {"bias_psd": WhangParams().Q_b / AIR_DATA_PERIOD}
"""BaselineKF's baro-bias random walk: the one whang2008 gives its own filter's bias for this
weather, Q^b = 400 m² per air-data step (2000 m²/s). A barometer calibrated at launch errs by
-δΓ·h²/(2 T0), redrawn every 10 s: about 83 m (1σ) at 4000 m, which the default 0.05 m²/s
cannot follow (coverage of |e| <= 2 h_std 0.42, RMS 49 m; with this: 0.97, 27 m)."""


def _scenario(name: str, description: str, estimator: type, record: tuple[str, ...],
              metrics: tuple[Metric, ...], parameters: dict | None = None) -> SystemSpec:
    components = (
        plant_components("whang2008", step=BASE_STEP, atmosphere=ATMOSPHERE)
        + sensor_components(SENSOR_NAMES, parameters=SENSORS,
                            steps={"air_data": AIR_DATA_PERIOD, "gnss": GPS_PERIOD})
        + (ComponentSpec("estimator", estimator.__name__, AIR_DATA_PERIOD,
                         dict(parameters or {})),)
    )
    return SystemSpec(
        name=name, description=description, components=components,
        connections=(plant_connections() + sensor_connections(SENSOR_NAMES)
                     + estimator_connections(estimator)),
        stop_time=STOP_TIME, base_step=BASE_STEP, output_interval=AIR_DATA_PERIOD,
        record=SENSOR_RECORD + record, metrics=SENSOR_METRICS + metrics,
    )


def whang2008() -> SystemSpec:
    """whang2008 Section 3 with WhangGAEstimator (the paper's parameters) as ``estimator``."""
    return _scenario(
        "whang2008",
        "whang2008 Section 3: climb at 10 m/s to 4000 m and cruise, lapse rate redrawn every "
        "10 s (σ 0.003 K/m), 5 m / 1.5 K air data at 0.2 s, 70 m GPS at 1 s, "
        "WhangGAEstimator with the paper's parameters",
        WhangGAEstimator,
        ("estimator.h_est", "estimator.h_comp", "estimator.h_std", "estimator.scale_factor",
         "estimator.bias", "estimator.n_rejected"),
        (Metric("compensated-height error", "estimator.h_comp", "plant.h"),
         Metric("final height error", "estimator.h_est", "plant.h")),
    )


def whang2008_baseline() -> SystemSpec:
    """The scenario of :func:`whang2008` with BaselineKF as ``estimator``."""
    return _scenario(
        "whang2008_baseline",
        "whang2008 Section 3's scenario (see whang2008) with BaselineKF as the estimator",
        BaselineKF,
        ("estimator.h_est", "estimator.h_std", "estimator.bias", "estimator.n_rejected"),
        (Metric("final height error", "estimator.h_est", "plant.h"),),
        BASELINE,
    )
