"""The motion model's process noise adapted from the innovations, bounded: raised while the
sources find the prediction off (a manoeuvre the model cannot follow), back to the stated
noise when they agree with it again.

A filter without an accelerometer predicts with a motion model whose noise (AltitudeEKF's
``accel_psd`` and ``jerk_psd``) says how fast the vehicle's speed and acceleration may
change. Told too small a noise for the flight, the model lags every change of speed while
its variances stay small: every source then disagrees with the prediction, on the same
side, for as long as the manoeuvre lasts (the gates may even reject the samples that show
it). Told too large a noise, the estimate is noisier than it needs to be but consistent.
So the noise can be raised from the innovations, never lowered below what was stated.

Evidence: each judge (the height sources and the GNSS vertical speed) keeps the fading
mean ȳ of its innovations y, each clipped to its gate (one wild sample moves the mean by at
most one gate),

    ȳ ← ȳ + w·(y - ȳ),   V ← (1 - w)²·V + w²·max(S, D/2),   D ← D + w·((y - y_prev)² - D)
    w = min(1 - exp(-Δt/MEMORY), MAX_WEIGHT)

Δt the time since the judge's previous sample, S the innovation's variance: V is the
variance ȳ would have if the prediction were right (white innovations: Mehra's test of
optimality), so that ȳ²/V measures the disagreement over the last :data:`MEMORY` seconds,
or the last 1/:data:`MAX_WEIGHT` samples of a slow source, whatever its rate. The spread of
one sample is the stated S or, if larger, the one the successive differences D show (von
Neumann's mean square successive difference: 2σ² for white noise, blind to a slowly
varying offset): a source noisier than stated (a baro told 2 m that has 9 m) has a mean
that wanders by its true spread, which the stated S would read as a disagreement.

Every :data:`PERIOD` the judges gated within :data:`MEMORY` (isolated ones left out) judge
the prediction (:func:`~altfusion.estimators.prediction_judges.inconsistent`): it is off
when two of them (the one judge there is, alone) disagree beyond :data:`SIGMAS` standard
deviations of ȳ, the height sources on one side and the speed, if it counts, on theirs (a
lag moves the height and the speed the same way), none pinning the height tighter; once
off, while they stay beyond :data:`HOLD_SIGMAS`. A manoeuvre moves every source's
innovations alike; a bad sensor moves its own. A noisier one's mean stays within its
spread; a drifting or offset one disagrees with the others (on the other side of the
prediction, or pinned by them); a speed sensor that is off (a GNSS whose vertical speed
input is left unconnected and reads 0) disagrees with the heights' side. None of them
raises the motion noise alone.

Response (bounded innovation-based adaptation, after Mehra, and the adjustable process
noise level of Bar-Shalom et al.): while the prediction is found off the noise is
multiplied by :data:`GROWTH`, at most every :data:`ESCALATION` and up to
:attr:`MotionNoise.maximum` (the estimator's physical bound, a vehicle's largest
acceleration: :func:`maximum_scale`); otherwise it returns to the stated noise with the
time constant :data:`DECAY`. The estimator multiplies its motion-model noise by
:attr:`MotionNoise.scale` (1 exactly while never raised: its outputs are those of the
stated noise, bit for bit); ``status`` carries the bit ``PROCESS_NOISE_ADAPTED`` while the
scale is above :data:`ADAPTED`.

Anchors and deviations:

* Mehra (1970, 1972): the innovations of an optimal filter are white; their mean and
  correlation identify a wrong noise. Here only a mean beyond its spread, shared by the
  sources, is used, and only to raise the process noise: a measurement noise stated too
  small moves one source's innovations, not all, and is that source's check.
* Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and
  Navigation* (2001), Chapter 11 (adjustable process noise level): the noise level raised
  while a fading-memory average of the innovations exceeds a threshold, lowered when it
  falls back. Their statistic is one sensor's normalized innovation squared; here it is
  the innovation mean of several sources, so that a sensor noisier than stated (which
  raises its squared innovations, not their mean) does not raise the motion noise.
* Sage-Husa's estimator (hajiyev's adaptive factor, eqs. 26-31, is its one-sample form)
  sets the noise from the innovations' spread at every step; the escalation here instead
  follows the evidence in steps, each judged on innovations after the one before, as the
  accelerometer check (:mod:`~altfusion.estimators.accelerometer_check`) inflates an
  accelerometer's noise. It settles where the lag is within about :data:`HOLD_SIGMAS` of
  the evidence's spread.
* Interacting multiple models (a bank of filters over noise levels weighted by their
  likelihoods) would follow a manoeuvre's onset within a sample or two, but cost one filter
  per level at every step; one scale costs a few multiplications per sample.
"""

