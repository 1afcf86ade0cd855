"""The prediction judged by the aid sources: is it off, rather than one of them?

A filter's prediction that is off (an accelerometer noisier than stated, a motion model that
cannot follow a manoeuvre) moves the innovations of every source that observes it at once,
each far beyond its own standard deviation, and the height sources' on the same side. One
source alone could be off itself; every one at once points at the prediction (PX4 EKF2's
``checkVerticalAccelerationHealth`` judges the accelerometer this way: several height
sources' innovations beyond their test limit together).

Each judgement is one source's disagreement with the prediction: a name, whether it is a
height source, a disagreement y (m or m/s: the mean of its recent innovations) and the
variance of y if the prediction were right. The prediction is *inconsistent* when at least
``min_judges`` independent judges disagree with it by more than :data:`SIGMAS` standard
deviations (or as many as the caller asks), the height sources among them on one side (a
speed on any side, or, where the prediction is a motion model, on theirs: its lag moves its
height and speed the same way), and no height source that agrees pins the height tighter
than the smallest of the disagreements (a 5 mm laser that agrees with the prediction clears
it; a 30 m GNSS cannot tell a 3 m error). The rangefinders count as one judge (:data:`RANGE`):
both measure above the same terrain, and a terrain step moves both of their innovations as
an error of the prediction would.

Used by :mod:`~altfusion.estimators.accelerometer_check` (the accelerometer as the
prediction's input) and :mod:`~altfusion.estimators.process_noise` (the motion model
without one); each decides what a judgement is made of.
"""

import math
from collections.abc import Iterable
from typing import Final

SIGMAS: Final = 3.0
"""A disagreement beyond this many standard deviations counts against the prediction (PX4
EKF2's vertical innovation test limit, 3)."""

MIN_SOURCES: Final = 2
"""Fewest independent judges of the prediction for it to be found off where more are there
to judge: with one height source alone, that source could be the one off."""

RANGE, RANGE_SOURCES = "range", ("radar", "laser")
"""The rangefinders count as one judge (the module docstring)."""

Judgement = tuple[str, bool, float, float]
"""(source name, height source?, disagreement y, variance of y if the prediction is right)."""


def judge(name: str) -> str:
    """The judge a source's judgement counts for: the rangefinders are one."""
    return RANGE if name in RANGE_SOURCES else name


def inconsistent(judgements: Iterable[Judgement], min_judges: int = MIN_SOURCES,
                 speeds_on_side: bool = False, sigmas: float = SIGMAS) -> bool:
    """True if at least ``min_judges`` judges (:func:`judge`) of ``judgements`` disagree
    with the prediction beyond ``sigmas`` standard deviations, the height sources among
    them all on one side, and no height source that agrees pins the height tighter than
    the smallest of their disagreements. With ``speeds_on_side`` a speed (a judgement that
    is no height source's) counts only on the height sources' side: where the prediction's
    speed is off, its height drifts off the same way (a lagging motion model); a speed off
    the other way is no such evidence. Compared squared (no square roots)."""
    sign = 0
    beyond: set[str] = set()
    speeds: list[tuple[str, int]] = []
    smallest, pinned = math.inf, math.inf             # squared
    for name, height, y, variance in judgements:
        bound = sigmas * sigmas * variance
        if y * y <= bound:
            if height and bound < pinned:
                pinned = bound
            continue
        side = 1 if y > 0.0 else -1
        if not height:
            speeds.append((name, side))
            continue
        beyond.add(judge(name))
        if sign and side != sign:
            return False
        sign = side
        smallest = min(smallest, y * y)
    beyond.update(name for name, side in speeds if side == sign or not speeds_on_side)
    return len(beyond) >= min_judges and pinned >= smallest
