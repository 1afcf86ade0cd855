"""The vertical accelerometer checked against every height source (PX4 EKF2's
``bad_acc_vertical``), with its noise inflated while it is found bad.

An estimator that integrates an accelerometer (AltitudeEKF, as its input) trusts it for the
motion between height samples. An accelerometer much noisier than its stated noise
(vibration, a loose mount, clipping) drives the prediction off while the filter's variances
stay small: every height source then disagrees with the prediction at once, each far beyond
its own innovation standard deviation, and on the same side (the prediction is off, not the
sources). One height source alone could be off itself; every one at once, together with the
GNSS speed where there is one, points at the accelerometer.

Two kinds of evidence, both bounded innovation-based adaptation after Mehra (the noise settles
where the evidence puts it, never below the stated noise):

* **the accelerometer's own scatter**, for any estimator that reads one: its noise measured
  from the spread of the second differences of its last :data:`SCATTER_SAMPLES` samples
  (a robust estimate: the median absolute second difference, which a manoeuvre's steps
  and a steady jerk leave alone; see :func:`scatter_noise`). A noise more
  than :data:`MARGIN` times the stated is used instead of it. This finds white noise (vibration, a
  loose mount) within a second, before the prediction has drifted;
* **the height sources' disagreement with the prediction**, only for an accelerometer that
  is the prediction's input (AltitudeEKF), which finds an error the scatter cannot see (one
  that is not white: a wandering error, clipping). Where the accelerometer is a measurement
  of an acceleration state driven by a white jerk (YangFusionKF), inflating it leaves a
  motion model that lags every acceleration step, and the lag reads as a bad accelerometer:
  there only the scatter counts.

Check, every :data:`PERIOD` (PX4 EKF2 ``checkVerticalAccelerationHealth``, at every IMU
sample): the prediction is *inconsistent*
(:func:`~altfusion.estimators.prediction_judges.inconsistent`) when, of the aid sources
that judge it (height sources and the GNSS vertical speed; isolated ones left out) gated
within :data:`WINDOW`, at least two independent ones disagree with it by more than
:data:`~altfusion.estimators.prediction_judges.SIGMAS` standard deviations, the height
sources among them on one side, and none of the others pins it tighter than those
disagreements (a source that precise and consistent says the prediction is right). A height
source's disagreement is the mean of its innovations over its bias window (over seconds,
many coarse samples see a drift no single one can), the GNSS speed's its last innovation.
The accelerometer's noise is too small for what the prediction shows when more than
:data:`FRACTION` of the checks of the last :data:`WINDOW` (an exponential average of that
time constant) were inconsistent.

Then its noise is inflated, by :data:`GROWTH` at most every :data:`ESCALATION` while the
checks stay inconsistent, up to the accelerometer's clipping level (an accelerometer noisier
than that measures nothing), and returns to the stated noise with the time constant
:data:`DECAY` (the noise settles just above the level the innovations show). The estimator
reads :attr:`AccelerometerCheck.noise` (the larger of the two kinds' noises) where it used
its stated noise; ``status`` carries the bit ``BAD_ACC_VERTICAL`` (PX4's
``bad_acc_vertical``) while the noise is more than :data:`BAD` times the stated.

Deviations from PX4: PX4 requires clipping evidence unless GNSS speed and height are both
available, holds the flag for 10 s (``BADACC_PROBATION``) and inflates the noise to one
fixed level (``BADACC_BIAS_PNOISE``, 4.9 m/s²); here any two independent judges suffice (two
height sources are independent of each other) and the inflation follows the evidence (a
40x noisier accelerometer needs 2 m/s², a 10 m/s² one twice PX4's level). PX4 measures the
IMU's vibration (``accel_vibration_metric``) but does not use it in the filter; here the
scatter sets the noise.

An accelerometer whose noise was *not stated* (the estimator starts from a small UAV's
typical value) is measured both ways: once :data:`SCATTER_SAMPLES` are in, its scatter is the
noise the estimator uses (within
:data:`~altfusion.estimators.noise_check.UNSTATED_RANGE` below the starting value, up to the
clipping level), and the height sources' evidence inflates it from there. Before, from
:data:`EARLY_SAMPLES` on, a scatter above the starting value already raises it: a slowly
logged accelerometer would otherwise be trusted at the typical noise for as many seconds as
it takes to log 100 samples.
"""

import math
import statistics
from collections import deque
from collections.abc import Iterator
from typing import Final

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.fault_detection import BIAS_MIN_SAMPLES
from altfusion.estimators.noise_check import UNSTATED_RANGE
from altfusion.estimators.prediction_judges import Judgement, inconsistent
from altfusion.estimators.restorable import Restorable
from altfusion.estimators.streams import ACC_CLIP

PERIOD: Final = 0.1
"""The check runs at most this often, s (at every estimator step when that is longer): its
evidence moves over seconds, and a check at every 10 ms step cost 10 µs, a fifth of an
estimator's step."""

