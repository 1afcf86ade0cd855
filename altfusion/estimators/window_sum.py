"""The correctly rounded sum of the last values of a stream, kept as they come.

``math.fsum(window)`` over a sliding window of n values costs n additions at every sample
(xu2016's noise estimates: 100 accelerometer differences at every step). :class:`WindowSum`
keeps the window's exact sum as Shewchuk's non-overlapping partials (the algorithm of
``math.fsum``, Python's ``msum`` recipe): a value entering is added, the value leaving is
added negated, each exactly (no rounding: every partial sum is split into its rounded value
and its exact error), and :meth:`WindowSum.total` rounds the partials, a few floats, with
``math.fsum``. Both are the correctly rounded value of the same exact sum: the same bits as
``math.fsum`` over the window. Exactness needs finite values whose sums do not overflow: while
the window holds a value that is not finite, or its partials overflowed (rebuilt from the
window at each value until they no longer do), :meth:`WindowSum.total` is ``math.fsum`` of
the window itself.
"""

import math
from collections import deque

from altfusion.estimators.floats import finite
from altfusion.estimators.restorable import Restorable


class WindowSum(Restorable):
    """The last ``length`` values pushed (:attr:`values`) and their sum (:meth:`total`)."""

    __slots__ = ("values", "partials", "non_finite", "exact")

    def __init__(self, length: int) -> None:
        self.values: deque[float] = deque(maxlen=length)
        self.partials: list[float] = []
        """The window's exact sum: non-overlapping floats, by increasing magnitude."""
        self.non_finite = 0
        """Values in the window that are not finite."""
        self.exact = True
        """The partials hold the sum of the window's finite values (False: they overflowed)."""

    def __len__(self) -> int:
        return len(self.values)

    def push(self, value: float) -> None:
        """``value`` enters the window (the oldest leaves it once it is full)."""
        values = self.values
        if len(values) == values.maxlen:
            self._leave(values[0])
        values.append(value)
        if finite(value):
            self._add(value)
        else:
            self.non_finite += 1
        if not self.exact:
            self._rebuild()

    def clear(self) -> None:
        """An empty window."""
        self.values.clear()
        self.partials = []
        self.non_finite = 0
        self.exact = True

    def total(self) -> float:
        """``math.fsum`` of the window (0.0 when it is empty)."""
        if self.non_finite or not self.exact:
            return math.fsum(self.values)
        return math.fsum(self.partials)

    def _leave(self, value: float) -> None:
        """``value``, the oldest, leaves the window's sum."""
        if finite(value):
            self._add(-value)
        else:
            self.non_finite -= 1

    def _rebuild(self) -> None:
        """The partials summed afresh from the window's finite values."""
        self.partials = []
        self.exact = True
        for value in self.values:
            if finite(value):
                self._add(value)

    def _add(self, x: float) -> None:
        """Add ``x`` to the partials exactly (Shewchuk's two-sum, as ``math.fsum``); a sum
        that overflows leaves them inexact."""
        partials = self.partials
        kept = 0
        for y in partials:
            if abs(x) < abs(y):
                x, y = y, x
            high = x + y
            if not finite(high):
                self.exact = False
                return
            low = y - (high - x)
            if low != 0.0:
                partials[kept] = low
                kept += 1
            x = high
        del partials[kept:]
        partials.append(x)
