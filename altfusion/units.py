"""SI units of the signal contract as exponents of the SI base units.

Written into every modelDescription.xml (FMI UnitDefinitions) and SSP file (ssd:Units).
"""

BASE_UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "s": {"s": 1},
    "m": {"m": 1},
    "m2": {"m": 2},
    "m/s": {"m": 1, "s": -1},
    "m2/s": {"m": 2, "s": -1},
    "m2/s2": {"m": 2, "s": -2},
    "m/s2": {"m": 1, "s": -2},
    "m2/s4": {"m": 2, "s": -4},
    "m/s3": {"m": 1, "s": -3},
    "m.s": {"m": 1, "s": 1},
    "1/s": {"s": -1},
    "1/s2": {"s": -2},
    "1/s3": {"s": -3},
    "kg": {"kg": 1},
    "kg/m": {"kg": 1, "m": -1},
    "kg/m3": {"kg": 1, "m": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "Pa/s": {"kg": 1, "m": -1, "s": -3},
    "K": {"K": 1},
    "K2": {"K": 2},
    "K/s": {"K": 1, "s": -1},
    "K/m": {"K": 1, "m": -1},
    "J/(kg.K)": {"m": 2, "s": -2, "K": -1},
}

