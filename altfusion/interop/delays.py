"""The sensor delays of a Jacobi-type master (libcosim, ECOS, our ``master="jacobi"``).

A Jacobi master latches every input at the start of its consumer's step. A sensor stepped
from t to t + T therefore samples the plant's output of t and stamps its sample t + T: its
measurements are one sensor step older than their stamps. Our ordered master steps the plant
before the sensors, so there they are not. An estimator with sensor-delay parameters
(AltitudeEKF's ``baro_delay``, ``gps_delay`` and ``range_delay``, YangFusionKF's
``gps_delay``) fuses a sample against its state taken back to the stamp less the delay; a
user of a Jacobi-type host sets each to the step of the sensor the samples come from, and
:func:`jacobi_sensor_delays` does so for a system.
"""

from pathlib import Path

from altfusion.cosim.instances import fmu_info
from altfusion.estimators.base import MAX_DELAY
from altfusion.systems.sensors import SENSORS
from altfusion.systems.spec import ComponentSpec, SystemSpec

DELAY_OF_STAMP = {"baro_time": "baro_delay", "gps_time": "gps_delay",
                  "radar_time": "range_delay", "laser_time": "range_delay"}
"""An estimator's time-stamp input -> the delay parameter of its samples."""

SENSOR_FMUS = frozenset(sensor.fmu for sensor in SENSORS.values())
"""The FMUs that sample the plant (a log replay's samples carry their own instants)."""


def sampling_sensor(system: SystemSpec, end: str) -> ComponentSpec | None:
    """The sensor whose samples reach input ``end`` ('component.variable'), through any
    component that passes them on from an input ``raw_<variable>`` (SensorFaults); None if
    they come from no sensor."""
    producers = {connection.end: connection.start for connection in system.connections}
    start = producers.get(end)
    while start is not None:
        name, _, variable = start.partition(".")
        component = system.component(name)
        if component.fmu in SENSOR_FMUS:
            return component
        start = producers.get(f"{name}.raw_{variable}")
    return None


def jacobi_sensor_delays(system: SystemSpec, fmu_paths: dict[str, Path]) -> SystemSpec:
    """``system`` with every estimator's sensor-delay parameters the step of the sensor its
    samples come from (module docstring). A parameter the system sets already keeps its
    value; one fed by sensors of different steps (a radio altimeter and a laser for one
    ``range_delay``), or by a sensor stepped longer than the parameters' bound
    (:data:`~altfusion.estimators.base.MAX_DELAY`), is left as it is."""
    overrides = {}
    for component in system.components:
        parameters = {v.name for v in fmu_info(fmu_paths[component.fmu]).variables.values()
                      if v.causality == "parameter"}
        steps: dict[str, set[float]] = {}
        for stamp, parameter in DELAY_OF_STAMP.items():
            sensor = (sampling_sensor(system, f"{component.name}.{stamp}")
                      if parameter in parameters else None)
            if sensor is not None:
                steps.setdefault(parameter, set()).add(sensor.step_size)
        for parameter, found in steps.items():
            if len(found) == 1 and parameter not in component.parameters \
                    and 0.0 < (step := found.pop()) <= MAX_DELAY:
                overrides[f"{component.name}.{parameter}"] = step
    return system.with_parameters(overrides)
