"""Altitude reference profiles of the papers' scenarios, as (h, vz, az) functions of time.

Every profile is a feasible trajectory: altitude, vertical speed and acceleration agree, so the
flight controller can use vz and az as feedforward.

=================  ===========================================================================
name               trajectory
=================  ===========================================================================
``yang2020``       yang2020 Section 4.1: climb 0-180 s (+0.2 m/s² to 12 m/s, constant, -0.2
                   m/s² to 0), cruise 180-240 s at 1440 m, descend 240-420 s back to 0 m
``hajiyev``        hajiyev Section 5: the altitude of a static pressure rising from 23 kPa to
                   99.85 kPa by 0.05 kPa per 1 s sample (10,892 m to 123 m), then held
``whang2008``      whang2008 Fig. 2 (not in the text; docs/papers.md): climb at 10 m/s to 4000 m
                   (0.25 m/s² ramps), then cruise
``xu_hover15``     xu2016 Section 3.1: take off to 15 m and hover
``xu_hover35``     xu2016 Section 3.1: take off to 35 m and hover
``xu_multipoint``  xu2016 Section 3.2: hover at 10 m, 22 m, 37 m within 1000 s
``fault_flight``   the fault suite's generic flight: take off at 5 s to 15 m and hover, climb
                   at 60 s to 120 m and cruise, descend at 200 s and land at 264 s
``hold``           hold the offset altitude
``table``          user table 't h; t h; ...' (s, m), linear between points
=================  ===========================================================================

All altitudes are shifted by ``offset`` (m), the height of the profile's zero.
"""

import math
from abc import ABC, abstractmethod
from bisect import bisect_right

import numpy as np

from altfusion.errors import ParameterError
from altfusion.physics.barometric import height_from_pressure
from altfusion.tables import parse_table


class Profile(ABC):
    """An altitude reference: h (m), vz (m/s), az (m/s²) at time t (s)."""

    @abstractmethod
    def reference(self, t: float) -> tuple[float, float, float]:
        """(h_ref, vz_ref, az_ref) at time t."""


class AccelerationSegments(Profile):
    """Piecewise-constant vertical acceleration from a start altitude at rest."""

    def __init__(self, h_start: float, segments: list[tuple[float, float]]):
        self._starts: list[tuple[float, float, float, float]] = []  # (t0, h0, v0, a)
        t, h, v = 0.0, h_start, 0.0
        for duration, accel in segments:
            self._starts.append((t, h, v, accel))
            h += v * duration + 0.5 * accel * duration**2
            v += accel * duration
            t += duration
        self._start_times = [start[0] for start in self._starts]
        self._end = (t, h, v)

    def reference(self, t: float) -> tuple[float, float, float]:
        t_end, h_end, v_end = self._end
        if t >= t_end:
            return h_end + v_end * (t - t_end), v_end, 0.0
        # The last segment started by t (the first one before it); starts never decrease.
        t0, h0, v0, accel = self._starts[max(bisect_right(self._start_times, t) - 1, 0)]
        tau = max(0.0, t - t0)
        return h0 + v0 * tau + 0.5 * accel * tau**2, v0 + accel * tau, accel


def trapezoid_moves(
    h_start: float,
    moves: list[tuple[float, float]],
    accel_max: float,
    speed_max: float,
) -> AccelerationSegments:
    """Rest-to-rest moves to altitude ``h`` starting at time ``t`` for each (t, h) in ``moves``,
    with trapezoidal (or triangular) speed profiles."""
    segments: list[tuple[float, float]] = []
    t, h = 0.0, h_start
    for t_move, h_target in moves:
        if t_move < t:
            raise ValueError(f"move at t = {t_move} s starts before the previous one ends ({t} s)")
        if t_move > t:
            segments.append((t_move - t, 0.0))
        distance = abs(h_target - h)
        sign = 1.0 if h_target >= h else -1.0
        if distance >= speed_max**2 / accel_max:
            t_accel = speed_max / accel_max
            t_cruise = (distance - speed_max**2 / accel_max) / speed_max
        else:
            t_accel = math.sqrt(distance / accel_max)
            t_cruise = 0.0
        segments += [(t_accel, sign * accel_max), (t_cruise, 0.0), (t_accel, -sign * accel_max)]
        t = t_move + 2 * t_accel + t_cruise
        h = h_target
    return AccelerationSegments(h_start, segments)


