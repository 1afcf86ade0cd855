"""A reading that repeats bit for bit: a stuck sensor, or an input left unconnected.

A sensor with noise does not deliver the same floating-point value many samples in a row:
two successive readings of noise σ quantized at q << σ coincide with a probability of about
q/(2σ√π) (a 5 mm laser read to the millimetre: 6 %; ten in a row: 10⁻¹²). A reading that
stays bit for bit the same is a frozen sensor, a replay stuck on one record, or, the common
case, one value of a stream whose input was left unconnected and reads its start value
while the stream's other values arrive (a GNSS receiver delivering heights but no vertical
speed: its ``gps_vz`` reads 0). Fused, such a reading is a perfect measurement of something
false: a speed of 0 pins the estimate's speed through a descent, and the height sources
that disagree look like the faulty ones (measured on hajiyev's 7 m/s descent, AltitudeEKF
told only the noises: RMS 1853 m, the baro and GNSS isolated).

A reading is *stuck* from its ``limit``-th repetition on (``limit`` + 1 identical samples)
until it changes; the estimator does not fuse it meanwhile. PX4 EKF2 has no such check on
values (it checks that samples arrive, by their timestamps); ArduPilot's EKF3 declares a
GPS stale on an unchanged time of week. Deviation: values, not timestamps, are compared,
since an unconnected value arrives with fresh stamps.

A receiver at rest repeats itself too: u-blox's static hold (its integration manuals) keeps
the position and sets the velocity to zero while it sees no movement, and PX4 SITL's GNSS
reports a vertical speed of exactly 0.0 on the ground (measured in the pyulog sample log:
gps_vz 0.0 for 9 s). It does so only while the vehicle does not move, which the baro shows:
its heights since a GNSS reading first repeated, judged for a climb or descent
(:class:`HeightSlope`, :data:`VEHICLE_MOVING`) in spans of :data:`MOTION_WINDOW`. A
repeated GNSS reading under no such climb is held (not fused: a repetition adds no
information), neither refused nor isolated; under a climb it is stuck, unless the climb
has moved the height less than the receiver's resolution allows since the reading first
repeated (:meth:`GnssCheck.hold`: a receiver read to 0.1 m holds a reading for seconds in
a slow climb; an input that never changed gets no allowance). A vertical speed
reading exactly 0 is also judged by the receiver's own heights over the run of zeros, in
the same spans and by the same rule (:meth:`HeightSlope.follow`,
:meth:`HeightSlope.moving`): a receiver that holds still does not climb. The rule's floor
keeps a receiver's own wander from reading as a climb: its height error drifts by a metre
or two over minutes (its Gauss-Markov part), which a noise measured from successive
samples, a few centimetres on a smooth receiver, would otherwise take for motion beyond any
gate.
"""

import math
from collections.abc import Callable, Iterable
from typing import Any, Final

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.floats import finite
from altfusion.estimators.restorable import Restorable

VEHICLE_MOVING: Final = 0.05
"""The slowest climb or descent (m/s) the baro's heights must show, beyond their scatter, for a
repeated GNSS height to be stuck rather than held by a receiver at rest: seven times the
fastest drift of a baro at rest (a strong weather front, ~3 hPa/h ≈ 25 m/h ≈ 0.007 m/s), so
that a receiver in static hold through a long wait on the ground is not taken for a stuck
one."""


MOTION_WINDOW: Final = 10.0
"""The span (s) of the baro's heights judged at once for motion while a GNSS reading
repeats: the run starts afresh after each span that shows none, so that a climb after a
long wait on the ground shows within about one span (a least-squares slope over a ten-minute
rest and τ s of climb at r is only ~3rτ²/600², 0.05 m/s after 77 s of a 1 m/s climb)."""


class StuckCheck(Restorable):
    """Whether one reading is stuck (:meth:`stuck`)."""

    __slots__ = ("limit", "last", "repeats", "since")

    def __init__(self, limit: int) -> None:
        self.limit = limit
        """Repetitions from which the reading is stuck (0: never)."""
        self.last: float | None = None
        """The last reading."""
        self.repeats = 0
        """How many samples in a row repeated it."""
        self.since = 0.0
        """Time of the first of them."""

    def stuck(self, value: float, now: float = 0.0) -> bool:
        """The next reading, taken at ``now``: True while it is stuck."""
        if value == self.last:
            self.repeats += 1
        else:
            self.last, self.repeats, self.since = value, 0, now
        return 0 < self.limit <= self.repeats

    def hold(self) -> float:
        """How far the height may move while a healthy sensor holds this reading, m: 0 (no
        allowance; a GNSS height's: :meth:`GnssCheck.hold`)."""
        return 0.0


