"""Sample streams as plain arrays, and the clean-up of recorded time stamps.

A :class:`SampleStream` holds one contract stream (``baro``, ``gps``, ``acc``, ``laser``,
``radar``, ``ekf``): strictly increasing sample times in seconds and one array per contract
variable, every value finite. Whatever had to be changed to get there (reordered, duplicated or
non-finite samples, gaps, unit conversions, approximations) is a :class:`LogProblem` in the
log's report; nothing is dropped or changed silently.
"""

from dataclasses import dataclass, field

import numpy as np

GAP_FACTOR = 5.0
"""An interval longer than this many times the stream's median interval is reported as a gap."""


@dataclass(frozen=True)
class LogProblem:
    """One finding about a log: ``kind`` is one of 'missing topic', 'non-monotonic',
    'duplicate', 'gap', 'non-finite', 'invalid', 'unit', 'time stamp', 'approximation',
    'not measured', 'skipped', 'damaged' (the reader's own warnings)."""

    topic: str
    kind: str
    message: str

    def __str__(self) -> str:
        return f"{self.topic}: {self.kind}: {self.message}"


@dataclass
class SampleStream:
    """One stream of samples: ``time`` (s, strictly increasing) and contract-named values.

    ``valid`` (or None for streams that are always valid) is the stream's validity flag, named
    ``valid_name`` in the contract (``gps_fix``, ``laser_valid``...). Values of invalid samples
    are already replaced as the contract says (held, or 0 for the laser)."""

    prefix: str
    topic: str
    time: np.ndarray
    values: dict[str, np.ndarray]
    valid: np.ndarray | None = None
    valid_name: str | None = None
    problems: list[LogProblem] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.time)

    @property
    def names(self) -> tuple[str, ...]:
        """Every contract variable the stream sets, count and time included."""
        valid = (self.valid_name,) if self.valid_name else ()
        return (*self.values, *valid, f"{self.prefix}_count", f"{self.prefix}_time")


OUTLIER_WINDOW = 5
"""Samples in the running median a time stamp is compared with (tolerates steps and runs of
up to two bad stamps)."""
OUTLIER_TOLERANCE_US = 1_000_000
"""A stamp further than this (or ``OUTLIER_PERIODS`` median periods) from the running median
of its neighbours in log order is an outlier."""
OUTLIER_PERIODS = 5


def outlier_stamps(time_us: np.ndarray, topic: str) -> tuple[np.ndarray, list[LogProblem]]:
    """Mask of the plausible stamps (in log order) and what was dropped: a stamp far from the
    running median of its ``OUTLIER_WINDOW`` neighbours (a corrupted stamp, +100000 s) would
    stretch the replay to its time; a real gap in logging moves the median with it."""
    time_us = np.asarray(time_us, dtype=np.int64)
    if len(time_us) < OUTLIER_WINDOW:
        return np.ones(len(time_us), dtype=bool), []
    half = OUTLIER_WINDOW // 2
    padded = np.pad(time_us, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, OUTLIER_WINDOW)
    median = np.median(windows, axis=1)
    steps = np.diff(time_us)
    period = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0
    tolerance = max(OUTLIER_TOLERANCE_US, OUTLIER_PERIODS * period)
    keep = np.abs(time_us - median) <= tolerance
    if keep.all():
        return keep, []
    worst = time_us[~keep][np.argmax(np.abs((time_us - median)[~keep]))]
    return keep, [LogProblem(topic, "bad time stamp",
                             f"{int((~keep).sum())} sample(s) stamped far from their "
                             f"neighbours (worst {worst} us); dropped")]


def clean_order(time_us: np.ndarray, topic: str) -> tuple[np.ndarray, list[LogProblem]]:
    """Indices that put samples in strictly increasing time order, and what that took.

    Samples out of order are sorted (stably, so equal stamps keep their log order); of samples
    with the same time stamp the later one in the log is kept (it carries the newer data)."""
    problems = []
    time_us = np.asarray(time_us, dtype=np.int64)
    backwards = int(np.sum(np.diff(time_us) < 0))
    if backwards:
        problems.append(LogProblem(topic, "non-monotonic",
                                   f"time stamps go backwards {backwards} time(s); samples "
                                   f"sorted by time"))
    order = np.argsort(time_us, kind="stable")
    ordered = time_us[order]
    last_of_run = np.append(ordered[1:] != ordered[:-1], True)[:len(ordered)]
    duplicates = int(np.sum(~last_of_run))
    if duplicates:
        problems.append(LogProblem(topic, "duplicate",
                                   f"{duplicates} sample(s) share a time stamp with a later "
                                   f"one; the later sample is kept"))
    return order[last_of_run], problems


def find_gaps(time_s: np.ndarray, topic: str) -> list[LogProblem]:
    """Report intervals longer than ``GAP_FACTOR`` times the median interval."""
    if len(time_s) < 3:
        return []
    intervals = np.diff(time_s)
    median = float(np.median(intervals))
    long = np.flatnonzero(intervals > GAP_FACTOR * median)
    if not len(long):
        return []
    worst = long[np.argmax(intervals[long])]
    return [LogProblem(topic, "gap",
                       f"{len(long)} interval(s) longer than {GAP_FACTOR:g} x the median "
                       f"{median:.4g} s; longest {intervals[worst]:.4g} s after "
                       f"t = {time_s[worst]:.4g} s")]


def drop_non_finite(values: dict[str, np.ndarray], topic: str,
                    ) -> tuple[np.ndarray, list[LogProblem]]:
    """A mask of samples whose values are all finite, and a report of those that are not."""
    keep = np.ones(len(next(iter(values.values()))), dtype=bool)
    problems = []
    for name, array in values.items():
        bad = ~np.isfinite(np.asarray(array, dtype=float))
        if bad.any():
            problems.append(LogProblem(topic, "non-finite",
                                       f"{int(bad.sum())} sample(s) with non-finite {name}"))
            keep &= ~bad
    return keep, problems


def hold_invalid(values: np.ndarray, valid: np.ndarray, initial: float = 0.0) -> np.ndarray:
    """Values with each invalid sample replaced by the last valid one (``initial`` before any):
    the contract's "a measurement that is not currently valid keeps its last value"."""
    index = np.where(valid, np.arange(len(values)), -1)
    last_valid = np.maximum.accumulate(index) if len(index) else index
    held = np.asarray(values, dtype=float)[np.maximum(last_valid, 0)]
    return np.where(last_valid >= 0, held, initial)
