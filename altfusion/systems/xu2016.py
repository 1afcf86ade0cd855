"""xu2016 Section 3 (Xu et al. 2016): the hover simulations of Section 3.1 and the multipoint
hovers of Section 3.2, as catalog systems.

* Trajectories (profiles of :mod:`altfusion.physics.profiles`, take-off from the ground at 5 s,
  rest-to-rest moves at 0.5 m/s² and 2 m/s): ``xu2016_hover15`` climbs to 15 m (reached at
  16.5 s) and hovers, 120 s; ``xu2016_hover35`` climbs to 35 m (26.5 s), 120 s;
  ``xu2016_multipoint`` and ``xu2016_multipoint_wind`` hover at 10 m (from 14 s), 22 m (from
  345 s) and 37 m (from 676.5 s) within the 1000 s of Figs. 12-13. The paper gives no
  durations for Section 3.1.
* Loop: the FlightController is closed on XuSHAEKF's estimate (``estimator.h_est``,
  ``estimator.vz_est``), as in the paper's flight tests: the UAV hovers where its estimator
  believes the set point is. The errors are the estimates minus the plant's true altitude.
* Sensors: the paper gives no noise levels (docs/papers.md), so realistic ones of the classes it
  names (Section 1.2):

  - LaserRangefinder (Section 1.2.4): 100 Hz, σ 5 mm (its ±5 mm read as 1σ), valid from
    0.1 m to 25 m above the flat terrain at 0 m, reading 0 outside;
  - AirDataModule, a MEMS barometer (Section 1.2.2, eq. 4): 50 Hz, height noise σ 0.5 m,
    MS5611 pressure resolution 1.2 Pa (0.1 m), calibrated at take-off, the module's default
    drift (+10 m per hour and a random walk of 0.0025 m²/s: the constant error ε_b that
    changes slowly), and the wind's dynamic pressure seen as a static-pressure drop;
  - GnssReceiver (Section 1.2.3, eq. 5): 5 Hz (the paper: 1-10 Hz), white height noise
    σ 3 m (user range error 2 m × VDOP 1.5);
  - Accelerometer (Section 1.2.1): 100 Hz, white noise σ 0.05 m/s², a turn-on bias of
    σ 0.03 m/s² drawn per run (a calibrated MEMS accelerometer, docs/papers.md).
* Sudden GPS failure (``xu2016_hover15``, Section 3.1, Fig. 10): the GPS has no fix from
  60 s to the end (a scheduled outage window: the receiver blocked, Section 1.2.3: "sometimes
  there is no output because the GPS module is blocked").
* Wind grade 3 (``xu2016_multipoint_wind``, Fig. 13): Beaufort 3 is 3.4-5.4 m/s; the
  Atmosphere's wind is 4.4 m/s mean with Gauss-Markov gusts of σ 1 m/s (2 s correlation),
  which keep it mostly within that band. It acts through the barometer's static port: ½ρv²
  = 11.8 Pa at 4.4 m/s, about 1 m of baro height, varying by 0.45 m per 1 m/s of gust. The
  vertical dynamics have no wind force; the paper's Fig. 13 shows the hover held.
* ``estimator``: XuSHAEKF with its defaults, which are the nominal variances of these sensors
  (R_gps 9 m², R_baro 0.25 m², R_laser 2.5e-5 m², σ_a 0.05 m/s²) and the choices its
  docstring states (γ = 16, b = 0.99, N = 20, switch at 25 m), stepped at 0.01 s.
* ``baseline``: BaselineKF (baro and GPS, the same variances), estimating the same flight from
  the same samples without feeding the loop, stepped with the barometer. In the hover systems
  ``kalman`` is XuSHAEKF with ``adaptive`` false, the "Kalman filter improved before" that
  Figs. 10-11 compare with, also without feeding the loop.

Steps: the plant, accelerometer, laser and estimators at the 0.01 s base step; the
controller at 0.02 s (Section 1.2.3: the UAV's control runs at 50 Hz), the atmosphere, the
barometer and BaselineKF at 0.02 s; the GPS at 0.2 s. Signals are recorded every 0.1 s.
"""

from dataclasses import replace

from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.xu import XuSHAEKF
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

BASE_STEP = 0.01
BARO_PERIOD = 0.02
GPS_PERIOD = 0.2
CONTROL_PERIOD = 0.02
"""Section 1.2.3: "the control frequency of the UAV which reaches 50Hz"."""
PLANT_STEPS = {"controller": CONTROL_PERIOD, "atmosphere": BARO_PERIOD}
"""Steps of the plant block other than the base step."""
OUTPUT_INTERVAL = 0.1
HOVER_STOP_TIME = 120.0
MULTIPOINT_STOP_TIME = 1000.0
GPS_FAILURE_TIME = 60.0
SENSOR_NAMES = ("air_data", "gnss", "accelerometer", "laser")

SENSORS = {
    "laser": {"sample_period": BASE_STEP, "noise_std": 0.005, "min_range": 0.1,
              "max_range": 25.0},
    "air_data": {"sample_period": BARO_PERIOD, "height_noise_std": 0.5},
    "gnss": {"sample_period": GPS_PERIOD, "user_range_error": 2.0, "vdop": 1.5},
    "accelerometer": {"sample_period": BASE_STEP, "noise_std": 0.05, "bias_std": 0.03},
}
"""Realistic sensors of the classes of Section 1.2 (the module docstring); the air-data
module keeps its default resolution and drift."""

GPS_FAILURE = {"outage_windows": f"{GPS_FAILURE_TIME:g} {HOVER_STOP_TIME:g}"}
"""Section 3.1: the GPS fails suddenly at 60 s and stays out."""

