"""The sampling mechanism shared by every sensor: schedule, latency, counter, time stamp.

The multi-rate convention of ``docs/signals.md`` (FMI 2.0 has no clocks):

* samples are taken at t = sample_offset + k·sample_period (k = 0, 1, ...) strictly after the
  start time, computed in integer ticks of the component's step (its tick), so over 3600 s
  from t = 0 a 0.2 s period gives exactly 18000 samples whatever the host's communication
  steps (the period, the offset and the latency are whole multiples of the tick); when several
  samples fall within one communication step the outputs hold the last and the count rises by
  the number taken;
* a sample is delivered exactly ``latency`` after it was taken: its values, its time stamp
  ``<prefix>_time`` (the sampling instant, exact) and the increment of ``<prefix>_count``
  appear together;
* between deliveries every output holds. Before the first delivery the count is 0, the time
  stamp is the start time and the measurement outputs hold each sensor's documented initial
  value (never NaN); consumers ignore count 0;
* a sample may carry no new measurement (``Sample.new`` false: a GNSS outage, a radio
  altimeter beyond its range); then only the values it carries change (validity flags) and
  the count and time stamp hold.

Randomness: each sensor draws from its own ``numpy`` ``SeedSequence`` built from its ``seed``
parameter and its prefix (so two different sensors with equal seeds are still independent),
spawned into one ``Generator`` per error source: enabling one error source never changes
another's realization, and the same seed gives identical outputs. A stream drawn only through
``standard_normal()`` (``normal_streams``) is drawn :class:`NormalDraws` at a time: the same
numbers, at a fraction of numpy's cost per call.
"""

import math
import zlib
from abc import abstractmethod
from collections import deque
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from altfusion.component import Component
from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.timegrid import TickClock, exact


@dataclass(frozen=True)
class SamplingParams:
    """Parameters common to every sensor; each sensor's Params extends this dataclass."""

    seed: int = param(0, None, "Seed of this component's random streams", min=0)
    sample_period: float = param(0.01, "s", "Time between samples", positive=True)
    sample_offset: float = param(
        0.0, "s", "Samples are taken at t = sample_offset + k*sample_period, after the start",
        min=0.0,
    )
    latency: float = param(
        0.0, "s", "Delay between taking a sample and delivering it (a multiple of step_size)",
        min=0.0,
    )


class Sample(NamedTuple):
    """What a sensor measured at one sampling instant (a named tuple: one per sample).

    ``values`` maps output attribute names to the values to deliver; ``new`` tells whether the
    sample is a new measurement (the count increments and the time stamp moves) or only a
    change of status (e.g. ``gps_fix`` false), with every other output holding.
    """

    values: dict[str, Any]
    new: bool = True


NORMAL_BATCH = 256
"""Standard normal numbers :class:`NormalDraws` takes from its generator at once."""


class NormalDraws:
    """The standard normal numbers of one ``Generator``, taken ``batch`` at a time.

    :meth:`draw` returns the same numbers in the same order as one ``standard_normal()`` call
    per number (numpy fills an array with the same algorithm, number after number), for about
    a tenth of the instructions of a numpy call. The generator runs up to a batch ahead, so
    nothing else may draw from it.
    """

    def __init__(self, rng: np.random.Generator, batch: int = NORMAL_BATCH):
        self._rng = rng
        self._batch = batch
        self._left: list[float] = []
        """The batch's numbers not yet drawn, the next one last."""

    def draw(self) -> float:
        """The next standard normal number."""
        left = self._left
        if not left:
            left = self._left = self._rng.standard_normal(self._batch).tolist()
            left.reverse()
        return left.pop()


def first_sample_tick(clock: TickClock, offset: float, period_ticks: int) -> int:
    """The first tick n >= 1 at which start + n·step = offset + k·period for some k >= 0."""
    start = exact(clock.time(0))
    relative = (exact(offset) - start) / exact(clock.step_size)
    if relative.denominator != 1:
        raise ParameterError(
            "sample_offset", offset,
            f"minus the start time {clock.time(0)!r} s must be a multiple of the step size "
            f"{clock.step_size!r} s",
        )
    tick = int(relative)
    if tick < 1:
        tick += math.ceil((1 - tick) / period_ticks) * period_ticks
    return tick


