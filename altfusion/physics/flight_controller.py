"""Altitude-tracking flight controller: PID on altitude with feedforward, producing thrust.

    a_cmd  = az_ref + kp (h_ref - h_fb) + kd (vz_ref - vz_fb) + ki ∫(h_ref - h_fb) dt
    thrust = m (g + a_cmd) + c vz_ref |vz_ref|,   saturated to [0, thrust_max]

The gains are normalised by the mass (kp in 1/s², kd in 1/s, ki in 1/s³). Their defaults come
from the pole-placement design on the linearised VerticalDynamics made with python-control in
:mod:`altfusion.physics.controller_design` (closed-loop poles, margins: docs/controller_design.md).
The altitude feedback ``h_fb``/``vz_fb`` is an input: a system closes the loop on truth or on an
estimator's output. The integrator stops while the thrust saturates (anti-windup).

Guards: non-finite feedback is refused (the step fails naming it); absurd finite feedback is
bounded by the saturation (an infinite command is clipped to 0 or ``thrust_max``), and feedback
whose command is undefined (inf - inf) is refused.
"""

import math
from dataclasses import dataclass

from altfusion.component import Component
from altfusion.constants import G0
from altfusion.params import param
from altfusion.physics.profiles import PROFILE_NAMES, make_profile
from altfusion.timegrid import TickClock

DESIGN_KP = 5.25
DESIGN_KD = 3.0
DESIGN_KI = 3.25
"""Gains of the python-control design (poles -1, -1 ± 1.5j rad/s); checked by the tests."""


@dataclass(frozen=True)
class FlightControllerParams:
    profile: str = param("yang2020", None, "Altitude profile: " + ", ".join(PROFILE_NAMES))
    profile_table: str = param(
        "", None, "Breakpoints 't h; t h; ...' (s, m) for profile = table"
    )
    profile_offset: float = param(0.0, "m", "Altitude (MSL) of the profile's zero")
    mass: float = param(1.5, "kg", "Vehicle mass used by the control law", positive=True)
    drag_coefficient: float = param(
        0.05, "kg/m", "Drag coefficient used for the feedforward", min=0.0
    )
    gravity: float = param(G0, "m/s2", "Gravitational acceleration", positive=True)
    kp: float = param(DESIGN_KP, "1/s2", "Altitude-error gain", min=0.0)
    kd: float = param(DESIGN_KD, "1/s", "Vertical-speed-error gain", min=0.0)
    ki: float = param(DESIGN_KI, "1/s3", "Integral gain", min=0.0)
    thrust_max: float = param(40.0, "N", "Maximum thrust", positive=True)


class FlightController(Component):
    """Inputs ``h_fb``, ``vz_fb``; outputs ``thrust``, ``h_ref``, ``vz_ref``, ``az_ref``."""

    Params = FlightControllerParams

    def __init__(self, params: FlightControllerParams | None = None, **kwargs):
        self.h_fb = 0.0
        self.vz_fb = 0.0
        super().__init__(params, **kwargs)

    def configure(self, clock: TickClock) -> None:
        p = self.params
        self._profile = make_profile(p.profile, p.profile_offset, p.profile_table)

    def reset(self) -> None:
        self.integral = 0.0
        self.h_ref, self.vz_ref, self.az_ref = self._profile.reference(self.time)
        self.thrust = self._thrust(0.0, 0.0)[0]

    def update(self) -> None:
        h_fb, vz_fb = self.h_fb, self.vz_fb
        if not (math.isfinite(h_fb) and math.isfinite(vz_fb)):
            raise ValueError(f"feedback h_fb = {h_fb!r}, vz_fb = {vz_fb!r} not finite")
        self.h_ref, self.vz_ref, self.az_ref = self._profile.reference(self.clock.now)
        error = self.h_ref - h_fb
        integral = self.integral + error * self.clock.step_size
        self.thrust, saturated = self._thrust(error, integral)
        if not saturated:
            self.integral = integral

    def _thrust(self, error: float, integral: float) -> tuple[float, bool]:
        """Thrust for an altitude error and error integral; also whether it saturated."""
        p = self.params
        vz_ref = self.vz_ref
        accel = self.az_ref + p.kp * error + p.kd * (vz_ref - self.vz_fb) + p.ki * integral
        thrust = p.mass * (p.gravity + accel) + p.drag_coefficient * vz_ref * abs(vz_ref)
        if math.isnan(thrust):      # inf - inf from absurd feedback; +-inf is clipped below
            raise ValueError(f"feedback h_fb = {self.h_fb!r}, vz_fb = {self.vz_fb!r} gives "
                             f"no thrust")
        clipped = min(max(thrust, 0.0), p.thrust_max)
        return clipped, clipped != thrust
