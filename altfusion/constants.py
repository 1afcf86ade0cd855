"""Physical constants (SI units) used throughout the core."""

G0 = 9.80665
"""Standard gravity, m/s²."""

R_AIR = 287.05287
"""Specific gas constant of dry air, J/(kg·K) (ISA value)."""

ISA_P0 = 101325.0
"""ISA sea-level pressure, Pa."""

ISA_T0 = 288.15
"""ISA sea-level temperature, K."""

ISA_LAPSE_RATE = -0.0065
"""ISA tropospheric lapse rate dT/dh, K/m."""

ISA_TROPOPAUSE_H = 11000.0
"""ISA tropopause geopotential height, m."""
