"""The GNSS height reference handed over to a rangefinder over a known terrain, when its
innovations' long mean shows it has shifted.

A GNSS reference that steps by less than its noise passes every gate and every bias test of
the fault layer (:func:`~altfusion.estimators.fault_detection.bias_test`, over
``reset_timeout``): the fault suite's ``all_fail``, the GNSS +10 m within its 30 m noise (a
mean over 2.5 s of 10 Hz samples is known to 6 m), the baro +5 m with it. The height follows
the shifted datum at the GNSS's weight while ``h_std`` stays that of the averages: measured,
AltitudeEKF told the noises 1.0-1.7 m off at an ``h_std`` of 0.5 m, |e| <= 2 ``h_std`` 0-85 %
of the minute after the fault, while the radio altimeter over the terrain told reads the
truth. Over :data:`SPAN` the shift shows: the mean of 300 samples is known to 1.7 m, and
the rangefinder's, read against the same prediction, stays near it.

The test, at each sample of the reference: its innovations' mean ȳ over :data:`SPAN` beyond
:data:`~altfusion.estimators.fault_detection.BIAS_SIGMAS` standard deviations of that mean
(√(ΣS)/n, with the GNSS's slow error, which no averaging removes:
:attr:`~altfusion.estimators.aid_source.InnovationWindow.shared`), and a rangefinder fused
within ``reset_timeout`` over the same span closer to the prediction and as far from ȳ
(:func:`~altfusion.estimators.fault_detection.agrees`), over a terrain known better than
that rangefinder's mean. Only samples that passed the gate enter a window, and a rejected
one empties it: a step the fault layer sees (a GNSS +100 m, one back 50 m off after an
outage) is its to isolate, and a reference re-admitted is judged on its samples from then on.

Then the estimator hands the datum over (PX4 EKF2 hands a failing height reference over,
its gpsRefFailOver and baroRefFailOver tests; it has no such slow test): the rangefinder over
the terrain becomes the datum, as with ``height_ref`` range, and the GNSS gets its offset
state (AltitudeEKF: :meth:`~altfusion.estimators.altitude_ekf.AltitudeEKF._hand_over`;
``gps_handover`` false keeps the GNSS the reference). Once, for the flight: the terrain does
not shift. Measured on ``all_fail`` (the evaluation, 10 runs, coverage outside the fault's
transient): told the noises 76 -> 93 %, told nothing 79 -> 91 %, told every noise x0.2
75 -> 93 %; RMS 0.78 -> 0.52 m told the noises; handed over 23-61 s after the fault; never
on the nominal flight, yang2020 or xu2016_hover15 (10 runs each, every mode).

Deviations from the fault layer's bias test: a long window, of samples that passed their
gate only, that reaches half its span back (:data:`COVERED`), for the reference alone; of
the GNSS only, not of a baro reference (its slow drift is its nature).
"""

import math
from collections.abc import Iterable, Mapping
from typing import Final

from altfusion.estimators.aid_source import AidSource, InnovationWindow
from altfusion.estimators.fault_detection import BIAS_MIN_SAMPLES, BIAS_SIGMAS, agrees
from altfusion.estimators.restorable import Restorable

SPAN: Final = 30.0
"""The long window, s: a 10 m shift of a 30 m GNSS at 10 Hz is 5.8 standard deviations of
its mean over it (1.7 m; over 10 s, 3.3)."""

COVERED: Final = 0.5
"""The reference's window must reach this share of :data:`SPAN` back: a source back from an
outage off by more than its noise is the fault layer's to judge in its first seconds
(measured: a GNSS back 50 m off, before its bias test isolated it, handed the datum over
within a second, re-admitted with the offset; PX4 does not re-admit it)."""

REFERENCE: Final = "gps"
"""The source whose shift is judged: the GNSS height reference."""


class ReferenceHandover(Restorable):
    """The long innovation windows of the GNSS reference and of the estimator's
    rangefinders."""

    __slots__ = ("windows",)

    def __init__(self, rangefinders: Iterable[str]) -> None:
        self.windows = {name: InnovationWindow() for name in (REFERENCE, *rangefinders)}
        """The innovations over :data:`SPAN` of the GNSS reference and of each rangefinder."""

    @property
    def reference(self) -> InnovationWindow:
        """The GNSS reference's window."""
        return self.windows[REFERENCE]

    def gated(self, source: str, now: float, innovation: float, variance: float,
              fused: bool) -> None:
        """A sample of ``source`` was gated: if it is the reference's or a rangefinder's, a
        fused one enters its window, a rejected one empties it."""
        window = self.windows.get(source)
        if window is None:
            return
        if fused:
            window.add(now, innovation, variance, SPAN)
        else:
            window.clear()

    def shifted(self, now: float, aid: Mapping[str, AidSource], timeout: float,
                terrain_variance: float) -> str | None:
        """The rangefinder that shows the reference shifted (module documentation), or
        None. ``aid``: the estimator's sources (a rangefinder's time of last fusion)."""
        window = self.reference
        if window.n < BIAS_MIN_SAMPLES or now - window.samples[0][0] < COVERED * SPAN:
            return None
        mean, spread = window.mean(), math.sqrt(window.mean_variance())
        if abs(mean) <= BIAS_SIGMAS * spread:
            return None
        for name, other in self.windows.items():
            if name != REFERENCE and other.n >= BIAS_MIN_SAMPLES \
                    and now - aid[name].last_fused <= timeout \
                    and terrain_variance < other.mean_variance() \
                    and agrees(other, BIAS_SIGMAS, mean, spread):
                return name
        return None
