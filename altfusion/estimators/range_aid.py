"""PX4 EKF2's conditional range aid on the vertical axis: a rangefinder used as the height
where it is consistent with flat terrain.

An estimator that fuses a rangefinder as z = h - t, with the terrain height t a random walk
(the terrain under a vehicle that moves), cannot take more from a precise rangefinder than
the terrain's walk lets it: the height stays at the level of the coarse absolute sources (a
5 mm laser at 15 m over flat ground, the height at the baro's 0.2 m). PX4 EKF2 uses the
rangefinder as its height where the terrain under it can be taken as flat (EKF2_RNG_CTRL 1,
"conditional range aid"): the horizontal speed below EKF2_RNG_A_VMAX, the height above ground
below EKF2_RNG_A_HMAX, and the range kinematically consistent with the vertical velocity
(its ``RangeFinderConsistencyCheck``: the range rate from successive samples against the
vertical speed, normalized by their uncertainty, low-pass filtered and gated by
EKF2_RNG_K_GATE).

Here, on the vertical axis only, the aid is *active* while a rangefinder

* reads within the height limit ``max_height`` (off above it; on again below it less
  ``hysteresis``),
* is kinematically consistent: over spans of at least :data:`RATE_SPAN`, its rate
  ṙ = Δz/Δt against the estimator's vertical speed v (before that sample's fusion),
  normalized, s = (ṙ - v)/√max(2R/Δt² + P_vv, :data:`RATE_FLOOR`²) (R: the noise
  variance in use, the noise check's factor on the stated or typical one), low-pass
  filtered with the time constant :data:`TAU`, |s̄| < :data:`GATE`,

and every rangefinder within its height limit (gated within :data:`STALE`) is consistent,
passed its gate with its last sample and is not isolated, and no height source has its
noise flagged as inflated (:mod:`~altfusion.estimators.noise_check`: a terrain estimate made
from sources stated too precise is itself too confident, and held it would keep its error
under a small variance; measured on xu2016_hover15 with every noise stated 5x too small,
coverage 0.79 and 0.45 on two seeds with the aid held regardless, 0.87 and 0.71 without),
all of it for :data:`HOLD` without a break. It stops at once when one condition fails.
While it is active the terrain is flat: the estimator holds its terrain state (no process
noise on t), so the rangefinder pins the height against a terrain that the absolute sources
(GNSS, baro) keep averaging; outside it the terrain walks again.

Deviations from PX4 EKF2:

* no horizontal-speed condition (EKF2_RNG_A_VMAX): the estimator has no horizontal state;
  the flatness is judged on the range alone;
* the height limit defaults to 25 m (xu2016's laser switch height), not EKF2_RNG_A_HMAX's
  5 m: the consistency check and the gate, not the height, judge the terrain here;
* the rangefinder is not switched in as a separate height measurement with its own bias
  estimator; the terrain state of the joint filter is held instead, so that nothing jumps
  when the aid starts or stops (PX4 PR #18864: switching in and out of range aid
  accumulated an offset);
* the rate innovation's standard deviation is at least :data:`RATE_FLOOR`;
* the aid needs :data:`HOLD` of consistency before it starts (a consistent sample just after
  a terrain change is no evidence of flatness).
"""

import math
from typing import Final

from altfusion.estimators.aid_source import AidSource
from altfusion.estimators.restorable import Restorable

RATE_SPAN: Final = 0.2
"""Shortest time between the two samples of a range rate, s: a 5 mm laser's rate is then
known to 0.035 m/s (√2·0.005/0.2); at 100 Hz a rate from successive samples would hold
0.7 m/s of noise."""

TAU: Final = 2.0
"""Time constant of the low-pass filter on the normalized rate innovation s, s. With spans of
RATE_SPAN, s̄ of a consistent rangefinder has the standard deviation √(α/(2 - α)) = 0.23
(α = RATE_SPAN/TAU): beyond :data:`GATE` at 4.4 of it (once in 10⁵ spans)."""

RATE_FLOOR: Final = 0.1
"""Least standard deviation of a rate innovation, m/s: the range rate also moves with what a
vertical model lacks, the vehicle's tilt and its horizontal motion over terrain that is
nearly flat (a 1° slope crossed at 5 m/s moves the range by 0.09 m/s), and a rangefinder
stated too precise (its noise not yet inflated by its noise check, which cannot see it while
the terrain walks) would otherwise never be found consistent."""

