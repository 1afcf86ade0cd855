"""The catalog of systems: name -> function building its :class:`SystemSpec`."""

from collections.abc import Callable
from dataclasses import replace

from altfusion.systems.bao2017 import bao2017
from altfusion.systems.fault_demo import fault_demo_altitude_ekf, fault_demo_yang
from altfusion.systems.faults import fault_flight, with_fault
from altfusion.systems.hajiyev import hajiyev, hajiyev_drift
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.replay import LOGS, catalog_replay
from altfusion.systems.sensors import SEED_003_SENSORS, sensor_components, sensor_connections
from altfusion.systems.spec import Metric, SystemSpec
from altfusion.systems.whang2008 import whang2008, whang2008_baseline
from altfusion.systems.xu2016 import (
    xu2016_hover15,
    xu2016_hover35,
    xu2016_multipoint,
    xu2016_multipoint_wind,
)
from altfusion.systems.yang2020 import yang2020, yang2020_altitude_ekf, yang2020_baseline


def plant_yang2020() -> SystemSpec:
    """yang2020's 420 s climb/cruise/descend flown on the true altitude."""
    return SystemSpec(
        name="plant_yang2020",
        description="VerticalDynamics + Atmosphere + FlightController flying yang2020's "
                    "climb/cruise/descend profile, closed on the true altitude",
        components=plant_components("yang2020"),
        connections=plant_connections(),
        stop_time=420.0,
        output_interval=0.1,
        record=("plant.h", "plant.vz", "plant.az", "controller.h_ref", "controller.vz_ref",
                "controller.thrust", "atmosphere.p_static", "atmosphere.T_air"),
        metrics=(Metric("tracking error", "plant.h", "controller.h_ref"),),
    )


def sensors_yang2020() -> SystemSpec:
    """yang2020's profile flown on the true altitude and sensed by all five sensors with
    yang2020 Section 4.2's error levels; the metrics are each sensor's error."""
    return SystemSpec(
        name="sensors_yang2020",
        description="Plant flying yang2020's climb/cruise/descend profile, sensed by "
                    "AirDataModule, GnssReceiver, Accelerometer, RadioAltimeter and "
                    "LaserRangefinder with yang2020 Section 4.2's noise levels",
        components=plant_components("yang2020") + sensor_components(
            parameters=SEED_003_SENSORS),
        connections=plant_connections() + sensor_connections(),
        stop_time=420.0,
        output_interval=0.1,
        record=("plant.h", "plant.vz", "plant.az", "air_data.baro_h", "gnss.gps_h",
                "radar.radar_h", "laser.laser_h", "gnss.gps_vz", "accelerometer.acc_z",
                "air_data.baro_count", "gnss.gps_count", "radar.radar_count",
                "laser.laser_valid"),
        metrics=(Metric("baro_h error", "air_data.baro_h", "plant.h"),
                 Metric("gps_h error", "gnss.gps_h", "plant.h"),
                 Metric("radar_h error (flat terrain at 0 m)", "radar.radar_h", "plant.h"),
                 Metric("gps_vz error", "gnss.gps_vz", "plant.vz"),
                 Metric("acc_z error", "accelerometer.acc_z", "plant.az")),
    )


def fault_flight_baro_step() -> SystemSpec:
    """The fault suite's flight with the barometer failing by +200 m at 130 s (the
    SensorFaults FMU's reference run)."""
    return replace(with_fault(fault_flight(), "baro_step"), name="fault_flight_baro_step")


SYSTEMS: dict[str, Callable[[], SystemSpec]] = {
    "plant_yang2020": plant_yang2020,
    **{name: (lambda name=name: catalog_replay(name)) for name in LOGS},
    "sensors_yang2020": sensors_yang2020,
    "whang2008": whang2008,
    "whang2008_baseline": whang2008_baseline,
    "hajiyev": hajiyev,
    "hajiyev_drift": hajiyev_drift,
    "yang2020": yang2020,
    "yang2020_baseline": yang2020_baseline,
    "yang2020_altitude_ekf": yang2020_altitude_ekf,
    "bao2017": bao2017,
    "xu2016_hover15": xu2016_hover15,
    "xu2016_hover35": xu2016_hover35,
    "xu2016_multipoint": xu2016_multipoint,
    "xu2016_multipoint_wind": xu2016_multipoint_wind,
    "fault_flight": fault_flight,
    "fault_flight_baro_step": fault_flight_baro_step,
    "fault_demo_altitude_ekf": fault_demo_altitude_ekf,
    "fault_demo_yang": fault_demo_yang,
}

DEFAULT_SYSTEM = "yang2020"


def build_system(name: str) -> SystemSpec:
    """The system called ``name``."""
    if name not in SYSTEMS:
        raise KeyError(f"unknown system {name!r}; known: {sorted(SYSTEMS)}")
    return SYSTEMS[name]()
