"""The paper systems' sensor error models beyond white noise, by estimator parameter names.

An engineer configuring an estimator for a system's sensors tells it what the sensors' data
sheets and the flight say, not only their white noise (which ``altfusion evaluate`` derives
from the sensor components, ``evaluation.scenarios.sensor_noise``): a barometer calibrated at
launch, how its error drifts, whether its error grows with height, the terrain under the
rangefinders, the accelerometer's turn-on bias. :data:`SENSOR_ERRORS` states them per system
under the names of the estimator parameters that take them; ``altfusion evaluate`` hands each
value to every estimator that has a parameter of that name or of the same quantity under its
own name (``Estimator.stated_parameters``; as it hands the true noises), and
``benchmarks/altitude_ekf_scenarios.py`` reads the same table. Every value is a fact of the
system's sensors, weather or terrain, derived below from the constants that configure them,
never a choice made to favour an estimator; a parameter not stated keeps the estimator's
default.

The names (AltitudeEKF's; XuSHAEKF and YangFusionKF share ``baro_bias_psd``,
``acc_bias_psd`` and ``terrain_h`` with the same meaning):

* ``P0_offset`` (m²): variance of the baro's offset from the GNSS datum at start: a barometer
  calibrated at launch (every paper system's AirDataModule) reads the launch height, so its
  offset is known to the calibration's accuracy, :data:`CALIBRATED_OFFSET_VARIANCE`;
* ``baro_bias_psd`` (m²/s): the random walk of the baro error (the AirDataModule's
  ``drift_variance_rate``, or the weather's drift of the barometric reference);
* ``P0_scale``, ``baro_scale_psd``: the baro error proportional to the height change (0 where
  the true atmosphere is the calibration's);
* ``terrain_h``, ``P0_terrain``, ``terrain_psd``: flat terrain at a known height (the
  site rather than a sensor's error: ``altfusion evaluate`` tells it in every ``--told``
  mode, :func:`altfusion.evaluation.told.split_site`);
* ``P0_acc_bias``, ``acc_bias_psd``: the accelerometer's turn-on bias (1σ squared) and its
  drift.
"""

import math

from altfusion.sensors.accelerometer import AccelerometerParams
from altfusion.sensors.air_data import AirDataParams
from altfusion.systems import bao2017, hajiyev, whang2008, xu2016
from altfusion.systems.sensors import SEED_003_SENSORS

CALIBRATED_OFFSET_VARIANCE = 0.01
"""m²: a barometer calibrated at launch has no offset from the launch height; 0.1 m (1σ) is
the pressure resolution of the MS5611 class (1.2 Pa)."""

KNOWN = 1e-8
"""The variance of a quantity known exactly (the parameters must be positive)."""

CALIBRATED = {"P0_offset": CALIBRATED_OFFSET_VARIANCE}
NO_SCALE_ERROR = {"P0_scale": 0.0, "baro_scale_psd": 0.0}
"""The true atmosphere is the calibration's: the baro error does not grow with height."""
FLAT_TERRAIN = {"terrain_h": 0.0, "P0_terrain": KNOWN, "terrain_psd": 0.0}
"""The systems' Atmosphere has flat terrain at 0 m."""


def _whang2008_scale_psd() -> float:
    """whang2008's lapse rate, redrawn every 10 s with σ 0.003 K/m, makes the calibrated baro
    err by -δΓ·h²/(2 T0): a local scale error -δΓ·h/T0 of 1σ 0.042 at the 4000 m cruise,
    reached over the 440 s climb; as a random walk of the scale factor, (0.042)²/440 s."""
    top, climb = 4000.0, 440.0
    scale_std = whang2008.ATMOSPHERE["lapse_rate_std"] * top / 288.15
    return scale_std**2 / climb


XU2016 = {**CALIBRATED, **FLAT_TERRAIN,
          "baro_bias_psd": AirDataParams().drift_variance_rate,
          "P0_acc_bias": xu2016.SENSORS["accelerometer"]["bias_std"] ** 2,
          "acc_bias_psd": 0.0}
"""xu2016's sensors (``xu2016.SENSORS``): the laser over flat terrain at 0 m, the MEMS baro
calibrated at take-off with the AirDataModule's default drift, the accelerometer's turn-on
bias of σ 0.03 m/s², constant over the flight."""

WIND_BARO_NOISE = math.hypot(xu2016.SENSORS["air_data"]["height_noise_std"],
                             0.45 * xu2016.WIND_GRADE_3["gust_std"])
"""m: in wind grade 3 the gusts (σ 1 m/s) move the baro height by 0.45 m per 1 m/s (the
dynamic pressure on the static port, ``xu2016``'s docstring), on top of its 0.5 m noise."""

HAJIYEV_DRIFT_RATE = 1.0
"""m/s: hajiyev's drifting p0 and T0 make the baro read low by about 1 m more every second
(77 m in the first 78 s of the drift)."""

SENSOR_ERRORS: dict[str, dict[str, float]] = {
    "whang2008": {**CALIBRATED,
                  "baro_bias_psd": whang2008.SENSORS["air_data"]["drift_variance_rate"],
                  "baro_scale_psd": _whang2008_scale_psd()},
    "bao2017": {**CALIBRATED, **NO_SCALE_ERROR,
                "baro_bias_psd": bao2017.SENSORS["air_data"]["drift_variance_rate"]},
    "hajiyev": {**CALIBRATED, **NO_SCALE_ERROR,
                "baro_bias_psd": hajiyev.SENSORS["air_data"]["drift_variance_rate"]},
    # the drift as a random walk that moves by its rate within one sample period
    "hajiyev_drift": {**CALIBRATED,
                      "baro_bias_psd": HAJIYEV_DRIFT_RATE**2 * hajiyev.SAMPLE_PERIOD},
    "yang2020": {**CALIBRATED, **NO_SCALE_ERROR, **FLAT_TERRAIN,
                 "baro_bias_psd": SEED_003_SENSORS["air_data"]["drift_variance_rate"],
                 # yang2020's accelerometer: no turn-on bias
                 "P0_acc_bias": max(SEED_003_SENSORS["accelerometer"].get(
                     "bias_std", AccelerometerParams().bias_std) ** 2, KNOWN),
                 "acc_bias_psd": 0.0},
    "xu2016_hover15": XU2016,
    "xu2016_hover35": XU2016,
    "xu2016_multipoint": XU2016,
    "xu2016_multipoint_wind": {**XU2016, "baro_noise": WIND_BARO_NOISE},
}
"""System name -> its sensors' error models by parameter name (the module docstring)."""
