"""Each source's stated noise checked against its innovations, and inflated, within bounds,
while it is found too small.

A user tells an estimator the noise of each sensor from its data sheet; the sensor on the
vehicle is often noisier (vibration, quantization, a different mounting). A noise stated too
small makes the filter overconfident: its ``h_std`` shrinks while the error does not, and a
consistent sample may fail its gate. The innovations show it: for a consistent filter each
innovation y_k has the variance S_k the filter computes, and successive innovations are
uncorrelated (the innovation sequence of a Kalman filter is white; Mehra 1970), so

    E[(y_k - y_(k-1))²] = S_k + S_(k-1).

Check, at each gated sample of a source (after Mehra's covariance matching, in xu2016's
bounded form: xu2016 eqs. 22-24 scale R by the windowed mean normalized innovation squared,
bounded below by 1): with f the factor on the source's stated variance R in use,

    ρ_k = min((y_k - y_(k-1))² / (S_k + S_(k-1)), CLIP)
    m   ← m + (ρ_k·f - m)/min(n, window),    f = min(max(m, 1), maximum)

(n: the pairs so far: the first ``window`` pairs are averaged alike, so that a source
sampled at 1-5 Hz is judged within seconds, not after a window of a hundred samples)
m is an estimate of the ratio of the true noise variance to the stated one: at the fixed
point E[ρ] = 1, i.e. S holds the true noise. The factor is never below 1 (a quiet spell
cannot make the filter more confident than the user's figure) and never above ``maximum``
(beyond it the sensor is not the one described, and the fault layer judges it). A source's
``status`` bit ``NOISE_INFLATED`` is set while f exceeds :data:`FLAGGED`.

Deviations from xu2016 (which uses the mean of y²/S itself):

* the *differences* of successive innovations, not the innovations: a bias, a drift or an
  offset not yet learnt (a baro offset, a GNSS step before its isolation, a terrain step
  under a rangefinder) moves successive innovations alike and cancels in their difference,
  so only the scatter the noise makes is read as noise (xu2016's mean square would inflate
  R under a bias, widening the gate that should reject it);
* rejected samples count too, and a pair only when nothing moved the prediction between its
  two samples (no reset, no re-referencing: :meth:`NoiseCheck.forget`): a source stated so
  precise that its gate rejects it would otherwise never be inflated, and be isolated for
  its noise (measured: the GNSS of tests/test_noise_check.py's hover told 5x too small,
  isolated 10 s in at a factor of 10 with fused samples only);
* each pair's ratio is clipped at :data:`CLIP`, so that one wild sample within the gate
  moves m by at most CLIP/window (once the window is full);
* the flag waits for :data:`MIN_PAIRS` pairs;
* the factor's rise above its earlier peak is told (:attr:`NoiseCheck.rise`): the samples
  fused before were weighted as that much more precise than they were, and the estimator
  raises what they taught it by as much (AltitudeEKF: the datum's variance, for its height
  reference). A stated noise's factor is told as a rise only as far as the check has shown
  it with CONFIDENCE: the lower bound of the true ratio's one-sided interval,
  m·k/χ²_k(CONFIDENCE), at most the factor in use, once beyond :data:`FLAGGED` (for a
  source as told practically never: at one pair a ratio beyond 20, 10⁻⁵; at two, beyond
  15). The first pairs of a source as told scatter (their mean exceeds 4 once in 22 at one
  pair): rises told from them would widen what the user stated along with the datum (the
  numbers: docs/altitude_ekf.md);
* a source whose noise is found well above the stated (:data:`NOISY`) is neither isolated
  nor rejected by the bias test of the fault layer (a biased source told right is) during
  its first ``window`` pairs, while its noise is being learnt; after them its gate and bias
  test are sized by the learnt noise, and a fault is judged as for a source told right
  (measured: a GNSS told 6 m for its 30 m, spared for good, took its +100 m step in with the
  height, coverage 40 %; judged after its window, 91 %).

A noise *not stated* (the user told none: the estimator has a small UAV's typical value) is
measured instead of checked, within [1/:data:`UNSTATED_RANGE`², :data:`UNSTATED_RANGE`²] of
the typical value:

* it starts pessimistic, at :data:`UNSTATED_START` times the typical variance: a sensor far
  noisier than typical would otherwise have its first samples taken as precise, and they
  would weigh in the estimate for minutes (measured: a 30 m GNSS started at 3 m kept the
  height 15 m off after 10 s, 6 m after 40 s);
* the factor in use is the upper bound of m's one-sided :data:`CONFIDENCE` interval,
  m·k/χ²_k(1 - CONFIDENCE) with k = min(n, 2·window - 1) the degrees of freedom of m (the
  mean of n χ² ratios of one degree; the exponential window's average has about
  2·window - 1 once full, and this takes them from n = window on: slightly too few
  pairs' worth of caution in between), :func:`upper_bound_factor`, and falls by at most
  :data:`FALL` per pair: a noise known from a few pairs only is not yet trusted to be small
  (the mean of 4 ratios is below a third of the true one once in 7, and was so on the
  3 m GNSS of one xu2016_hover15 run: taken as 1.4 m, the height 5 m off under an
  ``h_std`` of 1.2 m, with the bound m·(1 + 2·√(2/n)) used before, 2.4 m at four pairs
  against the interval's 8.3);
* it is never flagged (there is no statement to be wrong), and it is ``noisy`` (spared by
  the fault layer) only until its first ``window`` pairs are in: until then its gate and
  bias test are not yet sized by its noise;
* a pair's ratio is taken against the two samples' typical noise variances (R without the
  factor, which changes from pair to pair while the noise is measured), ρ_k = (y_k -
  y_(k-1))² / (R_k + R_(k-1)) clipped at CLIP·f, and m ← m + (ρ_k - m)/min(n, window); not
  against S_k + S_(k-1):
  Mehra's E[(y_k - y_(k-1))²] = S_k + S_(k-1) holds for a consistent filter only, and one
  whose prediction is far less certain than its noise (its start, an offset not yet learnt)
  sees the same prediction error in successive innovations, which cancels in their
  difference while S counts it twice: the ratio then reads far too small, and a noise not
  stated would be taken down to a fraction of its value within a few pairs (measured: the
  3 m GNSS of xu2016_hover15 taken as 1.4 m after 1.4 s, the height 5 m off under an
  ``h_std`` of 1.2 m). Against R alone the ratio errs the other way when the prediction
  moves between two samples by more than their noise (a manoeuvre), which only makes the
  noise larger: the safe side for a noise measured both ways. A stated noise, never
  deflated, keeps S (the flag must not be set by a manoeuvre).

A stated noise is never deflated: a sensor whose errors are correlated in time (a GNSS)
scatters less from sample to sample than its datasheet's σ, which is the honest figure for
the filter. The check says how much less (:meth:`NoiseCheck.unshown`): the share of the
stated variance that successive innovations do not show, judged against R alone as a noise
not stated is (a prediction error shared by the two samples cancels in their difference,
which S would count twice), 1 - 2·w with w the upper bound of the shown ratio's
one-sided CONFIDENCE interval, from :data:`MIN_PAIRS` pairs on: 0 while the innovations
show half the stated variance or more (a source as told practically always: w < 1/2 at 20
pairs is χ² with 20 degrees of freedom below 4.8, 2·10⁻⁴, and rarer with every pair after),
the whole statement in the limit. That share is an error the samples share over
minutes, which averaging them does not reduce (AltitudeEKF: the GNSS datum's error,
``gps_slow_error``). A noise not stated is read alike against its typical value, w being
its measured ratio m: told nothing, the estimator assumes a typical receiver, whose
typical σ is mostly such an error, unless its samples scatter as much.
"""