def require_finite(name: str, value: float) -> float:
    """``value`` as a float, or a ValueError naming the input if it is NaN or infinite."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"input {name} = {value!r} is not finite")
    return value


class SampledSensor(Component):
    """Base of every sensor: the sampling schedule, the latency queue, count and time stamp.

    A subclass sets ``Params`` (extending :class:`SamplingParams`), ``prefix`` (the signal
    prefix, e.g. ``"baro"``) and ``streams`` (one name per independent error source), and
    implements :meth:`reset_sensor` (initial outputs and error states) and :meth:`measure`
    (one sample at the current time, from the current inputs). It may extend
    :meth:`configure_sensor` to check its own parameters.
    """

    prefix: ClassVar[str]
    streams: ClassVar[tuple[str, ...]] = ()
    normal_streams: ClassVar[tuple[str, ...]] = ()
    """The streams drawn only through ``standard_normal()``: through ``self.normal[name]``
    (:class:`NormalDraws`), never ``self.rng[name]``."""

    # ----------------------------------------------------------------- hooks
    def configure_sensor(self, clock: TickClock) -> None:
        """Check the sensor's own parameters against the step; default: nothing to check."""
        return None

    @abstractmethod
    def reset_sensor(self) -> None:
        """Set the initial measurement outputs and error states (``self.rng`` is ready)."""

    @abstractmethod
    def measure(self) -> Sample:
        """Take one sample now (``self.time`` is the sampling instant)."""

    # ----------------------------------------------------------------- Component
    @classmethod
    def natural_step(cls, params: SamplingParams) -> float:
        """The greatest common divisor of the sample period, offset and latency."""
        durations = [exact(d) for d in (params.sample_period, params.sample_offset,
                                        params.latency) if d > 0]
        denominator = math.lcm(*(d.denominator for d in durations))
        numerator = math.gcd(*(int(d * denominator) for d in durations))
        return numerator / denominator

    def configure(self, clock: TickClock) -> None:
        p = self.params
        self._period_ticks = clock.ticks_in(p.sample_period, "sample_period", allow_zero=False)
        self._latency_ticks = clock.ticks_in(p.latency, "latency")
        self._first_tick = first_sample_tick(clock, p.sample_offset, self._period_ticks)
        self._count_name, self._time_name = f"{self.prefix}_count", f"{self.prefix}_time"
        self.configure_sensor(clock)

    def reset(self) -> None:
        entropy = [self.params.seed, zlib.crc32(self.prefix.encode())]
        children = np.random.SeedSequence(entropy).spawn(len(self.streams))
        self.rng = {name: np.random.default_rng(child)
                    for name, child in zip(self.streams, children, strict=True)}
        self.normal = {name: NormalDraws(self.rng[name]) for name in self.normal_streams}
        self._queue: deque[tuple[int, float, Sample]] = deque()
        setattr(self, f"{self.prefix}_count", 0)
        setattr(self, f"{self.prefix}_time", self.time)
        self.reset_sensor()

    def update(self) -> None:
        clock = self.clock
        tick = clock.ticks
        queue = self._queue
        if tick >= self._first_tick and (tick - self._first_tick) % self._period_ticks == 0:
            queue.append((tick + self._latency_ticks, clock.now, self.measure()))
        while queue and queue[0][0] <= tick:
            _, stamp, sample = queue.popleft()
            self._deliver(stamp, sample)

    def _deliver(self, stamp: float, sample: Sample) -> None:
        for name, value in sample.values.items():
            setattr(self, name, value)
        if sample.new:
            setattr(self, self._count_name, getattr(self, self._count_name) + 1)
            setattr(self, self._time_name, stamp)

    # ----------------------------------------------------------------- helpers
    def ticks_since(self, tick: int) -> float:
        """Time from ``tick`` to now, s, from the integer tick difference."""
        return (self.clock.ticks - tick) * self.clock.step_size
