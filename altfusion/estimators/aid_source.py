"""One aid source per sensor stream: what the estimator knows about that source's samples.

PX4 EKF2 keeps one control unit per aiding source (``aid_sources/``: baro, GNSS, range
height) and one status struct per source (``estimator_aid_source1d``: innovation, its
variance, test ratio, fused or rejected, time of the last fusion). :class:`AidSource` is that
struct here, with the bias-test window and the isolation state of the fault layer
(:mod:`altfusion.estimators.fault_detection`). Gating a sample gives an explicit
:class:`Verdict`.
"""

import math
from collections import deque
from enum import Enum
from typing import Any, Final

from altfusion.estimators.health import (
    HEIGHT_SOURCES,
    NOISE_CHECKED,
    SourceBit,
    source_bit,
)
from altfusion.estimators.restorable import Restorable

MAX_WINDOW_VALUE: Final = 1e100
"""Innovations and variances entering a bias window are clipped to this magnitude, so that
its running sums stay finite."""


class InnovationWindow(Restorable):
    """A height source's innovations y and their variances S over a span of time, with
    running sums: the mean ȳ = Σy/n and its variance ΣS/n² + :attr:`shared` (independent
    samples, but for the error they share)."""

    def __init__(self) -> None:
        self.samples: deque[tuple[float, float, float]] = deque()
        self.sum_y = 0.0
        self.sum_S = 0.0
        self.sigmas = math.inf
        """The bias test's threshold for this source, set by each test (inf before)."""
        self.shared = 0.0
        """The variance of the error every sample in the window shares, m² (set by the
        estimator: a slowly varying error its filter takes as white, which no number of
        samples averages away; 0: the samples' errors are independent). Kept by
        :meth:`clear`: it is the source's, not the window's."""

    @property
    def n(self) -> int:
        return len(self.samples)

    def add(self, now: float, y: float, S: float, span: float) -> None:
        """Add the sample (y, S) of time ``now`` and drop those older than ``span``."""
        y = min(max(y, -MAX_WINDOW_VALUE), MAX_WINDOW_VALUE)
        S = min(max(S, 0.0), MAX_WINDOW_VALUE)
        samples = self.samples
        samples.append((now, y, S))
        self.sum_y += y
        self.sum_S += S
        while now - samples[0][0] > span:
            _, old_y, old_S = samples.popleft()
            self.sum_y -= old_y
            self.sum_S -= old_S

    def clear(self) -> None:
        """Forget every sample (a re-referenced source starts its window anew)."""
        self.samples.clear()
        self.sum_y = self.sum_S = 0.0
        self.sigmas = math.inf

    def mean(self) -> float:
        return self.sum_y / len(self.samples)

    def mean_variance(self) -> float:
        n = len(self.samples)
        return max(self.sum_S, 0.0) / (n * n) + self.shared

    def one_sided(self, min_samples: int) -> bool:
        """True if the window holds ``min_samples`` or more innovations, all of one sign (a
        constant offset, not noise)."""
        return self.n >= min_samples and (all(y > 0.0 for _, y, _ in self.samples)
                                               or all(y < 0.0 for _, y, _ in self.samples))


class Verdict(Enum):
    """What became of a gated sample."""

    FUSED = "fused"
    """It passed its gate: the estimator fuses it."""
    REJECTED = "rejected"
    """It failed its gate (or its plausibility bound): counted, not fused."""
    RESET = "reset"
    """It failed its gate, and the estimator reset its state onto it (PX4's height or
    velocity reset): consumed, not fused."""
    REREFERENCED = "rereferenced"
    """An isolated source with a constant offset: the estimator's offset state moved onto it
    and the source re-admitted: consumed, not fused."""


FUSED: Final = Verdict.FUSED
""":attr:`Verdict.FUSED` as a module constant, for the per-sample paths: an enum member read
through its class takes the metaclass's slow attribute lookup (~0.1 µs), a global does not."""


