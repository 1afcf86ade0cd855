"""Estimator health in words: the events of a run, derived from the estimators' recorded outputs.

Every estimator reports its health through the same outputs (``docs/estimator_health.md``):
the ``status`` bits, ``h_valid``, ``n_height_resets`` and each source's ``<source>_test_ratio``
(and ``<source>_rejected`` where recorded). The events are read off their changes between
recorded rows, so they come out the same from any host's results (our runner, libcosim,
ECOS, a CSV written elsewhere) and need nothing from inside the FMU:

* ``initialized``: the ``INITIALIZED`` bit is first set;
* ``rejected``: samples of the source rejected by its gate or plausibility bound, counted
  exactly by the increments of ``<source>_rejected`` where it is recorded; else one event per
  row where the source's ``REJECTED`` bit is set and its test ratio changed (a new rejected
  sample; a source sampled faster than the rows are recorded may have had more, so these
  events are not ``exact`` and are said as "in N recorded rows");
* ``isolated``: the source's ``ISOLATED`` bit is set (declared faulty), and ``re-admitted``
  when it is cleared again (its samples pass, or its offset state was re-referenced);
* ``fallback``: at an isolation, the height sources fused and not isolated that carry the
  height from then on (AltitudeEKF's height-reference fallback, PX4 EKF2's, is exactly this:
  the lost source's offset stops being observed and the others keep the height);
* ``height reset``: ``n_height_resets`` increased (the height reset onto the rejected
  source's sample, named where the row shows which);
* ``validity lost`` / ``validity regained``: ``h_valid`` turns false after having been true
  (no height source fused for ``aiding_timeout``: dead reckoning; or a source the algorithm
  cannot do without silent as long: XuSHAEKF's accelerometer), and true again;
* the accelerometer found bad and consistent again (``BAD_ACC_VERTICAL`` set, cleared), a
  source's noise found too small and back (its ``NOISE_INFLATED`` set, cleared), the range
  aid started and stopped (``RANGE_AID`` set, cleared), the motion model's process noise
  raised and back near the stated (``PROCESS_NOISE_ADAPTED`` set, cleared).

A row's time is the end of the output interval in which the change happened.
"""

import csv
import io
import math
from dataclasses import astuple, dataclass, fields
from itertools import groupby
from pathlib import Path

import numpy as np

from altfusion.atomic import write_text
from altfusion.cosim.results import Results
from altfusion.estimators.health import (
    HEIGHT_SOURCES,
    NOISE_CHECKED,
    SOURCES,
    SourceBit,
    Status,
    status_bits,
)

INITIALIZED, REJECTED, ISOLATED, READMITTED = "initialized", "rejected", "isolated", "re-admitted"
FALLBACK, HEIGHT_RESET = "fallback", "height reset"
INVALID, VALID = "validity lost", "validity regained"
BAD_ACC = ("accelerometer found bad (noisier than told, or inconsistent with the height "
           "sources): noise inflated")
GOOD_ACC = "accelerometer consistent again"
NOISE_UP = "noise found too small for its innovations: inflated"
NOISE_OK = "noise back near its stated value"
RANGE_AID_ON = "range aid started: a rangefinder is the height"
RANGE_AID_OFF = "range aid stopped"
RAISED_MOTION = ("motion model found lagging (every source off the prediction): process "
                 "noise raised")
STATED_MOTION = "motion model's process noise back near the stated"

SHOWN_LINES = 12
"""Most lines :func:`format_events` prints per estimator; the rest are counted (all are in
the CSV)."""


@dataclass(frozen=True)
class HealthEvent:
    """One thing an estimator did: at ``time`` (s), ``what`` about ``source`` ('' for the
    estimator as a whole; sources joined by '+' for a fallback), with the source's test
    ratio then (nan where it has none) and how many samples it covers."""

    time: float
    estimator: str
    source: str
    what: str
    test_ratio: float = math.nan
    count: int = 1
    exact: bool = True
    """False: at least ``count`` samples (rejections seen in the recorded rows only)."""


def status_names(value: int) -> list[str]:
    """The names of the ``status`` bits set in ``value`` (``docs/estimator_health.md``)."""
    return [name for name, mask in status_bits().items() if value & mask]


def estimators_in(results: Results) -> list[str]:
    """The components of ``results`` that report health (a recorded ``status``)."""
    return [name[:-len(".status")] for name in results.columns if name.endswith(".status")]


