"""GnssReceiver: height and vertical velocity with noise, satellite geometry and outages.

Measurement (yang2020 eq. 1, xu2016 eq. 5, with bao2017 Section 3.3's quality indicators):

    gps_h  = h + height_bias + e_GM + σ_h·n₁,    σ_h = UERE · VDOP · √max(1, N_ref / N)
    gps_vz = vz + σ_v·n₂

* σ_h: the vertical error is the user-equivalent range error times VDOP (the usual DOP error
  model), growing further when the satellites used N fall below ``nsat_reference`` (fewer
  redundant ranges). bao2017 gives no mapping from VDOP and satellites to accuracy; this is
  the one the air-data/GNSS estimators can invert (docs/papers.md, bao2017 eq. 14).
* VDOP and N (``dop_mode``): ``constant``; ``scheduled`` by the tables ``vdop_schedule`` and
  ``nsat_schedule`` ('t value; ...', each value held from its time on, the first one before
  it); or ``random``: N performs a ±1 random walk in [nsat_min, nsat_max] (a change with
  probability 1 - exp(-Δt/nsat_change_time) per sample) and VDOP = vdop·√(nsat / N), the
  1/√N scaling of dilution with the number of well-spread satellites.
* e_GM: an optional first-order Gauss-Markov height error (σ ``gm_std``, correlation time
  ``gm_time_constant``), started from its stationary distribution.
* No fix (outputs hold, ``gps_fix`` false, the count stops): inside a scheduled outage window
  [start, end), inside a random outage (Poisson starts at ``outage_rate``, exponential
  durations of mean ``outage_mean_duration``, a continuous-time process independent of the
  sample period), or with fewer than 4 satellites (no 3D solution).

Every error source has its own random stream and draws at every sampling instant, fix or not,
so outages never shift the noise realization of later samples. Before the first fix the
outputs are 0, ``gps_vdop`` = 99.99 (what receivers report without a solution), ``gps_nsat``
= 0 and ``gps_fix`` false.
"""

import math
from dataclasses import dataclass

import numpy as np

from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.physics.gauss_markov import gauss_markov_step
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams, require_finite
from altfusion.tables import parse_table
from altfusion.timegrid import TickClock

DOP_MODES = ("constant", "scheduled", "random")
MIN_SATELLITES_FOR_FIX = 4
NO_FIX_DOP = 99.99


@dataclass(frozen=True)
class GnssParams(SamplingParams):
    sample_period: float = param(1.0, "s", "Time between fixes (1 Hz)", positive=True)
    user_range_error: float = param(
        2.0, "m", "User-equivalent range error, 1 sigma: sigma_h = UERE*VDOP (single-frequency "
        "GPS: about 2 m; yang2020 simulates sigma_h = 30 m, whang2008 70 m). At most 1000 m: "
        "a receiver reports no fix with a worse solution, and sigma_h (up to 250 UERE) then "
        "stays within the +-100 km the estimators accept as a height (1e200 overflows their "
        "variances)", min=0.0, max=1000.0,
    )
    height_bias: float = param(0.0, "m", "Constant height error (xu2016 Section 2)")
    velocity_noise_std: float = param(
        0.2, "m/s", "White noise of the vertical velocity, 1 sigma (yang2020 Section 4.2). At most "
        "100 m/s: the estimators reject speeds beyond 1000 m/s (Mach 3) as implausible",
        min=0.0, max=100.0,
    )
    gm_std: float = param(
        0.0, "m", "Stationary 1 sigma of the first-order Gauss-Markov height error; 0: none. "
        "At most 1000 m, as user_range_error", min=0.0, max=1000.0,
    )
    gm_time_constant: float = param(
        300.0, "s", "Correlation time of the Gauss-Markov height error", positive=True
    )
    dop_mode: str = param("constant", None, "VDOP and satellites: " + " | ".join(DOP_MODES))
    vdop: float = param(
        1.5, "1", "VDOP (constant mode); in random mode the VDOP with nsat satellites",
        positive=True,
    )
    nsat: int = param(
        10, None, "Satellites used (constant mode); in random mode the initial count", min=0
    )
    nsat_reference: int = param(
        6, None, "Below this many satellites sigma_h grows as sqrt(nsat_reference/nsat)", min=1
    )
    vdop_schedule: str = param(
        "", None, "Scheduled mode: VDOP 't vdop; ...' (s, 1), held; empty: constant vdop"
    )
    nsat_schedule: str = param(
        "", None, "Scheduled mode: satellites 't n; ...' (s, count), held; empty: constant nsat"
    )
    nsat_min: int = param(5, None, "Random mode: fewest satellites", min=1)
    nsat_max: int = param(12, None, "Random mode: most satellites", min=1)
    nsat_change_time: float = param(
        60.0, "s", "Random mode: mean time between changes of the satellite count", positive=True
    )
    outage_windows: str = param(
        "", None, "Scheduled outages 'start end; ...' (s): no fix for samples in [start, end)"
    )
    outage_rate: float = param(0.0, "1/s", "Rate of random outage starts; 0: none", min=0.0)
    outage_mean_duration: float = param(
        10.0, "s", "Mean duration of random outages (exponential)", positive=True
    )


