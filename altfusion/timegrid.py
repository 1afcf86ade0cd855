"""Exact time on a fixed step: integer tick counts, never accumulated floats.

A step size such as 0.01 s is taken as the decimal it was written as (1/100), so
``time(n)`` is the exact rational n·step rounded once to a float, and durations
(sample periods, offsets, latencies) are checked to be exact multiples of the step.
"""

import math
from fractions import Fraction

from altfusion.errors import ParameterError, StepError


def exact(value: float) -> Fraction:
    """The decimal a float was written as (0.01 -> 1/100), via its shortest repr."""
    return Fraction(repr(float(value)))


class TickClock:
    """Counts fixed steps of ``step_size`` from ``start_time``."""

    def __init__(self, step_size: float, start_time: float = 0.0, name: str = "step_size"):
        for label, value in ((name, step_size), ("start_time", start_time)):
            if not math.isfinite(value):
                raise ParameterError(label, value, "must be finite")
        step = exact(step_size)
        if step <= 0:
            raise ParameterError(name, step_size, "must be > 0")
        start = exact(start_time)
        self.step_size = float(step_size)
        self._den = math.lcm(step.denominator, start.denominator)
        self._step_num = step.numerator * (self._den // step.denominator)
        self._start_num = start.numerator * (self._den // start.denominator)
        self._step = step
        self._step_tolerance = 1e-9 * self.step_size
        self._time_tolerance = 1e-3 * self.step_size
        self.ticks = 0
        self.now = self.time(0)
        """The current time, s (:meth:`time` of the current tick, kept at each advance)."""

    def time(self, ticks: int | None = None) -> float:
        """Time at ``ticks`` steps after the start (default: the current tick), in s."""
        if ticks is None:
            return self.now
        return (self._start_num + ticks * self._step_num) / self._den

    def ticks_in(self, duration: float, name: str, allow_zero: bool = True) -> int:
        """``duration`` as a whole number of steps, or a ParameterError naming ``name``."""
        if not math.isfinite(duration):
            raise ParameterError(name, duration, "must be finite")
        quotient = exact(duration) / self._step
        if quotient.denominator != 1:
            raise ParameterError(
                name, duration, f"must be a multiple of the step size {self.step_size} s"
            )
        if quotient < 0:
            raise ParameterError(name, duration, "must be >= 0")
        if quotient == 0 and not allow_zero:
            raise ParameterError(name, duration, "must be > 0")
        return int(quotient)

    def advance(self, current_time: float, step_size: float) -> int:
        """Check a doStep(current_time, step_size) request and move one tick ahead."""
        if abs(step_size - self.step_size) > self._step_tolerance:
            raise StepError(
                f"communication step {step_size!r} s differs from parameter "
                f"step_size = {self.step_size!r} s"
            )
        expected = self.now
        if abs(current_time - expected) > self._time_tolerance:
            raise StepError(
                f"doStep at t = {current_time!r} s, but this component is at t = {expected!r} s"
            )
        self.ticks += 1
        self.now = (self._start_num + self.ticks * self._step_num) / self._den
        return self.ticks

