"""The timing checks of one sensor stream on recorded rows (the convention of
``docs/signals.md``; what each check means for a user: ``docs/timing.md``).

A sensor samples at the instants t_k = sample_offset + k·sample_period strictly after the start
and delivers sample k at its due time t_k + latency, at the end of the step of its own that
contains that time; its ``<prefix>_count`` rises by the number of samples delivered and
``<prefix>_time`` holds the instant of the last of them. From the rows of a result:

* every recorded stamp is an instant (stamp error; jitter: the change of that error from one
  sample to the next); a row whose count rises by n holds the last of n samples, whose
  instants are the stamp and the n - 1 instants before it (a count that rises by more than
  the instants since the previous stamp counts samples twice: duplicated; instants skipped
  by a rise of fewer, or after the last stamp, are samples without a new measurement: allowed
  only while the sensor's validity output says its measurement is invalid, e.g. a GNSS
  outage, and never for a sensor without one);
* each sample first shows in the row at or after its due time, and no later than the row at
  or after the end of the sensor step that contains it (early: before it was due, which is
  also before it was taken when there is no latency; late or lost: after);
* each consumer's input count reaches it no later than the row at or after the time it
  showed plus the consumer's hand-over time (:attr:`~.streams.Consumer.handover`), never
  ahead of the sensor's output; its latency is the time from the sample's instant to that
  row, never less than the declared latency.

Times are compared with a tolerance of :data:`TIME_TOLERANCE` (hosts add floats and print
12-17 digits).
"""

import math
from dataclasses import dataclass, field, replace
from fractions import Fraction

import numpy as np

from altfusion.timing.streams import Consumer, Stream

TIME_TOLERANCE = 1e-6
"""s: two times closer than this are the same time."""

EXAMPLES = 3
"""Instances of each kind of violation spelled out (the rest are counted)."""


