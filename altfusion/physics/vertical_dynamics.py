"""Point-mass vertical motion of a UAV: thrust, gravity and quadratic drag.

    dh/dt  = vz
    dvz/dt = (thrust - m g - c vz |vz|) / m

The thrust input is held over each communication step (zero-order hold) and the state is
integrated with classical RK4 on internal sub-steps no longer than ``max_substep``, exactly to the
end of any communication step: a step of one tick (``step_size``) takes the tick's fixed
sub-steps, any other step (a host's 1e-3 s, its 1e-13 s remainder, a step of several ticks)
its own equal sub-steps from where the state is. The vehicle rests on the ground at ``ground_h``
and cannot sink below it. Outputs are the state at the end of the step; ``az`` is the
acceleration at that instant under the thrust held over the step, so no output depends on the
thrust value set for the next step (no direct feedthrough).

Guards: a non-finite thrust is refused, and so is a thrust that drives the state non-finite
(for example 1e308 N: the step fails with a message naming the input and the state is kept);
``max_substep`` is refused when a step would need more than ``MAX_SUBSTEPS`` sub-steps, so no
parameter can make a step run unboundedly long.
"""

import math
from dataclasses import dataclass

from altfusion.component import Component
from altfusion.constants import G0
from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.timegrid import TickClock

MAX_SUBSTEPS = 10_000
"""Most RK4 sub-steps per communication step (about 20 ms of Python per step)."""


@dataclass(frozen=True)
class VerticalDynamicsParams:
    mass: float = param(
        1.5, "kg", "Vehicle mass. At least 1 g (a micro air vehicle): the controller's thrust "
        "(N) on a lighter mass accelerates beyond any floating-point state (1e-300 kg: "
        "1e301 m/s2)", positive=True, min=0.001,
    )
    drag_coefficient: float = param(
        0.05, "kg/m", "Quadratic drag coefficient c: drag force = -c vz |vz|", min=0.0
    )
    h0: float = param(0.0, "m", "Initial altitude (MSL)")
    vz0: float = param(0.0, "m/s", "Initial vertical speed, positive up")
    ground_h: float = param(0.0, "m", "Ground height (MSL) the vehicle rests on")
    gravity: float = param(G0, "m/s2", "Gravitational acceleration", positive=True)
    max_substep: float = param(
        0.005, "s", "Longest internal RK4 sub-step", positive=True, max=1.0
    )


class VerticalDynamics(Component):
    """Vertical channel of the vehicle; input ``thrust``, outputs ``h``, ``vz``, ``az``."""

    Params = VerticalDynamicsParams

    def __init__(self, params: VerticalDynamicsParams | None = None, **kwargs):
        self.thrust = 0.0
        super().__init__(params, **kwargs)

    def configure(self, clock: TickClock) -> None:
        p = self.params
        if p.h0 < p.ground_h:
            raise ParameterError("h0", p.h0, f"is below ground_h = {p.ground_h}")
        self._substeps = max(1, math.ceil(clock.step_size / p.max_substep - 1e-9))
        if self._substeps > MAX_SUBSTEPS:
            raise ParameterError("max_substep", p.max_substep,
                                 f"needs {self._substeps} sub-steps per step of "
                                 f"{clock.step_size} s; at most {MAX_SUBSTEPS}")
        self._substep = clock.step_size / self._substeps

    def reset(self) -> None:
        p = self.params
        self.h = p.h0
        self.vz = p.vz0
        self.az = self.acceleration(self.vz, self.thrust)
        self._settle_on_ground()

    def acceleration(self, vz: float, thrust: float) -> float:
        """dvz/dt for a given vertical speed and thrust, m/s²."""
        p = self.params
        return (thrust - p.mass * p.gravity - p.drag_coefficient * vz * abs(vz)) / p.mass

    def do_step(self, current_time: float, step_size: float) -> None:
        clock = self.clock
        start = clock.host_time
        due = clock.due(current_time, step_size)
        for _ in range(due):
            clock.tick()
        end = clock.host_time
        if due == 1 and end == clock.now and start == clock.time(clock.ticks - 1):
            self.update()                       # one tick on the grid: its fixed sub-steps
        elif end > start:
            span = end - start
            substeps = max(1, math.ceil(span / self.params.max_substep - 1e-9))
            self._integrate(substeps, span / substeps)

    def update(self) -> None:
        self._integrate(self._substeps, self._substep)

    def _integrate(self, substeps: int, dt: float) -> None:
        """RK4 over ``substeps`` sub-steps of ``dt`` with the thrust held."""
        thrust = self.thrust
        if not math.isfinite(thrust):
            raise ValueError(f"input thrust = {thrust!r} is not finite")
        p = self.params
        mass, drag, ground_h = p.mass, p.drag_coefficient, p.ground_h
        # acceleration(vz, thrust) written out: (thrust - m g - c vz |vz|) / m, the same
        # operations in the same order, with thrust - m g (its first) taken once.
        net = thrust - mass * p.gravity
        h, vz = self.h, self.vz
        half_dt, sixth_dt = 0.5 * dt, dt / 6.0
        for _ in range(substeps):
            # Classical RK4 on (h, vz) with the thrust held constant.
            a1 = (net - drag * vz * abs(vz)) / mass
            v2 = vz + half_dt * a1
            a2 = (net - drag * v2 * abs(v2)) / mass
            v3 = vz + half_dt * a2
            a3 = (net - drag * v3 * abs(v3)) / mass
            v4 = vz + dt * a3
            a4 = (net - drag * v4 * abs(v4)) / mass
            h += sixth_dt * (vz + 2.0 * v2 + 2.0 * v3 + v4)
            vz += sixth_dt * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            if h <= ground_h and vz <= 0.0:
                h, vz = ground_h, 0.0
        az = (net - drag * vz * abs(vz)) / mass
        if not (math.isfinite(h) and math.isfinite(vz) and math.isfinite(az)):
            raise ValueError(f"input thrust = {thrust!r} N drives the state non-finite "
                             f"(h = {h!r}, vz = {vz!r}); state kept at h = {self.h!r} m")
        self.h, self.vz, self.az = h, vz, az
        if h <= ground_h and vz <= 0.0 and az <= 0.0:      # _settle_on_ground(), inlined
            self.h, self.vz, self.az = ground_h, 0.0, 0.0

    def _settle_on_ground(self) -> None:
        """On the ground with a net downward force the vehicle rests: vz = az = 0."""
        if self.h <= self.params.ground_h and self.vz <= 0.0 and self.az <= 0.0:
            self.h, self.vz, self.az = self.params.ground_h, 0.0, 0.0