class GnssCheck(StuckCheck):
    """A GNSS height's :class:`StuckCheck` that also learns the receiver's resolution: the
    smallest change between two successive readings (NMEA GGA reads the height to 0.1 m; a
    receiver read so holds its reading while the height moves less than a step)."""

    __slots__ = ("resolution",)

    def __init__(self, limit: int) -> None:
        super().__init__(limit)
        self.resolution = math.inf
        """The smallest change seen between successive readings (inf: none yet)."""

    def stuck(self, value: float, now: float = 0.0) -> bool:
        last = self.last
        if last is not None and value != last:
            self.resolution = min(self.resolution, abs(value - last))
        return super().stuck(value, now)

    def hold(self) -> float:
        """How far the height may move while a healthy receiver holds its reading, m: three
        of its steps (a step of motion, and its own wander over the hold: a smooth receiver
        read to 0.1 m, wandering 0.3 m over a minute, held a reading for 1.9 s of a
        0.1 m/s climb, 0.23 m); 0 before any change was seen (a reading that never changed,
        such as an unconnected input, gets no allowance)."""
        return 3.0 * self.resolution if finite(self.resolution) else 0.0


class HeightSlope(Restorable):
    """The least-squares slope of heights over a run of samples (times and heights taken
    from the run's first sample, so that the sums do not cancel)."""

    __slots__ = ("t0", "h0", "n", "sum_t", "sum_tt", "sum_h", "sum_th", "sum_hh")

    def __init__(self) -> None:
        self.restart()

    def restart(self) -> None:
        """Forget the run."""
        self.t0 = self.h0 = 0.0
        self.n = 0
        self.sum_t = self.sum_tt = self.sum_h = self.sum_th = self.sum_hh = 0.0

    def add(self, t: float, h: float) -> None:
        """The height ``h`` at time ``t``."""
        if self.n == 0:
            self.t0, self.h0 = t, h
        t -= self.t0
        h -= self.h0
        self.n += 1
        self.sum_t += t
        self.sum_tt += t * t
        self.sum_h += h
        self.sum_th += t * h
        self.sum_hh += h * h

    def _fit(self) -> tuple[float, float, float]:
        """(b, Sₜₜ, Sₜₕ) of the run: the slope b = Sₜₕ/Sₜₜ, with Sₜₜ = Σt² - (Σt)²/n and
        Sₜₕ = Σth - ΣtΣh/n (b is nan with fewer than two instants: Sₜₜ is 0)."""
        n = self.n
        if n < 2:
            return math.nan, 0.0, 0.0
        s_tt = self.sum_tt - self.sum_t * self.sum_t / n
        s_th = self.sum_th - self.sum_t * self.sum_h / n
        return (s_th / s_tt if s_tt > 0.0 else math.nan), s_tt, s_th

    def moved(self, span: float) -> float:
        """How far the heights' slope carries them over ``span`` s, m (0 with fewer than two
        instants)."""
        slope = self._fit()[0]
        return 0.0 if math.isnan(slope) else abs(slope) * span

    def moving(self, sigma: float, gate: float) -> bool:
        """The heights climb or descend: their slope b is faster than :data:`VEHICLE_MOVING`
        and beyond ``gate`` standard deviations of 0, Var b = s²/Sₜₜ with s² the larger of
        the heights' noise ``sigma``² and their scatter about the line (RSS/(n - 2), from
        three samples: a noise stated too small does not make a rest look like a climb).
        False with fewer than two instants."""
        slope, s_tt, s_th = self._fit()
        if not abs(slope) > VEHICLE_MOVING:                             # False for nan
            return False
        variance = sigma * sigma
        n = self.n
        if n > 2:
            rss = self.sum_hh - self.sum_h * self.sum_h / n - slope * s_th
            variance = max(variance, rss / (n - 2))
        return slope * slope * s_tt > gate * gate * variance

    def follow(self, t: float, h: float, sigma: Callable[[], float], gate: float) -> None:
        """The height ``h`` at time ``t`` joins the run, which starts afresh once a span of
        :data:`MOTION_WINDOW` showed no motion (:meth:`moving`, the heights' noise
        ``sigma()`` asked only then): a climb after a long rest is not averaged away."""
        if self.n and t - self.t0 >= MOTION_WINDOW and not self.moving(sigma(), gate):
            self.restart()
        self.add(t, h)