@dataclass(frozen=True)
class Schedule:
    """A stream's sampling instants after ``start``, exact, and its sensor's step grid."""

    period: Fraction
    offset: Fraction
    latency: Fraction
    step: float
    start: float

    def instant(self, k: np.ndarray) -> np.ndarray:
        """t_k = offset + k·period, each rounded once to a float."""
        den = math.lcm(self.period.denominator, self.offset.denominator)
        num = self.offset.numerator * (den // self.offset.denominator)
        per = self.period.numerator * (den // self.period.denominator)
        return (num + np.asarray(k, dtype=np.int64) * per) / den

    def nearest(self, t: np.ndarray) -> np.ndarray:
        """Index of the instant nearest to each time."""
        return np.rint((np.asarray(t) - float(self.offset)) / float(self.period)).astype(np.int64)

    def first_index(self) -> int:
        """Index of the first instant strictly after the start."""
        k = math.floor((self.start + TIME_TOLERANCE - float(self.offset)) / float(self.period))
        return max(k + 1, 0)

    def last_due_index(self, end: float) -> int:
        """Index of the last instant due (instant + latency) by ``end``."""
        return math.floor((end + TIME_TOLERANCE - float(self.offset + self.latency))
                          / float(self.period))

    def delivered_by(self, due: np.ndarray) -> np.ndarray:
        """The end of the sensor step that contains each due time (the step grid from the
        start): the latest time the sensor may deliver."""
        steps = np.ceil((due - self.start - TIME_TOLERANCE) / self.step)
        return self.start + np.maximum(steps, 0) * self.step


@dataclass(frozen=True)
class Violation:
    """One kind of breach of the convention in one stream, with its first instances."""

    stream: str
    kind: str
    count: int
    examples: tuple[str, ...]

    def __str__(self) -> str:
        more = f" (and {self.count - len(self.examples)} more)" if self.count > len(
            self.examples) else ""
        return f"{self.stream}: {self.count} {self.kind}: {'; '.join(self.examples)}{more}"


@dataclass(frozen=True)
class Spread:
    """Minimum, mean and maximum of a measured time, s."""

    low: float
    mean: float
    high: float

    @classmethod
    def of(cls, values: np.ndarray) -> "Spread | None":
        return cls(float(values.min()), float(values.mean()), float(values.max())) \
            if values.size else None


@dataclass(frozen=True)
class ConsumerResult:
    """A consumer's view of a stream; ``recorded`` False when its input count is absent."""

    consumer: Consumer
    recorded: bool
    seen: int = 0
    pending: int = 0
    """Samples shown too close to the last row for the hand-over to show."""
    ahead: int = 0
    """Rows in which the consumer's count is ahead of the sensor's."""
    early: int = 0
    late: int = 0
    never: int = 0
    latency: Spread | None = None
    allowed: float = 0.0
    """The largest latency the checks allow, s."""


@dataclass
class StreamResult:
    """What the rows show of one stream, against its schedule."""

    stream: Stream
    recorded: bool
    interval: float = math.nan
    """Median time between rows, s."""
    expected: int = 0
    seen: int = 0
    gaps: int = 0
    duplicated: int = 0
    ahead: int = 0
    """Rows in which the consumer's count is ahead of the sensor's."""
    early: int = 0
    late: int = 0
    stamp_error: float = 0.0
    jitter: float = 0.0
    delay: Spread | None = None
    allowed_delay: tuple[float, float] = (0.0, 0.0)
    consumers: list[ConsumerResult] = field(default_factory=list)
    violations: list[Violation] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.violations

    def violate(self, kind: str, examples: list[str]) -> None:
        if examples:
            self.violations.append(
                Violation(self.stream.name, kind, len(examples), tuple(examples[:EXAMPLES])))


def _row_at_or_after(time: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The first row time >= each t (within the tolerance); inf past the last row."""
    index = np.searchsorted(time, np.asarray(t) - TIME_TOLERANCE, side="left")
    padded = np.append(time, np.inf)
    return padded[index]


def _samples(result: StreamResult, schedule: Schedule, time: np.ndarray, count: np.ndarray,
             stamp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(instant index, row time first showing it) of every sample the count took, and the
    indices of the instants due by the last row that it skipped; checks the count and the
    stamps on the way."""
    name = result.stream.name
    rise = np.diff(count)
    result.violate("count decreases", [f"{count[i]:g} -> {count[i + 1]:g} at {time[i + 1]:g} s"
                                       for i in np.flatnonzero(rise < 0)])
    moved = np.flatnonzero((rise == 0) & (np.abs(np.diff(stamp)) > TIME_TOLERANCE))
    result.violate("stamps changed without a new count",
                   [f"{stamp[i]:.9g} -> {stamp[i + 1]:.9g} s at {time[i + 1]:g} s"
                    for i in moved])
    rows = np.flatnonzero(rise > 0) + 1
    nearest = schedule.nearest(stamp[rows])
    errors = stamp[rows] - schedule.instant(nearest)
    result.violate("stamps off the schedule",
                   [f"{stamp[i]:.9g} s at {time[i]:g} s ({error:+.3g} s from {name}'s instant "
                    f"{instant:.9g} s)" for i, error, instant in
                    zip(rows, errors, schedule.instant(nearest), strict=True)
                    if abs(error) > TIME_TOLERANCE])
    if errors.size:
        result.stamp_error = float(np.abs(errors).max())
        result.jitter = float(np.abs(np.diff(errors)).max()) if errors.size > 1 else 0.0
    previous = np.r_[schedule.first_index() - 1, nearest[:-1]][:nearest.size]
    taken = rise[rows - 1].astype(np.int64)
    spanned = nearest - previous
    twice = taken > spanned
    result.duplicated = int((taken - spanned)[twice].sum())
    result.violate("samples counted twice (the count rose by more than the instants since "
                   "the previous stamp)",
                   [f"+{n} at {time[i]:g} s, stamp {stamp[i]:.9g} s, {max(m, 0)} new instants"
                    for i, n, m in zip(rows[twice], taken[twice], spanned[twice], strict=True)])
    skipped = [np.arange(k0 + 1, k - n + 1) for k0, k, n in
               zip(previous, nearest, taken, strict=True) if k - n > k0]
    indices = np.concatenate([np.arange(k - n + 1, k + 1) for k, n in
                              zip(nearest, taken, strict=True)]) if rows.size else np.array([], int)
    shown = np.repeat(time[rows], taken)
    last = int(nearest[-1]) if rows.size else schedule.first_index() - 1
    skipped.append(np.arange(last + 1, schedule.last_due_index(float(time[-1])) + 1))
    return indices.astype(np.int64), shown, np.concatenate(skipped).astype(np.int64)


def _judge_skipped(result: StreamResult, schedule: Schedule, time: np.ndarray,
                   skipped: np.ndarray, valid: np.ndarray | None) -> None:
    """Instants without a sample: a sensor without a validity output must take every one; one
    with it may skip those at which its measurement was invalid (an outage, out of range),
    judged in the row by which the sample was due."""
    result.gaps = int(skipped.size)
    if not skipped.size:
        return
    instants = schedule.instant(skipped)
    due_rows = np.searchsorted(time, schedule.delivered_by(
        instants + float(schedule.latency)) - TIME_TOLERANCE, side="left")
    stream = result.stream
    if stream.valid is None:
        result.violate(f"samples missing ({stream.fmu} takes every sample: it has no "
                       f"validity output)", [f"instant {t:.9g} s" for t in instants])
    elif valid is None:
        result.notes.append(f"{skipped.size} instants without a new measurement, not judged: "
                            f"record {stream.valid_column} to tell outages from lost samples")
    else:
        lost = valid[np.minimum(due_rows, time.size - 1)] != 0
        result.violate(f"samples missing while {stream.valid} was true",
                       [f"instant {t:.9g} s" for t in instants[lost]])


def check_stream(stream: Stream, time: np.ndarray, columns: dict[str, np.ndarray],
                 step: float | None = None) -> StreamResult:
    """Check ``stream`` on rows ``time`` (s, increasing, the first at the start) and the
    recorded ``columns``; ``step``: the one step the host took for every component (default:
    each component's own step)."""
    count, stamp = columns.get(stream.count_column), columns.get(stream.time_column)
    result = StreamResult(stream, count is not None and stamp is not None)
    if not result.recorded:
        return result
    result.interval = float(np.median(np.diff(time))) if time.size > 1 else math.nan
    schedule = Schedule(stream.period, stream.offset, stream.latency, step or stream.step,
                        float(time[0]))
    finite = np.isfinite(count) & np.isfinite(stamp)
    result.violate("rows without a count or stamp", [f"at {t:g} s" for t in time[~finite]])
    time, count, stamp = time[finite], count[finite], stamp[finite]
    other = {name: values[finite] for name, values in columns.items()}
    if result.interval > float(stream.period) + TIME_TOLERANCE:
        result.notes.append(
            f"rows every {result.interval:g} s, sample period {float(stream.period):g} s: a row "
            f"holds the last of the samples since the row before; the others' instants are "
            f"inferred from the count (record every step: altfusion run --record timing)")
    result.expected = max(schedule.last_due_index(float(time[-1])) - schedule.first_index() + 1,
                          0)
    result.seen = int(count[-1] - count[0])
    indices, shown, skipped = _samples(result, schedule, time, count, stamp)
    _judge_skipped(result, schedule, time, skipped, other.get(stream.valid_column))
    instants = schedule.instant(indices)
    due = instants + float(stream.latency)
    early = shown < due - TIME_TOLERANCE
    allowed = _row_at_or_after(time, schedule.delivered_by(due))
    late = shown > allowed + TIME_TOLERANCE
    result.early, result.late = int(early.sum()), int(late.sum())
    result.violate("samples shown before they were due (instant + latency)",
                   [f"instant {t:.9g} s shown at {s:g} s" for t, s in
                    zip(instants[early], shown[early], strict=True)])
    result.violate("samples late or lost",
                   [f"instant {t:.9g} s shown at {s:g} s, due in the row at {a:g} s"
                    for t, s, a in zip(instants[late], shown[late], allowed[late],
                                       strict=True)])
    if shown.size:
        result.delay = Spread.of(shown - instants)
        result.allowed_delay = (float(stream.latency), float((allowed - instants).max()))
    consumers = stream.consumers if step is None else tuple(
        replace(c, handover=step * (len(c.relays) + 1)) for c in stream.consumers)
    result.consumers = [_check_consumer(result, consumer, time, count, other.get(
        consumer.column), instants, shown, allowed) for consumer in consumers]
    return result


def _check_consumer(result: StreamResult, consumer: Consumer, time: np.ndarray,
                    count: np.ndarray, seen_count: np.ndarray | None, instants: np.ndarray,
                    shown: np.ndarray, delivered_by: np.ndarray) -> ConsumerResult:
    """When ``consumer`` saw each sample (the first row its input count reached it): no
    later than the hand-over after the row that showed it; ``delivered_by``: the row by which
    each sample was due, for the latency allowed."""
    if seen_count is None:
        return ConsumerResult(consumer, recorded=False)
    name = consumer.column
    seen = seen_count - seen_count[0]
    delivered = count - count[0]
    ahead = np.flatnonzero(seen > delivered)
    result.violate(f"rows where {name} is ahead of the sensor's count",
                   [f"{seen_count[i]:g} > {count[i]:g} at {time[i]:g} s" for i in ahead])
    result.violate(f"decreases of {name}",
                   [f"at {time[i + 1]:g} s" for i in np.flatnonzero(np.diff(seen) < 0)])
    ordinal = np.arange(1, shown.size + 1)
    index = np.searchsorted(np.maximum.accumulate(seen), ordinal, side="left")
    at = np.append(time, np.nan)[index]
    allowed = _row_at_or_after(time, shown + consumer.handover)
    never = np.isnan(at) & np.isfinite(allowed)
    late = at > allowed + TIME_TOLERANCE
    result.violate(f"samples {name} never saw",
                   [f"instant {t:.9g} s shown at {s:g} s" for t, s in
                    zip(instants[never], shown[never], strict=True)])
    result.violate(f"samples {name} saw late (hand-over over {consumer.handover:g} s)",
                   [f"instant {t:.9g} s shown at {s:g} s, seen at {a:g} s" for t, s, a in
                    zip(instants[late], shown[late], at[late], strict=True)])
    latency = at - instants
    early = latency < float(result.stream.latency) - TIME_TOLERANCE
    result.violate(f"samples {name} saw before they were due",
                   [f"instant {t:.9g} s seen at {a:g} s" for t, a in
                    zip(instants[early], at[early], strict=True)])
    limit = _row_at_or_after(time, delivered_by + consumer.handover) - instants
    limit = limit[np.isfinite(limit)]
    return ConsumerResult(
        consumer, True, seen=int(np.isfinite(at).sum()), pending=int(
            (np.isnan(at) & ~np.isfinite(allowed)).sum()), ahead=int(ahead.size),
        early=int(early.sum()), late=int(late.sum()),
        never=int(never.sum()), latency=Spread.of(latency[np.isfinite(latency)]),
        allowed=float(limit.max()) if limit.size else 0.0)
