"""The plant block shared by every scenario: vertical dynamics, atmosphere, flight controller."""

from altfusion.physics.profiles import make_profile
from altfusion.systems.spec import ComponentSpec, Connection

VEHICLE = {"mass": 1.5, "drag_coefficient": 0.05}
"""A 1.5 kg multirotor; the controller is given the same mass and drag coefficient."""


def plant_components(profile: str, step: float = 0.01, atmosphere: dict | None = None,
                     controller: dict | None = None, dynamics: dict | None = None,
                     ) -> tuple[ComponentSpec, ...]:
    """``plant`` (VerticalDynamics), ``atmosphere`` and ``controller`` at the base step.

    The vehicle starts on the profile: h0 and vz0 are the profile's values at t = 0.
    """
    controller = {**VEHICLE, "profile": profile, **(controller or {})}
    h0, vz0, _ = make_profile(profile, controller.get("profile_offset", 0.0),
                              controller.get("profile_table", "")).reference(0.0)
    start = {"h0": h0, "vz0": vz0, "ground_h": min(0.0, h0)}
    return (
        ComponentSpec("plant", "VerticalDynamics", step, {**VEHICLE, **start, **(dynamics or {})}),
        ComponentSpec("atmosphere", "Atmosphere", step, dict(atmosphere or {})),
        ComponentSpec("controller", "FlightController", step, controller),
    )


def plant_connections(h_fb: str = "plant.h", vz_fb: str = "plant.vz") -> tuple[Connection, ...]:
    """Thrust to the plant, the plant's altitude to the atmosphere, feedback to the controller."""
    return (
        Connection("controller.thrust", "plant.thrust"),
        Connection("plant.h", "atmosphere.h"),
        Connection(h_fb, "controller.h_fb"),
        Connection(vz_fb, "controller.vz_fb"),
    )