WINDOW: Final = 1.0
"""Time constant of the fraction of inconsistent checks, and how recent a source's last
gated sample must be to count, s (PX4: the clipping fraction over the past 1 s)."""

FRACTION: Final = 0.5
"""The accelerometer is bad when more than this fraction of the recent checks was
inconsistent (PX4: more than 50 % clipped samples in the past 1 s)."""

PROBATION: Final = 10.0
"""The accelerometer stays suspect this long after the last time the checks found it
inconsistent, s (PX4 BADACC_PROBATION): long enough for the inflated noise to bring the
prediction back onto the sources before any of them can be isolated for its fault."""

GROWTH: Final = 4.0
"""Factor of the noise's inflation at each :data:`ESCALATION` over which the checks stay
inconsistent."""

ESCALATION: Final = 3.0
"""Time between two inflations, s: longer than the height sources' bias windows
(``reset_timeout``, 2.5 s by default), so that an inflation is judged on innovations taken
after it."""

DECAY: Final = 300.0
"""Time constant of the inflation's return to the stated noise, s: slow, so that a noise
that is really larger stays inflated between two inflations (the check can only see a noise
too small, never one too large)."""

BAD: Final = 2.0
"""The accelerometer is reported bad (``status`` bit ``BAD_ACC_VERTICAL``) while its noise
is inflated by more than this factor."""

SCATTER_SAMPLES: Final = 100
"""Second differences of consecutive samples the scatter is taken over (1 s at 100 Hz); no
estimate before there are as many."""

EARLY_SAMPLES: Final = 10
"""Second differences from which the scatter of an accelerometer whose noise was not stated
raises its noise above the starting value, before :data:`SCATTER_SAMPLES` are in (10: 0.1 s at
100 Hz, 1.2 s at the 8.6 Hz of a logged ``sensor_combined``, where 100 took 11.6 s). Over 10
differences the estimate of white noise scatters by 42 % (simulated, 20 000 draws: 5th
percentile 0.47, 99.9th 2.7): taken only above the starting value, it errs on the safe side
(an accelerometer as typical seen at most 2.7x noisier until 100 samples are in), while one
20x noisier (a logged multicopter's 6-10 m/s² of rotor vibration) is seen at least 4x
noisier."""

SECOND_DIFFERENCE_MAD: Final = 0.6744897501960817 * math.sqrt(6.0)
"""Median of |a_k - 2a_(k-1) + a_(k-2)| for white noise of σ = 1: the second difference of
white noise is normal with variance (1 + 4 + 1)σ², and the median of |N(0, 1)| is
Φ⁻¹(3/4)."""

MARGIN: Final = 3.0
"""The measured scatter replaces the stated noise only beyond this factor of it (the
accelerometer is then also reported bad, :data:`BAD`). Over :data:`SCATTER_SAMPLES` second
differences the estimate of white noise has a relative standard error of 14 % (simulated:
0.138, 99.9th percentile 1.49). The vehicle's motion between samples adds to it: a steady
jerk cancels and a manoeuvre's few steps are outliers the median ignores, but a closed
loop's thrust, changed at every controller step, is steps at every other sample: in
yang2020's closed-loop flight its 0.01 m/s² accelerometer scatters as 0.0125 m/s² (median
over the flight; at most 0.0198, 2x). A third difference does not help (0.0136, at most
0.021), and minus the lag-1 autocovariance of the first differences, unbiased for a
random-walk acceleration, scatters more (at most 0.032). So an accelerometer is measured
once it is 3x noisier than stated."""


