"""The sensor block: the five sensor FMUs wired to the plant block of :mod:`.plant`.

Components are named after their role (``air_data``, ``gnss``, ``accelerometer``, ``radar``,
``laser``); each gets its own seed, so changing one sensor's seed changes only that sensor.
Every sensor is stepped at the base step unless ``steps`` says otherwise (its sample period
must be a multiple of its step). Estimator systems add their estimator and connect it to the
sensor outputs named in ``docs/signals.md``.
"""

from dataclasses import dataclass
from typing import Any

from altfusion.systems.spec import ComponentSpec, Connection


@dataclass(frozen=True)
class SensorWiring:
    """A sensor FMU, the plant-block outputs driving its inputs, and its default seed."""

    fmu: str
    inputs: dict[str, str]
    seed: int


SENSORS: dict[str, SensorWiring] = {
    "air_data": SensorWiring("AirDataModule", {"p_static": "atmosphere.p_static",
                                               "T_air": "atmosphere.T_air",
                                               "wind_speed": "atmosphere.wind_speed"}, seed=1),
    "gnss": SensorWiring("GnssReceiver", {"h": "plant.h", "vz": "plant.vz"}, seed=2),
    "accelerometer": SensorWiring("Accelerometer", {"az": "plant.az"}, seed=3),
    "radar": SensorWiring("RadioAltimeter", {"h": "plant.h",
                                             "terrain_h": "atmosphere.terrain_h"}, seed=4),
    "laser": SensorWiring("LaserRangefinder", {"h": "plant.h",
                                               "terrain_h": "atmosphere.terrain_h"}, seed=5),
}

SEED_003_SENSORS: dict[str, dict[str, Any]] = {
    "gnss": {"user_range_error": 30.0, "vdop": 1.0, "velocity_noise_std": 0.2,
             "sample_period": 0.1},
    "air_data": {"height_noise_std": 20.0, "sample_period": 0.01, "drift_rate": 0.0,
                 "drift_variance_rate": 0.0},
    "radar": {"noise_std": 10.0, "sample_period": 0.2},
    "accelerometer": {"noise_std": 0.01, "sample_period": 0.01},
}
"""yang2020 Section 4.2: GPS 30 m and 0.2 m/s every 100 ms (VDOP 1, so σ_h = UERE); the
barometer 20 m every 10 ms with no scale-factor error (and no drift); the radio altimeter
10 m every 200 ms; the IMU 0.01 m/s². The laser is not in yang2020 and keeps its defaults."""


def sensor_components(names: tuple[str, ...] = tuple(SENSORS), step: float = 0.01,
                      parameters: dict[str, dict[str, Any]] | None = None,
                      steps: dict[str, float] | None = None) -> tuple[ComponentSpec, ...]:
    """One component per sensor in ``names``, with its default seed, ``parameters[name]`` and
    the step ``steps[name]`` (default ``step``, the base step)."""
    parameters, steps = parameters or {}, steps or {}
    unknown = (set(parameters) | set(steps) | set(names)) - set(SENSORS)
    if unknown:
        raise KeyError(f"unknown sensors {sorted(unknown)}; known: {list(SENSORS)}")
    return tuple(
        ComponentSpec(name, SENSORS[name].fmu, steps.get(name, step),
                      {"seed": SENSORS[name].seed, **parameters.get(name, {})})
        for name in names
    )


def sensor_connections(names: tuple[str, ...] = tuple(SENSORS)) -> tuple[Connection, ...]:
    """The plant-block outputs to the inputs of each sensor in ``names``."""
    return tuple(Connection(source, f"{name}.{variable}")
                 for name in names for variable, source in SENSORS[name].inputs.items())
