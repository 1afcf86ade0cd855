"""The first-order Gauss-Markov process, by its exact discretization: the wind gust of
:mod:`altfusion.physics.atmosphere` and the GNSS receiver's slowly wandering height error
(:mod:`altfusion.sensors.gnss`)."""

import math


def gauss_markov_step(value: float, phi: float, std: float, draw: float) -> float:
    """The process of stationary σ ``std`` one interval Δt after ``value``:
    e ← φe + σ√(1-φ²)·n, with φ = exp(-Δt/τ) and n the standard normal ``draw``."""
    return phi * value + std * math.sqrt(1.0 - phi * phi) * draw