class StuckReadings(Restorable):
    """The fault layer's stuck check of an estimator's readings
    (:meth:`~altfusion.estimators.intake.SampleIntake.due_samples`): a :class:`StuckCheck` per
    source, the GNSS receiver's heights while its vertical speed reads exactly 0, the baro's
    heights while a GNSS reading repeats, and the sources found stuck in the last step."""

    __slots__ = ("checks", "gnss", "gnss_speed", "gnss_still", "baro_run", "found")

    def __init__(self, sources: Iterable[str], limit: int) -> None:
        self.checks = {source: GnssCheck(limit) if source == "gps" else StuckCheck(limit)
                       for source in sources}
        self.gnss = self.checks.get("gps")
        """The GNSS height's check (None without a GNSS)."""
        self.gnss_speed = self.checks.get("gps_vz")
        """The GNSS vertical speed's check (None without one)."""
        self.gnss_still = HeightSlope()
        """The GNSS receiver's heights while its vertical speed reads exactly 0: an
        unconnected speed input reads 0 while they climb or descend (10 m/s over ten 1 Hz
        samples of 13 m noise is 7 standard deviations of the slope)."""
        self.baro_run = HeightSlope()
        """The baro's heights since a GNSS reading first repeated (:data:`VEHICLE_MOVING`)."""
        self.found: tuple[str, ...] = ()
        """The sources whose reading was stuck in the last step."""

    def baro_followed(self) -> bool:
        """True while a GNSS reading (its height, or its vertical speed) repeats: the baro's
        heights are then followed in :attr:`baro_run`; False otherwise, the run forgotten."""
        gnss, speed = self.gnss, self.gnss_speed
        if gnss is not None and (gnss.repeats or (speed is not None and speed.repeats)):
            return True
        if self.baro_run.n:
            self.baro_run.restart()
        return False

    def find(self, samples: dict[Any, dict[str, float]], now: float,
             ) -> list[tuple[Any, str, str]]:
        """The stuck readings of a step's ``samples`` (by stream: each stream's ``checked``
        values judged by their source's check, taken at ``now``): (stream, input, source)
        of each."""
        checks = self.checks
        found = []
        for stream, sample in samples.items():
            for name, source in stream.checked:
                if checks[source].stuck(sample[name], now):
                    found.append((stream, name, source))
        return found


def refuse_stuck(check: StuckCheck, source: AidSource, reading: float,
                 note: Callable[[str], None], at_rest: Callable[[], bool] | None = None) -> bool:
    """What becomes of ``reading`` of ``source``, found stuck by ``check`` (not to be fused):
    a GNSS reading repeated while ``at_rest`` (the receiver may hold still: the baro shows
    no climb; a speed of 0, the receiver's heights show none: :class:`HeightSlope`) is
    only held; any
    other is refused (counted) and, when it sticks, ``source`` is isolated (a failed sensor,
    until a changed reading passes its gate) and ``note`` told. Its first ``limit``
    repetitions were fused before they could be told from readings: its bias window and
    last fusion are forgotten then (it vouches for no prediction in the bias test). True if
    it is found stuck now (its run began at ``check.since``)."""
    name = source.name
    if at_rest is not None and not source.isolated and at_rest():
        if check.repeats == check.limit:
            note(f"{name}: the same reading {reading:.6g} {check.limit + 1} times in a row "
                 f"while the vehicle does not climb past the receiver's resolution: the "
                 f"receiver holds still (static hold, or a coarse reading); not fused while "
                 f"it repeats, not a fault")
        return False
    found = check.repeats == check.limit or not source.isolated
    if found:
        source.window.clear()
        source.last_fused = -math.inf
        source.isolate()
        note(f"{name}: the same reading {reading:.6g} {check.repeats + 1} times in a row: "
             f"stuck, isolated until it changes and passes its gate")
    source.refused()
    return found