GATE: Final = 1.0
"""|s̄| below this: kinematically consistent (PX4 EKF2_RNG_K_GATE's default, 1)."""

HOLD: Final = 1.0
"""The conditions hold this long before the aid starts, s."""

STALE: Final = 1.0
"""A rangefinder not gated for this long no longer counts (stopped, or out of its own
range), s."""


class RangeConsistency(Restorable):
    """PX4's kinematic consistency of one rangefinder: its rate against the vertical speed."""

    __slots__ = ("source", "ratio", "in_limit", "_anchor")

    def __init__(self, source: AidSource) -> None:
        self.source = source
        self.ratio = 0.0
        """s̄: the low-pass filtered normalized rate innovation."""
        self.in_limit = True
        """The last reading was within the height limit (with hysteresis; the first is
        judged against the limit itself)."""
        self._anchor: tuple[float, float] | None = None
        """(time, reading) of the first sample of the present span."""

    def sample(self, now: float, reading: float, noise_variance: float, speed: float,
               speed_variance: float) -> None:
        """A reading of the rangefinder at ``now``: closes a span of at least
        :data:`RATE_SPAN` and filters its normalized rate innovation."""
        anchor = self._anchor
        if anchor is None:
            self._anchor = (now, reading)
            return
        span = now - anchor[0]
        if span < RATE_SPAN * (1.0 - 1e-9):
            return
        self._anchor = (now, reading)
        variance = max(2.0 * noise_variance / (span * span) + max(speed_variance, 0.0),
                       RATE_FLOOR * RATE_FLOOR)
        innovation = (reading - anchor[1]) / span - speed
        normalized = innovation / math.sqrt(variance) if variance > 0.0 else 0.0
        self.ratio += (normalized - self.ratio) * min(span / TAU, 1.0)

    def restart(self) -> None:
        """Out of range or gone: the next reading starts a new span, the filter from 0."""
        self._anchor = None
        self.ratio = 0.0

    @property
    def consistent(self) -> bool:
        return abs(self.ratio) < GATE


class RangeAid(Restorable):
    """The conditional range aid of one estimator over its rangefinders."""

    __slots__ = ("max_height", "hysteresis", "checks", "heights", "active", "_since")

    def __init__(self, rangefinders: tuple[AidSource, ...], heights: tuple[AidSource, ...],
                 max_height: float, hysteresis: float) -> None:
        self.max_height = max_height
        """The aid is off where a rangefinder reads more than this, m."""
        self.hysteresis = hysteresis
        """Back on below ``max_height`` less this, m."""
        self.checks = {source.name: RangeConsistency(source) for source in rangefinders}
        self.heights = heights
        """Every height source: none may have its noise inflated (flagged) for the aid."""
        self.active = False
        """The rangefinder is the height: the terrain is held."""
        self._since: float | None = None
        """Time from which the conditions held without a break."""

    def sample(self, name: str, now: float, reading: float, noise_variance: float,
               speed: float, speed_variance: float) -> None:
        """A reading of rangefinder ``name`` (before its fusion, with the estimator's vertical
        speed and its variance then)."""
        check = self.checks[name]
        top = self.max_height if check.in_limit else self.max_height - self.hysteresis
        check.in_limit = reading <= top
        if check.in_limit:
            check.sample(now, reading, noise_variance, speed, speed_variance)
        else:
            check.restart()

    def update(self, now: float) -> bool:
        """Decide at ``now`` whether the aid is active (the rangefinders gated within
        :data:`STALE` count); True if it changed."""
        used = [c for c in self.checks.values()
                if c.in_limit and now - c.source.last_gated <= STALE]
        holds = bool(used) and all(c.consistent and c.source.bits & c.source.fused_mask
                                   and not c.source.isolated for c in used) and not any(
            source.bits & source.inflated_mask for source in self.heights)
        if not holds:
            self._since = None
            for check in self.checks.values():
                if now - check.source.last_gated > STALE:
                    check.restart()
        elif self._since is None:
            self._since = now
        since = self._since
        active = since is not None and now - since >= HOLD       # (None unless it holds)
        changed = active != self.active
        self.active = active
        return changed