class PressureDescent(Profile):
    """hajiyev Section 5: the altitude whose ISA pressure rises linearly in time.

    p(t) = p_start + rate·t up to p_end, h = eq. (1) with the paper's constants
    (p0 = 101.325 kPa, T0 = 288.15 K, lapse rate 0.0065 K/m, g = 9.81 m/s², R = 287 J/(kg·K)).
    """

    P0, T0, LAPSE, G, R = 101325.0, 288.15, -0.0065, 9.81, 287.0

    def __init__(self, p_start: float, p_end: float, rate: float, offset: float = 0.0):
        self.p_start, self.p_end, self.rate, self.offset = p_start, p_end, rate, offset
        self.t_end = (p_end - p_start) / rate

    def _height_derivatives(self, p: float) -> tuple[float, float, float]:
        e = -self.LAPSE * self.R / self.G
        scale = self.T0 / self.LAPSE
        ratio = p / self.P0
        h = height_from_pressure(p, self.P0, self.T0, self.LAPSE, 0.0, self.G, self.R)
        dh_dp = scale * e * ratio ** (e - 1.0) / self.P0
        d2h_dp2 = scale * e * (e - 1.0) * ratio ** (e - 2.0) / self.P0**2
        return h, dh_dp, d2h_dp2

    def reference(self, t: float) -> tuple[float, float, float]:
        if t >= self.t_end:
            h, _, _ = self._height_derivatives(self.p_end)
            return h + self.offset, 0.0, 0.0
        p = self.p_start + self.rate * max(t, 0.0)
        h, dh_dp, d2h_dp2 = self._height_derivatives(p)
        return h + self.offset, dh_dp * self.rate, d2h_dp2 * self.rate**2


class TableProfile(Profile):
    """Linear interpolation between user breakpoints; held before the first and after the last."""

    def __init__(self, table: np.ndarray, offset: float = 0.0):
        self._t = table[:, 0]
        self._h = table[:, 1] + offset

    def reference(self, t: float) -> tuple[float, float, float]:
        h = float(np.interp(t, self._t, self._h))
        i = int(np.searchsorted(self._t, t, side="right"))
        if i == 0 or i >= len(self._t):
            return h, 0.0, 0.0
        slope = (self._h[i] - self._h[i - 1]) / (self._t[i] - self._t[i - 1])
        return h, float(slope), 0.0


PROFILE_NAMES = (
    "yang2020", "hajiyev", "whang2008", "xu_hover15", "xu_hover35", "xu_multipoint",
    "fault_flight", "hold", "table",
)


def make_profile(name: str, offset: float = 0.0, table: str = "") -> Profile:
    """The profile called ``name`` (see the module docstring); ParameterError if unknown."""
    xu_accel, xu_speed = 0.5, 2.0
    if name == "yang2020":
        ramp = [(60.0, 0.2), (60.0, 0.0), (60.0, -0.2)]
        down = [(60.0, -0.2), (60.0, 0.0), (60.0, 0.2)]
        return AccelerationSegments(offset, ramp + [(60.0, 0.0)] + down)
    if name == "hajiyev":
        return PressureDescent(23000.0, 99850.0, 50.0, offset)
    if name == "whang2008":
        return AccelerationSegments(offset, [(40.0, 0.25), (360.0, 0.0), (40.0, -0.25)])
    if name == "xu_hover15":
        return trapezoid_moves(offset, [(5.0, offset + 15.0)], xu_accel, xu_speed)
    if name == "xu_hover35":
        return trapezoid_moves(offset, [(5.0, offset + 35.0)], xu_accel, xu_speed)
    if name == "xu_multipoint":
        moves = [(5.0, offset + 10.0), (335.0, offset + 22.0), (665.0, offset + 37.0)]
        return trapezoid_moves(offset, moves, xu_accel, xu_speed)
    if name == "fault_flight":
        moves = [(5.0, offset + 15.0), (60.0, offset + 120.0), (200.0, offset)]
        return trapezoid_moves(offset, moves, xu_accel, xu_speed)
    if name == "hold":
        return AccelerationSegments(offset, [])
    if name == "table":
        return TableProfile(parse_table(table, "profile_table"), offset)
    raise ParameterError("profile", name, f"unknown profile; choose one of {PROFILE_NAMES}")
