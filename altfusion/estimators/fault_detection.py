"""The fault layer of every estimator (``fault_detection`` true): the bias test with
hysteresis, isolation, pinning by other sources, height and velocity resets and the
re-referencing of an isolated source. With ``fault_detection`` false none of it runs: a gated
sample is fused or rejected on its own test ratio, as in the papers.

Height reset (PX4's height reset): when a height sample is rejected and no height sample at
all was fused for ``reset_timeout`` (every source disagrees with the prediction), the
estimator resets its height onto that sample (:meth:`Estimator.reset_height`) and counts it
in ``n_height_resets``; a GPS vertical speed rejected for ``reset_timeout`` resets the speed
the same way (PX4's velocity reset).

Isolation: a height source whose samples stay rejected for ``reset_timeout`` while another
source pins the height tighter (:func:`contradicted`), or that fails the bias test
(:func:`bias_test`), is isolated until one of its samples passes the gate again.

Bias test: a height source whose innovations average beyond the gate over the last
``reset_timeout`` (a step smaller than one sample's gate but persistent), and as far from
those of another fused source closer to the prediction, is rejected, and isolated after
``reset_timeout`` of it.

Re-referencing: an isolated height source with an offset state
(:meth:`Estimator.reset_offset`) whose innovations stay on one side is re-admitted with that
state reset onto it (PX4's baro bias estimator re-learns a baro offset the same way while
GNSS holds the height).

The history of these choices (which fault-suite runs each one fixed) is in
``docs/estimator_health.md``.
"""

import math
from collections.abc import Iterable
from typing import Final

from altfusion.estimators.aid_source import AidSource, InnovationWindow

BIAS_MIN_SAMPLES: Final = 5
"""Fewest samples in a source's window before its bias test can reject it."""

BIAS_SIGMAS: Final = 5.0
"""Widest threshold of the bias test, in standard deviations of a window's mean: a
consistent source's mean lies beyond it once in 1.7 million windows. An estimator whose
single-sample gate is wider (XuSHAEKF's 6, for its adaptive noise) keeps that gate for single
samples, not for the mean of many."""

READMIT_SIGMAS: Final = 2.0
"""An isolated height source is re-admitted when the mean of its innovations over
``reset_timeout`` lies within this many standard deviations of that mean (95 % of the time
for a consistent source)."""

def bias_test(source: AidSource, heights: Iterable[AidSource], now: float, timeout: float,
              innovation: float, variance: float, sigmas: float) -> bool:
    """The bias test of height source ``source``: True if over the last ``timeout`` (at
    least :data:`BIAS_MIN_SAMPLES` samples) the mean ȳ of its innovations is beyond
    ``sigmas`` (:data:`BIAS_SIGMAS` at most) standard deviations of that mean, √(S̄/n), and
    beyond as many from the mean of another height source of ``heights`` fused within
    ``timeout`` that lies closer to the prediction (:func:`agrees`): the source disagrees
    with a source that agrees better with the prediction.

    A step smaller than the gate of one sample (a 100 m GNSS step under a 30 m noise)
    passes every single-sample gate but not this one: for consistent white innovations
    ȳ/√(S̄/n) is a standard normal variable, beyond 5 once in 1.7 million. A prediction
    that lags every source alike (an overconfident filter in a climb) moves every mean
    alike and isolates none. Every sample enters the window, fused or not, clipped to
    the gate (one wild sample cannot bias the mean: it moves it by at most one gate
    half-width over n). An isolated source stays rejected while its own mean lies beyond
    :data:`READMIT_SIGMAS` standard deviations, whatever the other sources do (PX4: a GNSS
    back 50 m off is not re-admitted); it is re-admitted once its biased samples have left
    the window. A source found biased but not yet isolated stays biased on the same margin
    (hysteresis): a mean hovering about the threshold would otherwise let a sample in now
    and then, restart the ``timeout`` to isolation and move the estimate onto the offset
    sample by sample."""
    if not source.height:
        return False
    window = source.window
    half_width = sigmas * math.sqrt(max(variance, 0.0))
    window.add(now, min(max(innovation, -half_width), half_width), variance, timeout)
    window.sigmas = threshold = min(sigmas, BIAS_SIGMAS)
    if len(window.samples) < BIAS_MIN_SAMPLES:              # window.n without a frame
        source.biased = False
        return False
    mean, spread = window.mean(), math.sqrt(window.mean_variance())
    if source.isolated:
        biased = abs(mean) > READMIT_SIGMAS * spread
    else:
        level = READMIT_SIGMAS if source.biased else threshold
        biased = abs(mean) > level * spread and any(
            other is not source and now - other.last_fused <= timeout
            and agrees(other.window, level, mean, spread) for other in heights)
    source.biased = biased
    return biased


def agrees(window: InnovationWindow, sigmas: float, mean: float, spread: float) -> bool:
    """True if another height source's innovation mean, over its ``window``, lies closer to
    the prediction than ``mean`` (spread ``spread``), each in its own standard deviations,
    and more than ``sigmas`` combined standard deviations from ``mean``: of two sources
    that disagree, the one further from the prediction is off. A source never gated (an
    empty window) counts as agreeing, with mean 0 known exactly.

    The other's mean need not pass the bias test itself: a prediction that is off too
    (BaoDriftEstimator holds the last accepted baro sample, 20 m noise and all) moves
    the means of both sources, and a GNSS 28 m from it (4.7 of its standard deviations)
    still tells a baro 130 m from it (31) to be the failed one."""
    if window.n == 0:
        return abs(mean) > sigmas * spread
    other_mean, other_variance = window.mean(), window.mean_variance()
    return (abs(other_mean) * spread < abs(mean) * math.sqrt(other_variance)
            and abs(mean - other_mean) > sigmas * math.sqrt(spread**2 + other_variance))


def contradicted(source: AidSource, heights: Iterable[AidSource], now: float,
                 timeout: float, innovation: float) -> bool:
    """True if another height source of ``heights``, fused within ``timeout`` and passing
    its own gate since, pins the height tighter than ``innovation`` (:func:`pin`), or if
    ``source`` failed its last bias test: then a sample of ``source`` that far from the
    prediction is the faulty one. A source too coarse to tell (a 3 m GPS against a 2 m
    terrain step under the laser) contradicts nothing."""
    if not source.height:
        return False
    if source.biased:
        return True
    return any(other is not source and now - other.last_fused <= timeout
               and abs(innovation) > pin(other) for other in heights)


def pin(source: AidSource) -> float:
    """How far from the prediction height source ``source`` lets the height be: its last
    gate half-width or, tighter, the mean of its bias window plus that window's threshold
    (:data:`BIAS_SIGMAS` at most) in standard deviations of the mean (a 30 m GNSS at 10 Hz
    pins the height to 30 m over 2.5 s, not to one sample's 150 m gate)."""
    bound = source.gate_width
    window = source.window
    if window.n >= BIAS_MIN_SAMPLES:
        bound = min(bound, abs(window.mean()) + window.sigmas * math.sqrt(window.mean_variance()))
    return bound