class AidSource(Restorable):
    """The state of one source (``baro``, ``gps``, ``radar``, ``laser``, ``gps_vz``,
    ``acc``) of an estimator: its last sample's gating, its counters and its health."""

    __slots__ = ("name", "height", "fused_mask", "rejected_mask", "isolated_mask",
                 "inflated_mask", "test_ratio", "rejected", "innovation", "variance",
                 "gate_width", "window", "last_fused", "last_gated", "rejected_since", "biased",
                 "noisy", "shown", "bits")

    def __init__(self, name: str) -> None:
        self.name = name
        self.height = name in HEIGHT_SOURCES
        """A height source: its fusion keeps ``h_valid`` true; it can be isolated."""
        self.fused_mask = source_bit(name, SourceBit.FUSED)
        self.rejected_mask = source_bit(name, SourceBit.REJECTED)
        self.isolated_mask = source_bit(name, SourceBit.ISOLATED)
        self.inflated_mask = source_bit(name, SourceBit.NOISE_INFLATED) \
            if name in NOISE_CHECKED else 0
        self.test_ratio = 0.0
        """y²/(g²·S) of the last gated sample (PX4's test ratio; > 1: rejected)."""
        self.rejected = 0
        """Samples rejected so far."""
        self.innovation = 0.0
        """Innovation y of the last gated sample."""
        self.variance = 0.0
        """Its variance S."""
        self.gate_width = math.inf
        """Half-width g·√S of the gate the last fused sample passed (inf: none yet)."""
        self.window = InnovationWindow()
        """The bias test's innovations over ``reset_timeout`` (fault layer)."""
        self.last_fused = -math.inf
        """Time of the last fusion (a height source's: that aided the height)."""
        self.last_gated = -math.inf
        """Time of the last sample gated (its innovation and variance are the last ones)."""
        self.rejected_since: float | None = None
        """Time of the first of the current run of rejections (None: last sample fused)."""
        self.biased = False
        """The last bias test found the source biased (the test's hysteresis)."""
        self.noisy = False
        """Its noise is still being learnt, found well above the stated or not stated
        (:mod:`~altfusion.estimators.noise_check`): its rejections may be its noise's, so it
        is neither isolated nor rejected by the bias test for them."""
        self.shown: Any = None                    # (noise_check imports this module)
        """The fault layer's check of a paper filter's stated noise against its innovations
        (:class:`~altfusion.estimators.noise_check.ShownNoise`; None: unchecked, or checked
        by the estimator itself)."""
        self.bits = 0
        """This source's bits of ``status``."""

    @property
    def isolated(self) -> bool:
        """True while the source is isolated (declared faulty)."""
        return bool(self.bits & self.isolated_mask)

    def fused(self, now: float, aids_height: bool) -> None:
        """A sample of this source is fused at ``now``; it aids the height if it is a height
        source and ``aids_height``."""
        self.rejected_since = None
        self.bits = self.fused_mask | (self.bits & self.inflated_mask)
        if aids_height or not self.height:
            self.last_fused = now

    def refused(self) -> None:
        """A sample of this source is rejected (counted); an isolated source stays so, and
        a source whose noise is inflated stays flagged."""
        self.rejected += 1
        self.bits = self.rejected_mask | (self.bits & (self.isolated_mask | self.inflated_mask))

    def isolate(self) -> None:
        self.bits |= self.isolated_mask

    def rejudge(self) -> None:
        """Withdraw the fault layer's verdict on this source (it was judged against a stuck
        source: :meth:`~altfusion.estimators.gating.Gating.restart_without`): its bias
        window, bias, isolation and run of rejections forgotten."""
        self.window.clear()
        self.biased = False
        self.rejected_since = None
        self.bits &= ~self.isolated_mask

    def mark_inflated(self, inflated: bool) -> None:
        """Set (or clear) the source's ``NOISE_INFLATED`` bit
        (:mod:`~altfusion.estimators.noise_check`)."""
        self.bits = (self.bits | self.inflated_mask) if inflated \
            else (self.bits & ~self.inflated_mask)