def health_events(results: Results) -> list[HealthEvent]:
    """Every estimator's events in ``results``, in time order (estimators in their column
    order at equal times)."""
    events = [event for name in estimators_in(results)
              for event in _EstimatorHistory(results, name).events()]
    return sorted(events, key=lambda e: e.time)


class _EstimatorHistory:
    """One estimator's recorded health outputs, as integer bits and arrays."""

    def __init__(self, results: Results, name: str) -> None:
        self.name = name
        self.time = results.time
        self.columns = {column[len(name) + 1:]: values for column, values
                        in results.columns.items() if column.startswith(f"{name}.")}
        status = np.nan_to_num(self.columns["status"], nan=0.0)
        self.status = status.astype(np.int64)

    def bit(self, mask: int) -> np.ndarray:
        return (self.status & mask) != 0

    def source_bit(self, source: str, bit: SourceBit) -> np.ndarray:
        return self.bit(status_bits()[f"{source.upper()}_{bit.name}"])

    def ratio(self, source: str, row: int) -> float:
        ratios = self.columns.get(f"{source}_test_ratio")
        return math.nan if ratios is None else float(ratios[row])

    def event(self, row: int, source: str, what: str, count: int = 1,
              exact: bool = True) -> HealthEvent:
        ratio = self.ratio(source, row) if source in SOURCES and what != FALLBACK else math.nan
        return HealthEvent(float(self.time[row]), self.name, source, what, ratio, count, exact)

    def events(self) -> list[HealthEvent]:
        found = []
        initialized = np.flatnonzero(self.bit(Status.INITIALIZED))
        if initialized.size:
            found.append(self.event(int(initialized[0]), "", INITIALIZED))
        for source in SOURCES:
            if f"{source}_test_ratio" in self.columns or self.source_bit(
                    source, SourceBit.FUSED).any():
                found += self.rejections(source)
            found += self.isolations(source)
            if source in NOISE_CHECKED:
                found += self.flag(self.source_bit(source, SourceBit.NOISE_INFLATED), source,
                                   NOISE_UP, NOISE_OK)
        found += self.resets() + self.validity()
        found += self.flag(self.bit(Status.BAD_ACC_VERTICAL), "", BAD_ACC, GOOD_ACC)
        found += self.flag(self.bit(Status.RANGE_AID), "", RANGE_AID_ON, RANGE_AID_OFF)
        found += self.flag(self.bit(Status.PROCESS_NOISE_ADAPTED), "", RAISED_MOTION,
                           STATED_MOTION)
        return found

    def rejections(self, source: str) -> list[HealthEvent]:
        counts = self.columns.get(f"{source}_rejected")
        if counts is not None:
            added = np.diff(np.nan_to_num(counts), prepend=0.0)
            return [self.event(int(row), source, REJECTED, int(added[row]))
                    for row in np.flatnonzero(added > 0)]
        rejected = self.source_bit(source, SourceBit.REJECTED)
        ratios = self.columns.get(f"{source}_test_ratio")
        new = rejected & ~np.concatenate(([False], rejected[:-1]))
        if ratios is not None:
            new |= rejected & (np.diff(ratios, prepend=np.nan) != 0)
        return [self.event(int(row), source, REJECTED, exact=False)
                for row in np.flatnonzero(new)]

    def isolations(self, source: str) -> list[HealthEvent]:
        isolated = self.source_bit(source, SourceBit.ISOLATED).astype(np.int8)
        change = np.diff(isolated, prepend=0)
        found = []
        for row in np.flatnonzero(change):
            row = int(row)
            if change[row] < 0:
                found.append(self.event(row, source, READMITTED))
                continue
            found.append(self.event(row, source, ISOLATED))
            if source not in HEIGHT_SOURCES:       # a stuck GNSS speed or accelerometer
                continue
            carriers = [other for other in HEIGHT_SOURCES if other != source
                        and self.source_bit(other, SourceBit.FUSED)[row]
                        and not self.source_bit(other, SourceBit.ISOLATED)[row]]
            if carriers:
                found.append(self.event(row, "+".join(carriers), FALLBACK))
        return found

    def resets(self) -> list[HealthEvent]:
        counts = self.columns.get("n_height_resets")
        if counts is None:
            reset = self.bit(Status.HEIGHT_RESET)
            added = (reset & ~np.concatenate(([False], reset[:-1]))).astype(float)
        else:
            added = np.diff(np.nan_to_num(counts), prepend=0.0)
        found = []
        for row in np.flatnonzero(added > 0):
            row = int(row)
            onto = next((s for s in HEIGHT_SOURCES
                         if self.source_bit(s, SourceBit.REJECTED)[row]), "")
            found.append(self.event(row, onto, HEIGHT_RESET, int(added[row])))
        return found

    def flag(self, flagged: np.ndarray, source: str, raised: str,
             cleared: str) -> list[HealthEvent]:
        """An event ``raised`` where a status bit (``flagged`` per row) is set, ``cleared``
        where it is cleared again."""
        change = np.diff(flagged.astype(np.int8), prepend=0)
        return [self.event(int(row), source, raised if change[row] > 0 else cleared)
                for row in np.flatnonzero(change)]

    def validity(self) -> list[HealthEvent]:
        valid = self.columns.get("h_valid")
        if valid is None:
            valid = self.bit(Status.INITIALIZED) & ~self.bit(Status.DEAD_RECKONING)
        valid = np.nan_to_num(np.asarray(valid, dtype=float)) > 0.5
        first = np.flatnonzero(valid)
        if not first.size:
            return []
        change = np.diff(valid[first[0]:].astype(np.int8))
        return [self.event(int(first[0] + 1 + row), "", VALID if change[row] > 0 else INVALID)
                for row in np.flatnonzero(change)]


