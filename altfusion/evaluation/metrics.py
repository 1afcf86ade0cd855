"""The metrics of ``altfusion evaluate``, per run of one estimator in one scenario, and their
summary over runs.

Every metric works on the recorded series of one run: time t, the error e = h_est - truth, the
estimator's ``h_std``, ``h_valid`` and ``status`` (the bit field of
:mod:`altfusion.estimators.base`). Rows before the estimator is initialized (status bit
INITIALIZED clear: no sample fused yet, ``h_est`` a placeholder) take no part in the error
metrics.

* Start-up: the first :data:`STARTUP_TIME` s after the estimator's first initialized row,
  the time it is given to converge from its initial guess (and its first samples) before its
  error says anything about how it tracks.
* RMS over the initialized rows, start-up and fault reaction included (what they cost); the
  RMS of a cell over its runs is :func:`altfusion.scores.pooled_rms`
  (:data:`altfusion.scores.RMS_DEFINITION`), the same as ``altfusion report``'s.
* max |e| over the initialized rows after the start-up.
* Coverage: the fraction of initialized rows with |e| <= 2 h_std, outside the fault transient
  [start, start + transient) (the fault suite's honesty criterion: 85 % to 99.5 %).
* Valid fraction: the fraction of all rows with ``h_valid`` true.
* Time to isolate (fault scenarios): from the fault start to the first row where the status
  bit ISOLATED of every faulty source the estimator reads is set; inf if that never happens;
  None (n/a) when the estimator reads none of the faulty sources.
* Time to recover (fault scenarios): the error counts as recovered once its trailing RMS over
  :data:`RECOVERY_WINDOW` s stays within 3x the estimator's nominal RMS (its RMS in the same
  flight without the fault) to the end of the run, or the estimator declares its output
  invalid (``h_valid`` false, which the fault suite accepts instead of a recovery). Only rows
  after the fault start and after the start-up count; the time is measured from the later of
  the two to the end of the last bad row; 0 if the error never left the bound, inf if it is
  out of bounds and valid at the end.
"""

import math
from dataclasses import dataclass

import numpy as np

from altfusion import scores
from altfusion.estimators.health import SourceBit, Status, source_bit
from altfusion.scores import RECOVERY_FACTOR, pooled_rms

RECOVERY_WINDOW = 2.0
"""Seconds of the trailing RMS the recovery looks at: a single noise sample beyond 3x the
nominal RMS (0.27 % of Gaussian samples) is no failure to recover; 2 s of them are."""

STARTUP_TIME = 30.0
"""Seconds after an estimator's first initialized row that are its start-up: the 30 s the
fault suite gives an error to come back after a fault (docs/faults.md), given here to settle
from the initial guess. Without it max |e| is the initial transient (e.g. a filter started
on the first baro sample before its bias is known) and a fault starting at 0 s is 'recovered'
only when the start-up ends."""


@dataclass(frozen=True)
class Fault:
    """What a fault scenario tells the metrics: when the fault starts (s), which sources
    should be isolated, and how long after the start the coverage ignores (s)."""

    start: float
    faulty: tuple[str, ...] = ()
    transient: float = 0.0


@dataclass(frozen=True)
class Series:
    """The recorded series of one estimator in one run (equal lengths)."""

    time: np.ndarray
    error: np.ndarray
    h_std: np.ndarray
    h_valid: np.ndarray
    status: np.ndarray

    @property
    def initialized(self) -> np.ndarray:
        return (self.status.astype(np.int64) & int(Status.INITIALIZED)) != 0

    @property
    def startup_end(self) -> float:
        """Time the start-up ends: :data:`STARTUP_TIME` after the first initialized row
        (inf if the estimator never initializes)."""
        rows = np.flatnonzero(self.initialized)
        return float(self.time[rows[0]]) + STARTUP_TIME if rows.size else math.inf

    @property
    def settled(self) -> np.ndarray:
        """The initialized rows after the start-up."""
        return self.initialized & (self.time >= self.startup_end)


@dataclass(frozen=True)
class RunMetrics:
    """The metrics of one run (see the module docstring); None: not applicable."""

    rms: float
    max_abs: float
    coverage: float
    valid_fraction: float
    time_to_isolate: float | None = None
    time_to_recover: float | None = None


def rms(series: Series) -> float:
    """RMS error over the initialized rows (nan if there is none, or a non-finite error)."""
    error = series.error[series.initialized]
    return float(np.sqrt(np.mean(error**2))) if error.size else math.nan


def max_abs(series: Series) -> float:
    """Largest |error| after the start-up (nan if the run ends within it)."""
    error = series.error[series.settled]
    return float(np.max(np.abs(error))) if error.size else math.nan


def transient_windows(fault: Fault | None) -> tuple[tuple[float, float], ...]:
    """The fault transient [start, start + transient) as :mod:`altfusion.scores` windows."""
    if fault is None or fault.transient <= 0.0:
        return ()
    return ((fault.start, fault.start + fault.transient),)


def coverage(series: Series, fault: Fault | None = None) -> float:
    """Fraction of initialized rows outside the transient with |e| <= 2 h_std
    (:func:`altfusion.scores.coverage` over the initialized rows: an estimate declared
    invalid still claims its h_std here)."""
    return scores.coverage(series.time, series.error, series.h_std,
                           valid=series.initialized, excluded=transient_windows(fault))