import math
from functools import cache
from statistics import NormalDist
from typing import Final

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.floats import finite
from altfusion.estimators.restorable import Restorable

CLIP: Final = 25.0
"""Largest contribution of one pair of innovations to the ratio (the square of the 5σ gate:
a consistent pair exceeds it once in 1.7 million; two samples each within a 5σ gate can
reach 50)."""

FLAGGED: Final = 4.0
"""``NOISE_INFLATED`` is set while the variance factor exceeds this: the noise in use more
than twice the stated σ (the accelerometer check's ``BAD``). With the default window of 100
pairs, m of a source as told has the spread of χ² with about 200 degrees of freedom over
200: beyond 4 practically never (beyond 1.5 with a probability of about 10⁻⁷)."""

NOISY: Final = 2.0
"""Above this ratio m, within its first ``window`` pairs, the source is ``noisy``
(:attr:`AidSource.noisy`): it is not isolated, nor rejected for its bias test. While its
noise is being found too small its samples fail a gate and a bias test sized by the stated
noise, and rejecting or isolating it for that would leave the height to the others for good
(measured: the GNSS, the height reference, isolated 3-6 s into yang2020 and xu2016_hover15
told every noise 5x too small, the height walking 3-65 m off with the baro). A source as
told exceeds it only in its first pairs (the mean of 20 χ² ratios beyond 2 once in 200); a
step or a drift does not move the ratio (differences), one wild sample by at most
CLIP/window."""