# ----------------------------------------------------------------------------- words
def _line(group: list[HealthEvent]) -> str:
    first, last = group[0], group[-1]
    count = sum(e.count for e in group)
    ratios = [e.test_ratio for e in group if math.isfinite(e.test_ratio)]
    source = first.source.replace("+", ", ")
    subject = {FALLBACK: f"height carried by {source}",
               HEIGHT_RESET: f"height reset{' onto ' + source if source else ''}"}.get(
        first.what, f"{first.what} {source}".strip())
    if count == 1:
        ratio = f" (test ratio {ratios[0]:.3g})" if ratios else ""
        return f"    {first.time:7.2f} s  {subject}{ratio}"
    ratio = f" (test ratio up to {max(ratios):.3g})" if ratios else ""
    span = (f"between {first.time:.1f} and {last.time:.1f} s" if last.time > first.time
            else f"at {first.time:.1f} s")
    if not all(e.exact for e in group):
        return f"    {first.time:7.2f} s  {subject} in {count} recorded rows {span}{ratio}"
    return f"    {first.time:7.2f} s  {count} x {subject} {span}{ratio}"


def group_events(events: list[HealthEvent]) -> list[list[HealthEvent]]:
    """Runs of the same event of one estimator and source with no other event of that
    estimator and source between them, ordered by their first time."""
    groups = []
    for _key, stream in groupby(sorted(events, key=lambda e: (e.estimator, e.source)),
                                key=lambda e: (e.estimator, e.source)):
        ordered = sorted(stream, key=lambda e: e.time)
        groups += [list(run) for _what, run in groupby(ordered, key=lambda e: e.what)]
    return sorted(groups, key=lambda g: g[0].time)


def format_events(events: list[HealthEvent], where: str = "",
                  shown: int = SHOWN_LINES) -> str:
    """The events in words, estimator by estimator: one line per event or run of repeated
    events (``12 x rejected gps between 130.0 and 141.2 s``), at most ``shown`` lines each;
    ``where``: the file holding them all."""
    held = f" (all in {where})" if where else ""
    if not events:
        return f"health events: none{held}"
    text = [f"health events{held}:"]
    for estimator in dict.fromkeys(e.estimator for e in events):
        lines = [_line(g) for g in group_events([e for e in events if e.estimator == estimator])]
        text += [f"  {estimator}"] + lines[:shown]
        if len(lines) > shown:
            text.append(f"    ... {len(lines) - shown} more line(s)")
    return "\n".join(text)


COLUMNS = tuple(f.name for f in fields(HealthEvent))


def events_csv(events: list[HealthEvent], extra: dict[str, list] | None = None) -> str:
    """The events as CSV text (``time,estimator,source,what,test_ratio,count,exact``, with
    the ``extra`` columns first, one value per event)."""
    extra = extra or {}
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([*extra, *COLUMNS])
    for index, event in enumerate(events):
        writer.writerow([*(values[index] for values in extra.values()),
                         *(f"{v:.10g}" if isinstance(v, float) else int(v) if isinstance(v, bool)
                           else v for v in astuple(event))])
    return buffer.getvalue()


def write_events(events: list[HealthEvent], path: Path,
                 extra: dict[str, list] | None = None) -> Path:
    """Write :func:`events_csv` to ``path`` (atomically)."""
    return write_text(Path(path), events_csv(events, extra))