WIND_GRADE_3 = {"wind_mean": 4.4, "gust_std": 1.0, "gust_time_constant": 2.0}
"""Fig. 13's wind grade 3 (Beaufort 3: 3.4-5.4 m/s)."""

BASELINE = {"R_baro": 0.25, "R_gps": 9.0}
"""BaselineKF given the nominal variances of the barometer (0.5 m) and the GPS (3 m)."""

RECORD = ("plant.h", "controller.h_ref", "atmosphere.wind_speed", "air_data.baro_h",
          "gnss.gps_h", "gnss.gps_fix", "laser.laser_h", "laser.laser_valid",
          "estimator.h_est", "estimator.h_std", "estimator.height_source",
          "estimator.weight_gps", "estimator.weight_baro", "estimator.weight_laser",
          "estimator.R_gps_est", "estimator.R_baro_est", "estimator.baro_bias",
          "estimator.n_strong_tracking", "estimator.n_rejected", "baseline.h_est",
          "baseline.n_rejected")

METRICS = (Metric("XuSHAEKF error", "estimator.h_est", "plant.h"),
           Metric("BaselineKF error", "baseline.h_est", "plant.h"),
           Metric("tracking error", "plant.h", "controller.h_ref"),
           Metric("baro_h error", "air_data.baro_h", "plant.h"),
           Metric("gps_h error", "gnss.gps_h", "plant.h"))

KALMAN = ComponentSpec("kalman", XuSHAEKF.__name__, BASE_STEP, {"adaptive": False})
"""Figs. 10-11's "Kalman filter improved before": XuSHAEKF without its adaptive parts."""


def _scenario(name: str, description: str, profile: str, stop_time: float,
              atmosphere: dict | None = None, gnss: dict | None = None,
              kalman: bool = False) -> SystemSpec:
    sensors = {**SENSORS, "gnss": {**SENSORS["gnss"], **(gnss or {})}}
    comparators = (KALMAN,) if kalman else ()
    plant = tuple(replace(c, step_size=PLANT_STEPS.get(c.name, c.step_size))
                  for c in plant_components(profile, step=BASE_STEP, atmosphere=atmosphere))
    components = (
        plant
        + sensor_components(SENSOR_NAMES, step=BASE_STEP, parameters=sensors,
                            steps={"air_data": BARO_PERIOD, "gnss": GPS_PERIOD})
        + (ComponentSpec("estimator", XuSHAEKF.__name__, BASE_STEP, {}),
           ComponentSpec("baseline", BaselineKF.__name__, BARO_PERIOD, dict(BASELINE)))
        + comparators
    )
    connections = (plant_connections("estimator.h_est", "estimator.vz_est")
                   + sensor_connections(SENSOR_NAMES) + estimator_connections(XuSHAEKF)
                   + estimator_connections(BaselineKF, "baseline")
                   + sum((estimator_connections(XuSHAEKF, c.name) for c in comparators), ()))
    record = RECORD + tuple(f"{c.name}.h_est" for c in comparators)
    metrics = METRICS + tuple(Metric(f"{c.name} error", f"{c.name}.h_est", "plant.h")
                              for c in comparators)
    return SystemSpec(
        name=name, description=description, components=components, connections=connections,
        stop_time=stop_time, base_step=BASE_STEP, output_interval=OUTPUT_INTERVAL,
        record=record, metrics=metrics,
    )


def xu2016_hover15() -> SystemSpec:
    """Section 3.1, Figs. 8 and 10: hover at 15 m, the GPS failing suddenly at 60 s."""
    return _scenario(
        "xu2016_hover15",
        "xu2016 Section 3.1: hover at 15 m flown on XuSHAEKF, GPS out from 60 s; laser "
        "5 mm at 100 Hz, baro 0.5 m at 50 Hz, GPS 3 m at 5 Hz, accelerometer 0.05 m/s²; "
        "BaselineKF and the non-adaptive XuSHAEKF beside",
        "xu_hover15", HOVER_STOP_TIME, gnss=GPS_FAILURE, kalman=True)


def xu2016_hover35() -> SystemSpec:
    """Section 3.1, Figs. 9 and 11: hover at 35 m, above the laser's range."""
    return _scenario(
        "xu2016_hover35",
        "xu2016 Section 3.1: hover at 35 m (laser out of range) flown on XuSHAEKF; the "
        "sensors of xu2016_hover15; BaselineKF and the non-adaptive XuSHAEKF beside",
        "xu_hover35", HOVER_STOP_TIME, kalman=True)


def xu2016_multipoint() -> SystemSpec:
    """Section 3.2, Fig. 12: hovers at 10, 22 and 37 m within 1000 s, no wind."""
    return _scenario(
        "xu2016_multipoint",
        "xu2016 Section 3.2: hovers at 10, 22 and 37 m within 1000 s flown on XuSHAEKF, no "
        "wind; the sensors of xu2016_hover15; BaselineKF beside",
        "xu_multipoint", MULTIPOINT_STOP_TIME)


def xu2016_multipoint_wind() -> SystemSpec:
    """Section 3.2, Fig. 13: the multipoint hovers in wind grade 3."""
    return _scenario(
        "xu2016_multipoint_wind",
        "xu2016 Section 3.2: the hovers of xu2016_multipoint in wind grade 3 (4.4 m/s mean, "
        "1 m/s gusts) acting on the barometer; BaselineKF beside",
        "xu_multipoint", MULTIPOINT_STOP_TIME, atmosphere=WIND_GRADE_3)