MIN_PAIRS: Final = 20
"""The flag is set only after this many pairs: the mean of 20 ratios of a source as told
exceeds 4 with the probability of χ² with 20 degrees of freedom beyond 80, 10⁻⁸ (the
first pairs alone would flag a source as told once in 22: χ² with one degree beyond 4)."""

UNSTATED_RANGE: Final = 100.0
"""A noise not stated is learnt within this factor either way of its typical value (σ; its
variance within the square): from a small UAV's typical sensors to the 20-70 m baro and GNSS
of a paper's aircraft, and down to a 5 mm laser."""

UNSTATED_START: Final = 100.0
"""A noise not stated starts at this factor on its typical variance (σ tenfold)."""

FALL: Final = 4.0
"""The factor of a noise not stated falls by at most this ratio per pair."""

WINDOW: Final = 100.0
"""Pairs in a check's window (AltitudeEKF's default ``adaptive_window``, XuSHAEKF's checks,
:class:`ShownNoise`)."""

CONFIDENCE: Final = 0.975
"""One-sided confidence that the true variance of a noise not stated is below the one in use
(the two-standard-error bound of a normal estimate)."""


def chi2_quantile(dof: int, probability: float) -> float:
    """χ²_k(p), the p quantile of χ² with k degrees of freedom: exact for k = 1 and 2,
    Wilson-Hilferty's cube above (for k = 3 its 2.5 % quantile is 16 % low; within 5 % from
    k = 5 on); no scipy inside an FMU, which runs in the host's Python."""
    if dof == 1:
        return NormalDist().inv_cdf(0.5 + probability / 2.0) ** 2
    if dof == 2:
        return -2.0 * math.log1p(-probability)
    spread = 2.0 / (9.0 * dof)
    return dof * (1.0 - spread + NormalDist().inv_cdf(probability) * math.sqrt(spread)) ** 3


@cache
def upper_bound_factor(dof: int) -> float:
    """k/χ²_k(1 - CONFIDENCE): the factor from the mean m of k χ² ratios of one degree to the
    upper bound of the true ratio's one-sided CONFIDENCE interval (1018 for k = 1, 39.5 for
    2, 3.10 for 10, 1.23 for 199; Wilson-Hilferty's low quantile at k = 3 makes its bound
    19 % wide, the cautious side)."""
    return dof / chi2_quantile(dof, 1.0 - CONFIDENCE)


@cache
def lower_bound_factor(dof: int) -> float:
    """k/χ²_k(CONFIDENCE): the factor from m to the lower bound of the true ratio's one-sided
    CONFIDENCE interval (0.20 for k = 1, 0.27 for 2, 0.49 for 10, 0.83 for 199)."""
    return dof / chi2_quantile(dof, CONFIDENCE)


