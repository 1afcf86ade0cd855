"""Wiring an estimator to the sensor block of :mod:`.sensors` by contract names.

An estimator's inputs carry the names of the sensor outputs they read
(``docs/signals.md``): ``baro_*`` come from the ``air_data`` component, ``gps_*``
from ``gnss``, ``acc_*`` from ``accelerometer``, ``radar_*`` from ``radar`` and ``laser_*``
from ``laser``; inputs outside the sensor streams come from :data:`EXTRA_SOURCES`. The
inputs are those the estimator's core class declares (the FMU declares the same;
``system_tests/test_replay.py`` checks them against the built FMUs).
"""

from altfusion.estimators.base import Estimator
from altfusion.systems.spec import Connection

SENSOR_OF_PREFIX = {"baro": "air_data", "gps": "gnss", "acc": "accelerometer",
                    "radar": "radar", "laser": "laser"}
"""Sensor component (see :data:`altfusion.systems.sensors.SENSORS`) of each signal prefix."""

EXTRA_SOURCES = {"wind_speed": "atmosphere.wind_speed"}
"""Sources of the estimator inputs that are no sensor output (``extra_inputs``): the wind
speed of bao2017's wind correction (eq. 11), the wind the air-data module feels."""


def estimator_connections(estimator: type[Estimator], component: str = "estimator",
                          sensors: tuple[str, ...] | None = None) -> tuple[Connection, ...]:
    """Every input ``estimator`` declares, from the sensor output of the same name; with
    ``sensors``, only the inputs from those sensor components (an estimator that takes any
    subset of the sensors, AltitudeEKF, in a system without some of them: its unconnected
    streams never deliver a sample)."""
    connections = []
    for name in estimator.declared_inputs():
        if name in EXTRA_SOURCES:
            connections.append(Connection(EXTRA_SOURCES[name], f"{component}.{name}"))
            continue
        sensor = SENSOR_OF_PREFIX.get(name.partition("_")[0])
        if sensor is None:
            raise ValueError(f"{estimator.__name__} input '{name}' is no sensor output of "
                             f"{sorted(SENSOR_OF_PREFIX.values())}")
        if sensors is None or sensor in sensors:
            connections.append(Connection(f"{sensor}.{name}", f"{component}.{name}"))
    return tuple(connections)