def valid_fraction(series: Series) -> float:
    return float(np.mean(series.h_valid > 0.5)) if series.time.size else math.nan


def time_to_isolate(series: Series, fault: Fault, sources: tuple[str, ...]) -> float | None:
    """Seconds from the fault start until every faulty source in ``sources`` (those the
    estimator reads) is isolated at once; inf if never, None if it reads none of them."""
    faulty = [s for s in fault.faulty if s in sources]
    if not faulty:
        return None
    mask = 0
    for source in faulty:
        mask |= source_bit(source, SourceBit.ISOLATED)
    isolated = (series.status.astype(np.int64) & mask) == mask
    rows = np.flatnonzero(isolated & (series.time >= fault.start))
    return float(series.time[rows[0]] - fault.start) if rows.size else math.inf


def trailing_rms(time: np.ndarray, error: np.ndarray, window: float) -> np.ndarray:
    """RMS of ``error`` over the rows within ``window`` s up to and including each row."""
    squares = np.concatenate(([0.0], np.cumsum(np.nan_to_num(error, nan=np.inf) ** 2)))
    first = np.searchsorted(time, time - window, side="right")
    last = np.arange(1, time.size + 1)
    with np.errstate(invalid="ignore"):
        return np.sqrt((squares[last] - squares[first]) / (last - first))


def time_to_recover(series: Series, fault: Fault, nominal_rms: float) -> float | None:
    """Seconds from the fault start, or the end of the start-up if later, to the end of the
    last valid row after both whose trailing RMS exceeds 3x ``nominal_rms`` (0: never
    exceeded; inf: still exceeded at the end; None: no finite nominal RMS to compare with)."""
    if not math.isfinite(nominal_rms) or nominal_rms <= 0.0:
        return None
    since = max(fault.start, series.startup_end)
    window = trailing_rms(series.time, series.error, RECOVERY_WINDOW)
    bad = ~(window <= RECOVERY_FACTOR * nominal_rms) & (series.h_valid > 0.5) \
        & series.settled & (series.time >= since)
    rows = np.flatnonzero(bad)
    if not rows.size:
        return 0.0
    if rows[-1] == series.time.size - 1:
        return math.inf
    return float(series.time[rows[-1] + 1] - since)


def run_metrics(series: Series, fault: Fault | None = None, sources: tuple[str, ...] = (),
                nominal_rms: float = math.nan) -> RunMetrics:
    """Every metric of one run; the fault metrics only with a ``fault``."""
    return RunMetrics(
        rms=rms(series), max_abs=max_abs(series), coverage=coverage(series, fault),
        valid_fraction=valid_fraction(series),
        time_to_isolate=None if fault is None else time_to_isolate(series, fault, sources),
        time_to_recover=None if fault is None else time_to_recover(series, fault,
                                                                   nominal_rms),
    )


@dataclass(frozen=True)
class Summary:
    """One metric over the runs of a cell: its mean (for the RMS: the RMS over runs,
    :func:`altfusion.scores.pooled_rms`) and the sample standard deviation of the finite
    values, how many runs gave a finite value, and how many runs in all."""

    mean: float
    std: float
    finite: int
    runs: int

    def format(self, digits: int = 3, unit: str = "", percent: bool = False) -> str:
        """'mean ± std unit (n=k)' over the k runs with a finite value, '(n=k of N)' when
        only k of the N runs gave one (e.g. the runs that isolated the fault), 'never'
        when none did."""
        if self.runs == 0:
            return "-"
        if self.finite == 0:
            return "never"
        scale, suffix = (100.0, " %") if percent else (1.0, f" {unit}" if unit else "")
        text = f"{scale * self.mean:.{digits}g}"
        if self.finite > 1:
            text += f" ± {scale * self.std:.{2 if percent else digits}g}"
        text += suffix
        of = f" of {self.runs}" if self.finite < self.runs else ""
        return text + f" (n={self.finite}{of})"


def _finite(values: list[float | None]) -> tuple[np.ndarray, int] | None:
    applicable = [v for v in values if v is not None]
    if not applicable:
        return None
    return np.array([v for v in applicable if math.isfinite(v)], dtype=float), len(applicable)


def summarize(values: list[float | None]) -> Summary | None:
    """Mean and spread of the applicable values (None: the metric is n/a for every run)."""
    found = _finite(values)
    if found is None:
        return None
    finite, runs = found
    mean = float(finite.mean()) if finite.size else math.nan
    std = float(finite.std(ddof=1)) if finite.size > 1 else 0.0
    return Summary(mean, std, int(finite.size), runs)


def summarize_rms(values: list[float | None]) -> Summary | None:
    """The runs' RMS errors summarized as the RMS over runs (:func:`pooled_rms` of their
    squares) with the standard deviation of the per-run RMS."""
    summary = summarize(values)
    found = _finite(values)
    if summary is None or found is None or not found[0].size:
        return summary
    return Summary(pooled_rms(found[0] ** 2), summary.std, summary.finite, summary.runs)