class NoiseCheck(Restorable):
    """The noise factor of one source: :attr:`factor` multiplies its stated variance R."""

    __slots__ = ("source", "window", "maximum", "minimum", "stated", "flagged", "ratio",
                 "scatter", "factor", "peak", "rise", "pairs", "_last")

    def __init__(self, source: AidSource, window: float, maximum: float,
                 stated: bool = True, flagged: float = FLAGGED) -> None:
        self.source = source
        self.flagged = flagged
        """The factor beyond which a stated noise is flagged (:data:`FLAGGED`; higher for a
        filter whose innovations are not white)."""
        self.window = window
        """Pairs in the exponential window of the ratio's average."""
        self.stated = stated
        """The user stated the noise (checked: never deflated); False: it is measured, from
        a typical starting value, within :data:`UNSTATED_RANGE` either way."""
        self.maximum = maximum if stated else UNSTATED_RANGE**2
        """Largest factor on the variance."""
        self.minimum = 1.0 if stated else UNSTATED_RANGE**-2
        """Smallest factor on the variance."""
        self.ratio = 1.0
        """m: the windowed estimate of the true noise variance over the stated one."""
        self.scatter = 1.0
        """w: the windowed estimate of the variance successive samples show over the stated
        one, judged against the samples' R (a stated noise's; :meth:`unshown`)."""
        self.factor = 1.0 if stated else UNSTATED_START
        """f: the factor on the stated variance in use."""
        self.peak = self.factor
        """The largest factor so far told as a rise (a stated noise's: the largest shown,
        :meth:`_shown`)."""
        self.rise = 1.0
        """The ratio by which the last gated sample took the factor above its earlier peak
        (1: not above): the samples fused before were weighted as if that much more precise,
        and what they taught the filter is that much less certain."""
        self.pairs = 0
        """n: the pairs of innovations taken so far."""
        self._last: tuple[float, float, float] | None = None
        """(y, S, R) of the source's previous gated sample; None after a reset."""

    def gated(self, innovation: float, variance: float, noise: float) -> None:
        """A sample of innovation y, variance S and noise variance R (both with the present
        factor) was gated, fused or rejected: update the ratio and the factor from it and the
        previous one (a stated noise is judged against S, one not stated against R)."""
        self.rise = 1.0
        if self.stated:
            last = self._last
            pair = self._pair(innovation, variance, CLIP, noise)
            if pair is None or last is None:          # (no pair without a last sample)
                return
            pairs = min(self.pairs, self.window)
            self.ratio += (pair * self.factor - self.ratio) / pairs
            difference = innovation - last[0]
            scatter = difference * difference * self.factor / (noise + last[2])
            self.scatter += (min(scatter, CLIP) - self.scatter) / pairs
            self.factor = min(max(self.ratio, self.minimum), self.maximum)
            self.source.mark_inflated(self.beyond_flag and self.pairs >= MIN_PAIRS)
            self.source.noisy = self.ratio > NOISY and self.pairs < self.window
        else:
            # against each sample's R without the factor (it changes from pair to pair while
            # the noise is measured), clipped as the stated pairs are against f·R
            pair = self._pair(innovation, noise / self.factor, CLIP * self.factor, noise)
            if pair is None:
                return
            self.ratio += (pair - self.ratio) / min(self.pairs, self.window)
            bound = self.ratio * upper_bound_factor(self._dof())
            self.factor = min(max(bound, self.factor / FALL, self.minimum), self.maximum)
            self.source.noisy = self.pairs < self.window
        told = self.factor if not self.stated else self._shown()
        if told > self.peak:
            self.rise, self.peak = told / self.peak, told

    @property
    def beyond_flag(self) -> bool:
        """Whether the factor in use exceeds :attr:`flagged` (the ``NOISE_INFLATED`` bit also
        waits for :data:`MIN_PAIRS` pairs)."""
        return self.factor > self.flagged

    def unshown(self) -> float:
        """The share of a stated noise's variance (of the typical one, for a noise not
        stated) that successive innovations do not show (module documentation):
        1 - 2·w·k/χ²_k(1 - CONFIDENCE), from :data:`MIN_PAIRS` pairs on, in [0, 1]."""
        if self.pairs < MIN_PAIRS:
            return 0.0
        shown = self.scatter if self.stated else self.ratio
        return max(0.0, 1.0 - 2.0 * shown * upper_bound_factor(self._dof()))

    def _dof(self) -> int:
        """k: the degrees of freedom of m, min(n, 2·window - 1) (the exponential window's
        average has about 2·window - 1 once full)."""
        return min(self.pairs, 2 * math.ceil(self.window) - 1)

    def _shown(self) -> float:
        """How much too small a stated noise is shown to be: the lower bound of the true
        ratio's one-sided CONFIDENCE interval, m·k/χ²_k(CONFIDENCE), at most the factor f
        in use (the samples were weighted by no more), once beyond :data:`FLAGGED`; 1 before
        (the statement stands)."""
        if not self.beyond_flag:            # nor is the bound, at most f
            return 1.0
        bound = min(self._confident_ratio(), self.factor)
        return bound if bound > self.flagged else 1.0

    def _confident_ratio(self) -> float:
        """m·k/χ²_k(CONFIDENCE): the lower bound of the true ratio's one-sided CONFIDENCE
        interval."""
        return self.ratio * lower_bound_factor(self._dof())

    def _pair(self, innovation: float, variance: float, clip: float, noise: float,
              ) -> float | None:
        """(y_k - y_(k-1))² over the sum of the two samples' ``variance``, at most ``clip``,
        counted in :attr:`pairs`; None without a previous sample (or a variance that is not
        a positive number). The sample's noise variance R is kept with it."""
        last = self._last
        self._last = (innovation, variance, noise)
        if last is None:
            return None
        total = variance + last[1]
        if not total > 0.0 or not finite(total):
            return None
        difference = innovation - last[0]
        self.pairs += 1
        return min(difference * difference / total, clip)

    def forget(self) -> None:
        """The next sample starts a new pair (after a reset, a re-referencing or a gap)."""
        self._last = None


