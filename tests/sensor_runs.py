"""Helpers for the sensor unit tests: step a core sensor and collect its outputs.

Confidence intervals used throughout (99.9 %, z = 3.29, normal approximations):

* mean of N independent samples of σ:         |mean - μ| < z·σ/√N
* sample standard deviation of N normal ones: |s - σ|    < z·σ/√(2N)
"""

import math
from collections.abc import Callable
from typing import Any

import numpy as np

Z999 = 3.29
"""Two-sided 99.9 % quantile of the standard normal distribution."""


def mean_tolerance(sigma: float, n: int) -> float:
    """99.9 % half-width of the mean of n independent samples of standard deviation sigma."""
    return Z999 * sigma / math.sqrt(n)


def std_tolerance(sigma: float, n: int) -> float:
    """99.9 % half-width of the sample standard deviation of n normal samples."""
    return Z999 * sigma / math.sqrt(2 * n)


def run(sensor: Any, steps: int, outputs: tuple[str, ...],
        inputs: Callable[[float], dict[str, float]] | None = None) -> dict[str, np.ndarray]:
    """Step ``sensor`` ``steps`` times; before each step set the inputs to their value at the
    end of the step (as the runner does for feedthrough inputs); record ``outputs`` after
    each step. ``time`` holds the end time of each step."""
    rows: dict[str, list[Any]] = {name: [] for name in ("time", *outputs)}
    for _ in range(steps):
        if inputs is not None:
            for name, value in inputs(sensor.clock.time(sensor.clock.ticks + 1)).items():
                setattr(sensor, name, value)
        sensor.do_step(sensor.time, sensor.dt)
        rows["time"].append(sensor.time)
        for name in outputs:
            rows[name].append(getattr(sensor, name))
    return {name: np.array(values) for name, values in rows.items()}
