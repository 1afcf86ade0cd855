"""Fault demonstration: yang2020's climb/cruise/descend (``yang2020``) flown closed loop through
three faults of the suite (docs/faults.md), once on AltitudeEKF and once on YangFusionKF.

* accelerometer bias :data:`ACC_BIAS` from the start (``acc_bias``; the Accelerometer's own
  constant bias);
* GNSS outage :data:`GPS_OUTAGE` (the GnssReceiver's scheduled outage window: no fix);
* the barometer failing +200 m at :data:`BARO_FAILURE` and staying there (``baro_step``,
  the SensorFaults component inserted by :func:`~altfusion.systems.faults.with_fault`).

Sensors, steps and the estimators' noise parameters are those of ``yang2020`` (yang2020
Section 4.2; AltitudeEKF gets the noises only, its bias priors stay the defaults); the same
run of a campaign gives both systems the same weather and sensor noise.
``benchmarks/fault_demo.py`` flies both and draws ``docs/fault_demo.png``.
"""

from dataclasses import replace

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.yang import YangFusionKF
from altfusion.systems.faults import FAULT_COMPONENT, with_fault
from altfusion.systems.spec import SystemSpec
from altfusion.systems.yang2020 import ALTITUDE_EKF_NOISES, closed_loop

ACC_BIAS = 0.2
"""Accelerometer bias, m/s² (the fault suite's 0.1-0.4 m/s²)."""
GPS_OUTAGE = (100.0, 160.0)
"""No GNSS fix in this window, s: during the climb to the cruise."""
BARO_FAILURE = 250.0
"""The barometer's height steps by +200 m at this time, s (in the cruise), and stays."""

SENSOR_FAULTS = {"accelerometer": {"bias": ACC_BIAS},
                 "gnss": {"outage_windows": f"{GPS_OUTAGE[0]:g} {GPS_OUTAGE[1]:g}"}}

DESCRIPTION = (f"yang2020's loop (see yang2020) through three faults: accelerometer bias "
               f"{ACC_BIAS:g} m/s² from the start, no GNSS fix {GPS_OUTAGE[0]:g}-"
               f"{GPS_OUTAGE[1]:g} s, baro +200 m from {BARO_FAILURE:g} s; flown on ")


def _demo(name: str, estimator: type, parameters: dict) -> SystemSpec:
    spec = closed_loop(name, DESCRIPTION + estimator.__name__, estimator, parameters,
                       ("estimator.h_valid", "estimator.status", "estimator.n_rejected"))
    spec = replace(spec, components=tuple(
        replace(c, parameters={**c.parameters, **SENSOR_FAULTS.get(c.name, {})})
        for c in spec.components))
    spec = with_fault(spec, "baro_step")
    return replace(spec, name=name, components=tuple(
        replace(c, parameters={**c.parameters, "fault_start": BARO_FAILURE})
        if c.name == FAULT_COMPONENT else c for c in spec.components))


def fault_demo_altitude_ekf() -> SystemSpec:
    """The fault demonstration flown on AltitudeEKF: yang2020's noises, its defaults for
    everything the faults change (bias priors and random walks: the estimator is not told
    of the faults)."""
    return _demo("fault_demo_altitude_ekf", AltitudeEKF, ALTITUDE_EKF_NOISES)


def fault_demo_yang() -> SystemSpec:
    """The fault demonstration flown on YangFusionKF (its defaults: yang2020's variances)."""
    return _demo("fault_demo_yang", YangFusionKF, {})