SHOWN: Final = 2.0
"""A paper filter's stated noise is taken as shown too small (:class:`ShownNoise`) while the
lower bound of the true ratio's one-sided CONFIDENCE interval exceeds this (from
:data:`MIN_PAIRS` pairs on): the noise's σ more than 1.4 times the stated, beyond which
|e| <= 2 h_std would hold less than 80 % of the time (2/√2.4 σ for a ratio of 2.4, where
the bound passes 2 once the window is full). A source as told practically never: at 20 pairs
its mean ratio must exceed 3.4 (χ² with 20 degrees of freedom beyond 68, 10⁻⁷), rarer with
every pair after."""


SHOWN_MAXIMUM: Final = 100.0
"""Largest factor :class:`ShownNoise` shows (σ tenfold, AltitudeEKF's ``adaptive_max``):
its gate is widened by no more, so that a sensor gone to noise far beyond its description
is not let in at the weight the filter gives it, and is judged by the fault layer."""


class ShownNoise(NoiseCheck):
    """The noise a paper filter's source shows against the variance S its filter computes:
    the fault layer's check of a filter that keeps its stated R (the paper's equations stay
    as they are, ``fault_detection=false`` runs them unchecked).

    The ratio m is NoiseCheck's (Mehra's differences of successive innovations, the same
    window), taken against S as the filter computes it, each pair clipped at CLIP·f as
    NoiseCheck's at CLIP against f·S (f the factor shown: m of a noise 25 times the stated
    settles at half of it while f is 1, is shown, and rises to the ratio). While the noise
    is shown too small (:data:`SHOWN`) :attr:`factor` is the lower bound of the true ratio's
    one-sided CONFIDENCE interval, m·k/χ²_k(CONFIDENCE), at most :data:`SHOWN_MAXIMUM`: the
    gate judges the source's samples against f·S (so that a source stated 5x too precise is
    gated by its own noise, not rejected and isolated for it), the estimator's published
    ``h_std`` takes the largest factor of its sources
    (:meth:`~altfusion.estimators.gating.Gating.gate`), and the source's ``NOISE_INFLATED``
    bit is set; else the factor is 1 and everything is as the filter computes it: a filter
    told its noise is bit for bit the one without the check. The bound, not m: a filter
    told wrong starts with errors far beyond its S, its prediction jumps between a source's
    samples and the first pairs read more than the noise (yang2020 told 0.2x, m itself:
    a radar's gate widened 10x within 4 s let in a height 139 m off, held at an h_std of
    3 m; 10 runs: RMS 5.5 m, with the bound 1.45 m). Deviations from NoiseCheck: nothing is
    inflated inside the filter and the source is never spared as ``noisy``."""

    __slots__ = ()

    def __init__(self, source: AidSource, window: float = WINDOW,
                 maximum: float = SHOWN_MAXIMUM) -> None:
        super().__init__(source, window, maximum, flagged=SHOWN)

    def gated(self, innovation: float, variance: float, noise: float = 0.0) -> None:
        """A sample of innovation y and variance S (the filter's) was gated: update m and,
        while the noise is shown too small, the factor and the source's bit (``noise``:
        NoiseCheck's, unused here)."""
        # clipped as the stated pairs are against f·S (here S has no factor)
        pair = self._pair(innovation, variance, CLIP * self.factor, noise)
        if pair is None:
            return
        ratio = self.ratio = self.ratio + (pair - self.ratio) / min(self.pairs, self.window)
        if ratio > self.flagged and self.pairs >= MIN_PAIRS and \
                (bound := self._confident_ratio()) > self.flagged:
            self.factor = min(bound, self.maximum)
            self.source.mark_inflated(True)
        elif self.factor != 1.0:                # no longer shown (else nothing to undo)
            self.factor = 1.0
            self.source.mark_inflated(False)