import math
from typing import Final

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.prediction_judges import MIN_SOURCES, Judgement, inconsistent, judge
from altfusion.estimators.restorable import Restorable

PERIOD: Final = 0.1
"""The prediction is judged at most this often, s (at every estimator step when that is
longer): the evidence moves over seconds (the accelerometer check's period)."""

MEMORY: Final = 2.0
"""Time constant of each judge's fading innovation mean, s (a hundred samples of a 50 Hz
baro, ten of a 5 Hz one: a manoeuvre of a few seconds is seen), and how recent its last
sample must be to judge (a 1 Hz GNSS judges between its samples)."""

SIGMAS: Final = 4.0
"""A judge's fading mean beyond this many of its standard deviations disagrees with the
prediction: a right prediction's lies beyond it once in 16,000 independent windows (a 1 Hz
GNSS's ten-second windows: once in 44 hours), where the accelerometer check's 3 would be
once in 370 (an hour). The second judge that a source off by itself (a baro whose error
steps with the weather, which alone raises no motion noise) needs must not be found by
chance; a manoeuvre's lag grows beyond either within seconds."""

HOLD_SIGMAS: Final = 2.0
"""Once found off, the prediction stays off while the judges stay beyond this many standard
deviations (hysteresis, as the bias test's re-admission at 2): the noise is raised until the
lag is within the evidence's spread, not just below the threshold that found it."""

MAX_WEIGHT: Final = 0.1
"""Largest weight of one sample in the evidence: at least ten samples make it (ten seconds
of a 1 Hz GNSS; a faster source's :data:`MEMORY` holds more), so that the spread of its
successive differences is known to about a third, and one sample that is off by itself
(an outlier within the gate) does not make a disagreement."""

GROWTH: Final = 4.0
"""Factor of each raise of the noise (the accelerometer check's): from the default
``accel_psd`` of 0.01 m²/s³ to 1 g's bound (96 m²/s³) in 7 raises."""

ESCALATION: Final = 2.0
"""Least time between two raises, s: :data:`MEMORY`, so that a fast source's evidence is
judged on innovations taken after the previous raise (a slow source's, over ten samples,
mostly before: the hysteresis of :data:`HOLD_SIGMAS` then stops the raises once the lag is
within the spread)."""

DECAY: Final = 60.0
"""Time constant of the return to the stated noise, s: a manoeuvre's noise is kept for a
minute after the sources agree again (a flight's manoeuvres come in phases of tens of
seconds: a climb's start and end), and is gone within minutes of steady flight."""

ADAPTED: Final = 2.0
"""The noise is reported adapted (``status`` bit ``PROCESS_NOISE_ADAPTED``) while it is
more than this factor above the stated (the accelerometer check's ``BAD``)."""

REFERENCE_PERIOD: Final = 1.0
"""s: the white-acceleration noise of PSD q changes the speed by about √(q·T) over a time T
(Bar-Shalom et al., Chapter 6: their rule for choosing q): a vehicle whose acceleration stays below
a_max changes its speed by at most a_max·T, so q <= a_max²·T, taken over the 1 s of a slow
GNSS's sample period (at faster samples the bound allows more than the rule: cautious)."""


def maximum_scale(stated_psd: float, max_acceleration: float) -> float:
    """The largest factor on a stated white-acceleration PSD (m²/s³): the PSD at most
    ``max_acceleration``²·:data:`REFERENCE_PERIOD` (never below the stated, factor 1)."""
    return max(1.0, max_acceleration**2 * REFERENCE_PERIOD / stated_psd)