class AccelerometerCheck(Restorable):
    """The ``bad_acc_vertical`` condition of one estimator's accelerometer, and the noise to
    use for it (:attr:`noise`): its stated noise while good."""

    __slots__ = ("judges", "stated", "measured", "start", "floor", "noise", "bad", "suspect",
                 "fraction", "scatter", "_inflated", "_suspect_until", "_escalated", "_last",
                 "_decay", "_decay_dt", "_differences", "_last_samples")

    def __init__(self, stated_noise: float, judges: tuple[AidSource, ...],
                 stated: bool = True) -> None:
        self.judges = judges
        """The aid sources that judge the prediction: the height sources and the GNSS
        vertical speed (none: only the scatter is checked)."""
        self.stated = stated_noise
        """The accelerometer's stated noise, 1σ (m/s² per sample); not stated: its
        starting value, then its scatter."""
        self.measured = not stated
        """The noise was not stated: :attr:`stated` follows the scatter."""
        self.start = stated_noise
        """The noise stated, or where a noise not stated starts."""
        self.floor = stated_noise / UNSTATED_RANGE
        """The smallest noise a scatter sets when none was stated."""
        self.noise = stated_noise
        """The noise the estimator uses: the stated one, inflated while found too small."""
        self.bad = False
        """PX4's ``bad_acc_vertical``: :attr:`noise` more than :data:`BAD` times the stated."""
        self.suspect = False
        """True while more than :data:`FRACTION` of the recent checks were inconsistent, and
        for :data:`PROBATION` after: the height sources' disagreement with the prediction
        is then the accelerometer's fault, and no source is isolated for it."""
        self.fraction = 0.0
        """Exponential average of the inconsistent checks (time constant :data:`WINDOW`)."""
        self.scatter = 0.0
        """The noise measured from the samples' scatter (:func:`scatter_noise`; 0 until
        :data:`SCATTER_SAMPLES` second differences)."""
        self._inflated = stated_noise
        """The noise the height sources' disagreement calls for (decaying to the stated)."""
        self._differences: deque[float] = deque(maxlen=SCATTER_SAMPLES)
        self._last_samples = (math.nan, math.nan)
        """The last two samples, the latest first."""
        self._suspect_until = -math.inf
        self._escalated = -math.inf
        self._last = -math.inf
        """Time of the last check."""
        self._decay = self._decay_dt = 0.0

    def sample(self, acc_z: float) -> None:
        """An accelerometer sample (m/s²), in order: its second difference joins the
        scatter's (from the third sample on)."""
        a1, a2 = self._last_samples
        difference = abs(acc_z - 2.0 * a1 + a2)
        if difference == difference:                    # not NaN
            self._differences.append(difference)
        self._last_samples = (acc_z, a1)

    def step(self, now: float) -> None:
        """At the end of an estimator step: every :data:`PERIOD`, update the noise and the
        condition from the samples' scatter and the evidence of :attr:`judges`."""
        elapsed = now - self._last
        if elapsed < PERIOD * (1.0 - 1e-9):
            return
        self._last = now
        elapsed = min(elapsed, PERIOD if elapsed == math.inf else WINDOW)   # the first: one
        found = 1.0 if inconsistent(_judgements(self.judges, now)) else 0.0
        self.fraction += elapsed / WINDOW * (found - self.fraction)
        if self.fraction > FRACTION:
            self._suspect_until = now + PROBATION
        self.suspect = now <= self._suspect_until
        count = len(self._differences)
        if count == SCATTER_SAMPLES or (self.measured and count >= EARLY_SAMPLES):
            self.scatter = scatter_noise(self._differences)
            if self.measured:         # the base follows the scatter, a noise at the base too
                lowest = self.floor if count == SCATTER_SAMPLES else self.start
                base = min(max(self.scatter, lowest), ACC_CLIP)
                self._inflated = base if self._inflated == self.stated \
                    else max(self._inflated, base)
                self.stated = base
        if self.fraction > FRACTION and now - self._escalated >= ESCALATION:
            self._inflated, self._escalated = min(GROWTH * self.noise, ACC_CLIP), now
        elif self._inflated != self.stated:
            if elapsed != self._decay_dt:
                self._decay, self._decay_dt = math.exp(-elapsed / DECAY), elapsed
            self._inflated = self.stated + self._decay * (self._inflated - self.stated)
            if self._inflated < self.stated * (1.0 + 1e-6):
                self._inflated = self.stated
        measured = min(self.scatter, ACC_CLIP) if self.scatter > MARGIN * self.stated else 0.0
        self.noise = max(self._inflated, measured)
        self.bad = self.noise > BAD * self.stated

    @property
    def inflation(self) -> float:
        """(noise / stated)²: the factor on every variance stated for the accelerometer
        (exactly 1 while it is as stated)."""
        return (self.noise / self.stated) ** 2


def scatter_noise(differences) -> float:
    """The white noise (1σ) of samples whose absolute second differences are
    ``differences``: their median over :data:`SECOND_DIFFERENCE_MAD` (the median absolute
    deviation's estimate of σ, robust to the few large differences of a manoeuvre)."""
    return statistics.median(differences) / SECOND_DIFFERENCE_MAD


def _judgements(judges: tuple[AidSource, ...], now: float) -> Iterator[Judgement]:
    """The judgements of the prediction
    (:func:`~altfusion.estimators.prediction_judges.inconsistent`) by the recently gated
    (within :data:`WINDOW`), non-isolated ``judges``.

    A height source judges by the mean ȳ of its innovations over its bias window and that
    mean's variance S̄/n, once the window holds
    :data:`~.fault_detection.BIAS_MIN_SAMPLES` (an accelerometer's noise drives the
    prediction off for seconds: many coarse samples together see what one cannot, a 20 m
    drift under a 20 m baro); the GNSS vertical speed, which has no window, by its last
    innovation and its variance, whatever its sign (a noisy accelerometer's speed error
    and height error need not share theirs)."""
    for source in judges:
        if now - source.last_gated > WINDOW or source.isolated:
            continue
        window = source.window
        if window.n >= BIAS_MIN_SAMPLES:
            yield source.name, source.height, window.mean(), window.mean_variance()
        elif not source.height:
            yield source.name, False, source.innovation, max(source.variance, 0.0)
