"""The atmosphere around the vehicle: static pressure, temperature, wind and terrain.

A lapse-rate atmosphere (ISA by default: troposphere with lapse rate Γ, isothermal above the
tropopause) whose sea-level pressure p0, temperature T0 and lapse rate change with time:

* linear drift of p0 and T0 from ``drift_start_time`` (hajiyev, Section 5);
* a random lapse-rate change every ``lapse_rate_period`` seconds, Γ = Γ_nominal + N(0, σ²),
  held until the next change (whang2008, Section 3: every 10 s, σ = 0.003 K/m);
* wind speed = mean + first-order Gauss-Markov gust, clipped at 0 (drives bao2017's
  dynamic-pressure disturbance in the air-data sensor);
* terrain height under the vehicle: flat, or a table of terrain height versus time.

A barometer calibrated at launch and flown in this atmosphere shows the scale-factor and bias
errors of whang2008 eqs. (2)-(4) without them being injected.

Guard: the input altitude ``h`` is refused (the step fails naming it) when it is NaN or outside
[``H_MIN``, ``H_MAX``], so no output is NaN while the status is OK.
"""

import math
from dataclasses import dataclass

import numpy as np

from altfusion.component import Component
from altfusion.constants import G0, ISA_LAPSE_RATE, ISA_P0, ISA_T0, ISA_TROPOPAUSE_H, R_AIR
from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.physics.barometric import pressure_at, temperature_at
from altfusion.physics.gauss_markov import gauss_markov_step
from altfusion.tables import parse_table
from altfusion.timegrid import TickClock


@dataclass(frozen=True)
class AtmosphereParams:
    p0: float = param(ISA_P0, "Pa", "Sea-level static pressure at t = 0", positive=True)
    T0: float = param(ISA_T0, "K", "Sea-level air temperature at t = 0", positive=True)
    lapse_rate: float = param(
        ISA_LAPSE_RATE, "K/m", "Nominal tropospheric lapse rate dT/dh", min=-0.0342, max=0.01
    )
    p0_rate: float = param(0.0, "Pa/s", "Linear drift rate of the sea-level pressure")
    T0_rate: float = param(0.0, "K/s", "Linear drift rate of the sea-level temperature")
    drift_start_time: float = param(0.0, "s", "Time at which the linear drifts start", min=0.0)
    lapse_rate_std: float = param(
        0.0, "K/m", "Standard deviation of the random lapse-rate changes", min=0.0, max=0.01
    )
    lapse_rate_period: float = param(
        10.0, "s", "Period of the random lapse-rate changes", positive=True
    )
    wind_mean: float = param(0.0, "m/s", "Mean wind speed", min=0.0)
    gust_std: float = param(0.0, "m/s", "Standard deviation of the wind gusts", min=0.0)
    gust_time_constant: float = param(
        2.0, "s", "Correlation time of the first-order Gauss-Markov gusts", positive=True
    )
    terrain_height: float = param(0.0, "m", "Height of flat terrain (MSL)")
    terrain_profile: str = param(
        "", None, "Terrain height versus time as 't h; t h; ...' (s, m); empty: flat terrain"
    )
    gravity: float = param(G0, "m/s2", "Gravitational acceleration", positive=True)
    gas_constant: float = param(R_AIR, "J/(kg.K)", "Specific gas constant of air", positive=True)
    seed: int = param(0, None, "Seed of this component's random streams", min=0)


H_MIN = -1000.0
"""Lowest input altitude accepted, m (below the Dead Sea shore, -430 m)."""
H_MAX = 50_000.0
"""Highest input altitude accepted, m (the stratopause: above it the isothermal layer is
no longer a model of anything)."""


class Atmosphere(Component):
    """Time-varying lapse-rate atmosphere evaluated at the vehicle's true altitude."""

    Params = AtmosphereParams

    def __init__(self, params: AtmosphereParams | None = None, **kwargs):
        self.h = 0.0
        super().__init__(params, **kwargs)

    def configure(self, clock: TickClock) -> None:
        p = self.params
        self._lapse_ticks = clock.ticks_in(p.lapse_rate_period, "lapse_rate_period")
        self._terrain = (
            parse_table(p.terrain_profile, "terrain_profile") if p.terrain_profile else None
        )
        if p.T0 + p.lapse_rate * ISA_TROPOPAUSE_H <= 0:
            raise ParameterError("lapse_rate", p.lapse_rate, "gives T <= 0 K below 11 km")
        self._gust_phi = math.exp(-clock.step_size / p.gust_time_constant)   # over one tick

    def reset(self) -> None:
        p = self.params
        streams = np.random.SeedSequence(p.seed).spawn(2)
        self._lapse_rng = np.random.default_rng(streams[0])
        self._gust_rng = np.random.default_rng(streams[1])
        self.lapse_rate_actual = p.lapse_rate
        self.gust = p.gust_std * self._gust_rng.standard_normal()
        self._evaluate()

    def update(self) -> None:
        p = self.params
        if not H_MIN <= self.h <= H_MAX:    # also refuses NaN
            raise ValueError(f"input h = {self.h!r} m outside the model's range "
                             f"[{H_MIN:g}, {H_MAX:g}] m")
        if p.lapse_rate_std > 0 and self.clock.ticks % self._lapse_ticks == 0:
            self.lapse_rate_actual = p.lapse_rate + p.lapse_rate_std * (
                self._lapse_rng.standard_normal()
            )
        if p.gust_std > 0:
            self.gust = gauss_markov_step(self.gust, self._gust_phi, p.gust_std,
                                          self._gust_rng.standard_normal())
        self._evaluate()

    def _evaluate(self) -> None:
        """Set every output for the current time and input altitude ``h``."""
        p = self.params
        now = self.clock.now
        drift_time = max(0.0, now - p.drift_start_time)
        self.p0_actual = p.p0 + p.p0_rate * drift_time
        self.T0_actual = p.T0 + p.T0_rate * drift_time
        self.p_static, self.T_air = self.static_conditions(self.h)
        self.rho_air = self.p_static / (p.gas_constant * self.T_air)
        self.wind_speed = max(0.0, p.wind_mean + self.gust)
        if self._terrain is None:
            self.terrain_h = p.terrain_height
        else:
            self.terrain_h = float(np.interp(now, self._terrain[:, 0], self._terrain[:, 1]))

    def static_conditions(self, h: float) -> tuple[float, float]:
        """(static pressure Pa, temperature K) at altitude h in the current atmosphere."""
        p = self.params
        lapse = self.lapse_rate_actual
        h_trop = min(h, ISA_TROPOPAUSE_H)
        pressure = pressure_at(h_trop, self.p0_actual, self.T0_actual, lapse, 0.0, p.gravity,
                               p.gas_constant)
        temperature = temperature_at(h_trop, self.T0_actual, lapse)
        if h > ISA_TROPOPAUSE_H:
            pressure = pressure_at(h, pressure, temperature, 0.0, ISA_TROPOPAUSE_H, p.gravity,
                                   p.gas_constant)
        return pressure, temperature
