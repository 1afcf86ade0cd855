"""Exact time on a fixed step: integer tick counts, never accumulated floats.

A step size such as 0.01 s is taken as the decimal it was written as (1/100), so
``time(n)`` is the exact rational n·step rounded once to a float, and durations
(sample periods, offsets, latencies) are checked to be exact multiples of the step.

A component ticks on this grid whatever its host's communication steps: a doStep over
(t, t + h] runs every tick whose time falls within it, a tick within ``TICK_TOLERANCE`` of a
tick's length after the step's end included (hosts add floats: 1000 steps of 0.01 s end at
9.999999999999831 s). A step shorter than a tick may run none (a host's 1e-13 s remainder
before its stop time), a step longer than a tick runs several.
"""

import math
from fractions import Fraction

from altfusion.errors import ParameterError, StepError

TICK_TOLERANCE = 1e-3
"""How close (in ticks) a step's end or start must come to a tick's time to count as it."""

MAX_TICKS_PER_STEP = 10**8
"""Most ticks one doStep may run: 11.6 days at a 0.01 s tick, about 3 to 60 minutes of
computing. A longer request (a host's 1e12 s step against a 0.01 s tick: 1e14 ticks, a hang
of years holding the interpreter) is refused, the state unchanged."""


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
        self._time_tolerance = TICK_TOLERANCE * self.step_size
        self._start_time = float(start_time)
        self.ticks = 0
        self.now = self.time(0)
        """The current time, s (:meth:`time` of the current tick, kept at each tick)."""
        self._on_grid = True
        self._host_end = self.now

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

    def due(self, current_time: float, step_size: float) -> int:
        """Check a doStep(current_time, step_size) request and return how many ticks it runs.

        The usual request, one tick from the current tick, takes the first test. Otherwise
        ``current_time`` must be where the previous request ended (within the tolerance) and
        ``step_size`` positive and finite; the request ends at ``current_time + step_size``
        and may run at most :data:`MAX_TICKS_PER_STEP` ticks. A refused request (StepError)
        changes nothing.
        """
        if (self._on_grid and abs(step_size - self.step_size) <= self._step_tolerance
                and abs(current_time - self.now) <= self._time_tolerance):
            return 1
        if not (step_size > 0.0 and math.isfinite(step_size)):
            raise StepError(f"communication step {step_size!r} s: must be positive and finite")
        if not abs(current_time - self.host_time) <= self._time_tolerance:   # NaN included
            raise StepError(f"doStep at t = {current_time!r} s, but this component is at "
                            f"t = {self.host_time!r} s")
        end = current_time + step_size
        last = max(self.ticks,
                   math.floor((end - self._start_time) / self.step_size + TICK_TOLERANCE))
        if last - self.ticks > MAX_TICKS_PER_STEP:
            raise StepError(f"communication step {step_size!r} s would run {last - self.ticks} "
                            f"ticks of {self.step_size!r} s, more than {MAX_TICKS_PER_STEP} in "
                            "one doStep: take shorter steps")
        # A step ending on a tick puts the host back on the grid (the fast path again).
        self._on_grid = abs(end - self.time(last)) <= self._time_tolerance
        self._host_end = end
        return last - self.ticks

    @property
    def host_time(self) -> float:
        """Where the host's last doStep ended, s (:attr:`now` while it steps on the grid)."""
        return self.now if self._on_grid else self._host_end

    def tick(self) -> None:
        """Move one tick ahead."""
        self.ticks += 1
        self.now = (self._start_num + self.ticks * self._step_num) / self._den