def held_value(table: np.ndarray, t: float) -> float:
    """The value of the last row whose time is <= t (the first row's before it)."""
    row = int(np.searchsorted(table[:, 0], t, side="right")) - 1
    return float(table[max(row, 0), 1])


class GnssReceiver(SampledSensor):
    """Inputs ``h``, ``vz``; outputs ``gps_h``, ``gps_vz``, ``gps_vdop``, ``gps_nsat``,
    ``gps_fix``, ``gps_count``, ``gps_time``."""

    Params = GnssParams
    prefix = "gps"
    streams = ("height_noise", "velocity_noise", "gauss_markov", "geometry", "outage")
    normal_streams = ("height_noise", "velocity_noise", "gauss_markov")

    def __init__(self, params: GnssParams | None = None, **kwargs):
        self.h = 0.0
        self.vz = 0.0
        super().__init__(params, **kwargs)

    # ----------------------------------------------------------------- set-up
    def configure_sensor(self, clock: TickClock) -> None:
        p = self.params
        if p.dop_mode not in DOP_MODES:
            raise ParameterError("dop_mode", p.dop_mode, f"must be one of {DOP_MODES}")
        scheduled = bool(p.vdop_schedule or p.nsat_schedule)
        if scheduled != (p.dop_mode == "scheduled"):
            raise ParameterError("dop_mode", p.dop_mode, "must be 'scheduled' exactly when "
                                 "vdop_schedule or nsat_schedule is given")
        self._vdop_table = self._table("vdop_schedule", integer=False)
        self._nsat_table = self._table("nsat_schedule", integer=True)
        if p.dop_mode == "random":
            if p.nsat_min > p.nsat_max:
                raise ParameterError("nsat_min", p.nsat_min, f"exceeds nsat_max = {p.nsat_max}")
            if not p.nsat_min <= p.nsat <= p.nsat_max:
                raise ParameterError("nsat", p.nsat, "must lie in [nsat_min, nsat_max]")
        self._windows: list[tuple[float, float]] = []
        """The scheduled outages as (start, end) pairs of Python floats."""
        if p.outage_windows:
            windows = parse_table(p.outage_windows, "outage_windows")
            if np.any(windows[:, 1] <= windows[:, 0]):
                raise ParameterError("outage_windows", p.outage_windows,
                                     "each window must end after it starts")
            self._windows = [(start, end) for start, end in windows.tolist()]

    def _table(self, name: str, integer: bool) -> np.ndarray | None:
        text = getattr(self.params, name)
        if not text:
            return None
        table = parse_table(text, name)
        values = table[:, 1]
        if integer and np.any((values < 0) | (values != np.round(values))):
            raise ParameterError(name, text, "satellite counts must be integers >= 0")
        if not integer and np.any(values <= 0):
            raise ParameterError(name, text, "VDOP values must be > 0")
        return table

    def reset_sensor(self) -> None:
        p = self.params
        self.gps_h, self.gps_vz = 0.0, 0.0
        self.gps_vdop, self.gps_nsat, self.gps_fix = NO_FIX_DOP, 0, False
        self._nsat = p.nsat
        self._geometry_tick = 0
        self._gm_error = p.gm_std * self.normal["gauss_markov"].draw()
        self._gm_tick = 0
        self._outage_start = self._outage_end = self.time

    # ----------------------------------------------------------------- error model
    def height_sigma(self, vdop: float, nsat: int) -> float:
        """σ_h = UERE · VDOP · √max(1, N_ref / N), m."""
        p = self.params
        return p.user_range_error * vdop * math.sqrt(max(1.0, p.nsat_reference / max(nsat, 1)))

    def geometry(self, t: float) -> tuple[int, float]:
        """(satellites used, VDOP) at the sampling instant t; in random mode this advances the
        satellite-count walk to t (called once per sample)."""
        p = self.params
        if p.dop_mode == "constant":
            return p.nsat, p.vdop
        if p.dop_mode == "scheduled":
            nsat = p.nsat if self._nsat_table is None else int(held_value(self._nsat_table, t))
            vdop = p.vdop if self._vdop_table is None else held_value(self._vdop_table, t)
            return nsat, vdop
        elapsed = self.ticks_since(self._geometry_tick)
        self._geometry_tick = self.clock.ticks
        change, direction = self.rng["geometry"].random(2)
        if change < -math.expm1(-elapsed / p.nsat_change_time):
            candidate = self._nsat + (1 if direction < 0.5 else -1)
            if p.nsat_min <= candidate <= p.nsat_max:
                self._nsat = candidate
        return self._nsat, p.vdop * math.sqrt(p.nsat / self._nsat)

    def _advance_gauss_markov(self) -> float:
        """The Gauss-Markov height error after the time since its last step."""
        p = self.params
        clock = self.clock
        elapsed = (clock.ticks - self._gm_tick) * clock.step_size          # ticks_since()
        phi = math.exp(-elapsed / p.gm_time_constant)
        self._gm_tick = clock.ticks
        self._gm_error = gauss_markov_step(self._gm_error, phi, p.gm_std,
                                           self.normal["gauss_markov"].draw())
        return self._gm_error

    def in_outage(self, t: float) -> bool:
        """True inside a scheduled window or a random outage at time t."""
        scheduled = False
        for start, end in self._windows:
            if start <= t < end:
                scheduled = True
                break
        return self._in_random_outage(t) or scheduled

    def _in_random_outage(self, t: float) -> bool:
        p = self.params
        if p.outage_rate <= 0:
            return False
        rng = self.rng["outage"]
        while t >= self._outage_end:
            self._outage_start = self._outage_end + rng.exponential(1.0 / p.outage_rate)
            self._outage_end = self._outage_start + rng.exponential(p.outage_mean_duration)
        return t >= self._outage_start

    # ----------------------------------------------------------------- sampling
    def measure(self) -> Sample:
        p = self.params
        h = require_finite("h", self.h)
        vz = require_finite("vz", self.vz)
        t = self.clock.now
        nsat, vdop = self.geometry(t)
        gm_error = self._advance_gauss_markov()
        height_noise = self.height_sigma(vdop, nsat) * self.normal["height_noise"].draw()
        velocity_noise = p.velocity_noise_std * self.normal["velocity_noise"].draw()
        if self.in_outage(t) or nsat < MIN_SATELLITES_FOR_FIX:
            return Sample({"gps_fix": False}, new=False)
        return Sample({
            "gps_h": h + p.height_bias + gm_error + height_noise,
            "gps_vz": vz + velocity_noise,
            "gps_vdop": vdop,
            "gps_nsat": nsat,
            "gps_fix": True,
        })
