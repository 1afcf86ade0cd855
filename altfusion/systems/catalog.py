"""The catalog of systems: name -> function building its :class:`SystemSpec`."""

from collections.abc import Callable

from altfusion.cosim.system import Metric, SystemSpec
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.replay import LOGS, catalog_replay


def plant_yang2020() -> SystemSpec:
    """Seed 003's 420 s climb/cruise/descend flown on the true altitude."""
    return SystemSpec(
        name="plant_yang2020",
        description="VerticalDynamics + Atmosphere + FlightController flying seed 003's "
                    "climb/cruise/descend profile, closed on the true altitude",
        components=plant_components("yang2020"),
        connections=plant_connections(),
        stop_time=420.0,
        output_interval=0.1,
        record=("plant.h", "plant.vz", "plant.az", "controller.h_ref", "controller.vz_ref",
                "controller.thrust", "atmosphere.p_static", "atmosphere.T_air"),
        metrics=(Metric("tracking error", "plant.h", "controller.h_ref"),),
    )


SYSTEMS: dict[str, Callable[[], SystemSpec]] = {
    "plant_yang2020": plant_yang2020,
    **{name: (lambda name=name: catalog_replay(name)) for name in LOGS},
}

DEFAULT_SYSTEM = "plant_yang2020"


def build_system(name: str) -> SystemSpec:
    """The system called ``name``."""
    if name not in SYSTEMS:
        raise KeyError(f"unknown system {name!r}; known: {sorted(SYSTEMS)}")
    return SYSTEMS[name]()
