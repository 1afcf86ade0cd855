"""The barometric height formula of a constant-lapse-rate atmosphere and its inverse.

whang2008 eq. (1) (with the gas constant restored, see docs/papers.md), bao2017 eq. (2) and
hajiyev eq. (1) are all this formula with a different reference point: the reference
(H0, T0, P0) is sea level for an atmosphere model and the launch site for a barometer's
calibration. Γ (``lapse_rate``) is dT/dh, negative in the troposphere.
"""

import math

from altfusion.constants import G0, R_AIR


def temperature_at(h: float, T_ref: float, lapse_rate: float, h_ref: float = 0.0) -> float:
    """Air temperature at height h, K: T = T_ref + Γ (h - h_ref)."""
    return T_ref + lapse_rate * (h - h_ref)


def pressure_at(
    h: float,
    p_ref: float,
    T_ref: float,
    lapse_rate: float,
    h_ref: float = 0.0,
    gravity: float = G0,
    gas_constant: float = R_AIR,
) -> float:
    """Static pressure at height h, Pa, for a constant lapse rate (hydrostatic, ideal gas)."""
    return BarometricFormula(p_ref, T_ref, lapse_rate, h_ref, gravity, gas_constant).pressure(h)


def height_from_pressure(
    p: float,
    p_ref: float,
    T_ref: float,
    lapse_rate: float,
    h_ref: float = 0.0,
    gravity: float = G0,
    gas_constant: float = R_AIR,
) -> float:
    """Barometric height, m: h = h_ref + (T_ref/Γ)[(p/p_ref)^(-Γ R/g) - 1] (whang2008 eq. 1)."""
    return BarometricFormula(p_ref, T_ref, lapse_rate, h_ref, gravity, gas_constant).height(p)


class BarometricFormula:
    """The formula about one reference (H0, T0, P0), with the terms that depend on the
    reference alone computed once: kept by a barometer's calibration, which converts every
    sample about the same reference; :func:`pressure_at` and :func:`height_from_pressure`
    build one per call."""

    def __init__(
        self,
        p_ref: float,
        T_ref: float,
        lapse_rate: float,
        h_ref: float = 0.0,
        gravity: float = G0,
        gas_constant: float = R_AIR,
    ):
        self.p_ref, self.T_ref, self.lapse_rate, self.h_ref = p_ref, T_ref, lapse_rate, h_ref
        self._isothermal = abs(lapse_rate) < 1e-12
        if self._isothermal:
            self._minus_g, self._RT = -gravity, gas_constant * T_ref
            self._RT_over_g = gas_constant * T_ref / gravity
        else:
            self._pressure_exponent = -gravity / (lapse_rate * gas_constant)
            self._height_exponent = -lapse_rate * gas_constant / gravity
            self._T_over_lapse = T_ref / lapse_rate

    def pressure(self, h: float) -> float:
        """Static pressure at height h, Pa: p_ref·(T/T_ref)^(-g/(Γ R)), T = T_ref + Γ(h - h_ref)
        (p_ref·exp(-g (h - h_ref)/(R T_ref)) isothermal)."""
        if self._isothermal:
            return self.p_ref * math.exp(self._minus_g * (h - self.h_ref) / self._RT)
        T = self.T_ref + self.lapse_rate * (h - self.h_ref)
        return self.p_ref * (T / self.T_ref) ** self._pressure_exponent

    def height(self, p: float) -> float:
        """Barometric height at pressure p, m: h_ref + (T_ref/Γ)[(p/p_ref)^(-Γ R/g) - 1]
        (h_ref - (R T_ref/g) ln(p/p_ref) isothermal)."""
        if self._isothermal:
            return self.h_ref - self._RT_over_g * math.log(p / self.p_ref)
        return self.h_ref + self._T_over_lapse * ((p / self.p_ref) ** self._height_exponent - 1.0)
