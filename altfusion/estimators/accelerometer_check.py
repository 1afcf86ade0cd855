"""The vertical accelerometer checked against every height source (PX4 EKF2's
``bad_acc_vertical``), with its noise inflated while it is found bad.

An estimator that integrates an accelerometer (AltitudeEKF, as its input) trusts it for the
motion between height samples. An accelerometer much noisier than its stated noise
(vibration, a loose mount, clipping) drives the prediction off while the filter's variances
stay small: every height source then disagrees with the prediction at once, each far beyond
its own innovation standard deviation, and on the same side (the prediction is off, not the
sources). One height source alone could be off itself; every one at once, together with the
GNSS speed where there is one, points at the accelerometer.

Only for an accelerometer that is the prediction's input: where it is a measurement of an
acceleration state driven by a white jerk (YangFusionKF), inflating it leaves a motion
model that lags every acceleration step, and the lag reads as a bad accelerometer.

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
:data:`DECAY` (a bounded innovation-based adaptation, after Mehra: the noise settles just
above the level the innovations show). The estimator reads
:attr:`AccelerometerCheck.noise` where it used its stated noise; ``status`` carries the
bit ``BAD_ACC_VERTICAL`` (PX4's ``bad_acc_vertical``) while the noise is inflated by
more than :data:`BAD`.

Deviations from PX4: PX4 requires clipping evidence unless GNSS speed and height are both
available, holds the flag for 10 s (``BADACC_PROBATION``) and inflates the noise to one
fixed level (``BADACC_BIAS_PNOISE``, 4.9 m/s²); here any two independent judges suffice (two
height sources are independent of each other) and the inflation follows the evidence (a
40x noisier accelerometer needs 2 m/s², a 10 m/s² one twice PX4's level).
"""

import math
from collections.abc import Iterator

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.fault_detection import BIAS_MIN_SAMPLES
from altfusion.estimators.prediction_judges import Judgement, inconsistent
from altfusion.estimators.streams import ACC_CLIP

PERIOD = 0.1
"""The check runs at most this often, s (at every estimator step when that is longer): its
evidence moves over seconds, and a check at every 10 ms step cost 10 µs, a fifth of an
estimator's step."""

WINDOW = 1.0
"""Time constant of the fraction of inconsistent checks, and how recent a source's last
gated sample must be to count, s (PX4: the clipping fraction over the past 1 s)."""

FRACTION = 0.5
"""The accelerometer is bad when more than this fraction of the recent checks was
inconsistent (PX4: more than 50 % clipped samples in the past 1 s)."""

PROBATION = 10.0
"""The accelerometer stays suspect this long after the last time the checks found it
inconsistent, s (PX4 BADACC_PROBATION): long enough for the inflated noise to bring the
prediction back onto the sources before any of them can be isolated for its fault."""

GROWTH = 4.0
"""Factor of the noise's inflation at each :data:`ESCALATION` over which the checks stay
inconsistent."""

ESCALATION = 3.0
"""Time between two inflations, s: longer than the height sources' bias windows
(``reset_timeout``, 2.5 s by default), so that an inflation is judged on innovations taken
after it."""

DECAY = 300.0
"""Time constant of the inflation's return to the stated noise, s: slow, so that a noise
that is really larger stays inflated between two inflations (the check can only see a noise
too small, never one too large)."""

BAD = 2.0
"""The accelerometer is reported bad (``status`` bit ``BAD_ACC_VERTICAL``) while its noise
is inflated by more than this factor."""


class AccelerometerCheck:
    """The ``bad_acc_vertical`` condition of one estimator's accelerometer, and the noise to
    use for it (:attr:`noise`): its stated noise while good."""

    __slots__ = ("judges", "stated", "noise", "bad", "suspect", "fraction", "_suspect_until",
                 "_escalated", "_last", "_decay", "_decay_dt")

    def __init__(self, stated_noise: float, judges: tuple[AidSource, ...]) -> None:
        self.judges = judges
        """The aid sources that judge the prediction: the height sources and the GNSS
        vertical speed."""
        self.stated = stated_noise
        """The accelerometer's stated noise, 1σ (m/s² per sample)."""
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
        self._suspect_until = -math.inf
        self._escalated = -math.inf
        self._last = -math.inf
        """Time of the last check."""
        self._decay = self._decay_dt = 0.0

    def step(self, now: float) -> None:
        """At the end of an estimator step: every :data:`PERIOD`, update the noise and the
        condition from the evidence of :attr:`judges`."""
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
        if self.fraction > FRACTION and now - self._escalated >= ESCALATION:
            self.noise, self._escalated = min(GROWTH * self.noise, ACC_CLIP), now
        elif self.noise != self.stated:
            if elapsed != self._decay_dt:
                self._decay, self._decay_dt = math.exp(-elapsed / DECAY), elapsed
            self.noise = self.stated + self._decay * (self.noise - self.stated)
            if self.noise < self.stated * (1.0 + 1e-6):
                self.noise = self.stated
        self.bad = self.noise > BAD * self.stated


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