class _Evidence(Restorable):
    """One judge's fading innovation mean, the variance that mean would have if the
    prediction were right, and the fading mean square of its successive differences."""

    __slots__ = ("mean", "variance", "differences", "last", "time", "seen")

    def __init__(self) -> None:
        self.mean = self.variance = 0.0
        self.differences = math.nan
        """Fading mean of (y - y_previous)² (nan: no sample yet)."""
        self.last = 0.0
        """The last innovation."""
        self.time = -math.inf
        """Time of its last sample (-inf: none yet)."""
        self.seen = -math.inf
        """The judge's ``last_gated`` of that sample."""

    def add(self, now: float, y: float, S: float) -> None:
        w = min(1.0 - math.exp(-min(now - self.time, MEMORY) / MEMORY), MAX_WEIGHT)
        if math.isnan(self.differences):
            self.differences = 2.0 * S
        else:
            self.differences += w * ((y - self.last) ** 2 - self.differences)
        self.mean += w * (y - self.mean)
        self.variance = (1.0 - w) ** 2 * self.variance + w * w * max(S, 0.5 * self.differences)
        self.last, self.time = y, now


class MotionNoise(Restorable):
    """The factor on an estimator's motion-model noise (:attr:`scale`), from the innovations
    of its ``judges``."""

    __slots__ = ("judges", "maximum", "gate", "scale", "adapted", "raising", "_evidence", "_last",
                 "_escalated", "_decay", "_decay_dt")

    def __init__(self, judges: tuple[AidSource, ...], maximum: float, gate: float) -> None:
        self.judges = judges
        """The aid sources that judge the prediction: the height sources and the GNSS
        vertical speed."""
        self.maximum = maximum
        """Largest :attr:`scale` (:func:`maximum_scale`)."""
        self.gate = gate
        """The estimator's innovation gate in standard deviations (0: none): innovations
        enter the evidence clipped to it."""
        self.scale = 1.0
        """The factor on the stated motion-model noise, in [1, :attr:`maximum`]."""
        self.adapted = False
        """:attr:`scale` above :data:`ADAPTED`."""
        self.raising = False
        """The last check found the prediction off."""
        self._evidence = tuple(_Evidence() for _ in judges)
        self._last = self._escalated = -math.inf
        self._decay = self._decay_dt = 0.0

    def step(self, now: float) -> None:
        """At the end of an estimator step: fold the judges' new innovations into their
        evidence; every :data:`PERIOD`, raise the scale or let it decay."""
        for source, evidence in zip(self.judges, self._evidence, strict=True):
            if source.last_gated > evidence.seen:
                evidence.seen = source.last_gated
                S = max(source.variance, 0.0)
                y = source.innovation
                if self.gate > 0.0:
                    half_width = self.gate * math.sqrt(S)
                    y = min(max(y, -half_width), half_width)
                evidence.add(now, y, S)
        elapsed = now - self._last
        if elapsed < PERIOD * (1.0 - 1e-9):
            return
        self._last = now
        judgements = self._judgements(now)
        present = {judge(name) for name, *_ in judgements}
        sigmas = HOLD_SIGMAS if self.raising else SIGMAS
        self.raising = bool(present) and inconsistent(
            judgements, min(MIN_SOURCES, len(present)), True, sigmas)
        if self.raising:
            if now - self._escalated >= ESCALATION:
                self.scale, self._escalated = min(GROWTH * self.scale, self.maximum), now
        elif self.scale != 1.0:
            elapsed = min(elapsed, DECAY)
            if elapsed != self._decay_dt:
                self._decay, self._decay_dt = math.exp(-elapsed / DECAY), elapsed
            self.scale = 1.0 + self._decay * (self.scale - 1.0)
            if self.scale < 1.0 + 1e-6:
                self.scale = 1.0
        self.adapted = self.scale > ADAPTED

    def _judgements(self, now: float) -> list[Judgement]:
        """The evidence of the judges gated within :data:`MEMORY`, isolated ones left out."""
        return [(source.name, source.height, evidence.mean, evidence.variance)
                for source, evidence in zip(self.judges, self._evidence, strict=True)
                if now - evidence.time <= MEMORY and not source.isolated]
