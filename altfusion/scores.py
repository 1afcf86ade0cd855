"""Scores of an estimate against the truth: honesty of h_std, time to isolate a faulty
source, recovery after a fault (docs/faults.md's pass criteria, docs/estimator_health.md).

Every function takes the recorded arrays of one run (time, error = h_est - h, h_std,
h_valid, status) on one time grid; a window is a half-open interval [start, end) of time.
Samples where the estimator says its output is not valid (``h_valid`` false) claim nothing:
they count in neither the coverage nor the recovery RMS.
"""

import math

import numpy as np

from altfusion.estimators.health import SourceBit, source_bit

COVERAGE_SIGMAS = 2.0
"""|e| <= 2 h_std: 95.4 % of the time for a Gaussian error with an honest h_std."""

HONEST_COVERAGE = (0.85, 0.995)
"""docs/faults.md: the coverage of an honest h_std lies between 85 % and 99.5 %."""

RECOVERY_FACTOR = 3.0
"""docs/faults.md: after a fault the error returns within 3x its nominal RMS."""


def outside(time: np.ndarray, windows: tuple[tuple[float, float], ...]) -> np.ndarray:
    """Mask of the samples of ``time`` outside every window [start, end)."""
    mask = np.ones(len(time), dtype=bool)
    for start, end in windows:
        mask &= ~((time >= start) & (time < end))
    return mask


def coverage(time: np.ndarray, error: np.ndarray, h_std: np.ndarray,
             valid: np.ndarray | None = None,
             excluded: tuple[tuple[float, float], ...] = ()) -> float:
    """Fraction of the valid samples outside the ``excluded`` windows (fault transients)
    where |error| <= 2 h_std; NaN if there is no such sample."""
    mask = outside(time, excluded)
    if valid is not None:
        mask &= np.asarray(valid) > 0.5
    if not mask.any():
        return math.nan
    within = np.abs(error[mask]) <= COVERAGE_SIGMAS * h_std[mask]
    return float(np.mean(within))


def isolation_time(time: np.ndarray, status: np.ndarray, source: str,
                   start: float) -> float | None:
    """Seconds from ``start`` to the first sample at or after it whose ``status`` has
    ``source``'s ISOLATED bit, or None if it never does."""
    bit = source_bit(source, SourceBit.ISOLATED)
    flagged = (time >= start) & ((np.asarray(status).astype(np.int64) & bit) != 0)
    if not flagged.any():
        return None
    return float(time[np.argmax(flagged)] - start)


def rms(error: np.ndarray, mask: np.ndarray) -> float:
    """RMS of ``error`` over ``mask``; NaN if the mask is empty."""
    return float(np.sqrt(np.mean(error[mask] ** 2))) if mask.any() else math.nan


RMS_DEFINITION = ("RMS over runs: the square root of the mean, over the runs, of each run's "
                  "mean squared error (h_est - truth) over the rows where the estimator is "
                  "initialized (status bit INITIALIZED; every row when no status is "
                  "recorded); each run weighs the same")
"""The one RMS of an estimator over several runs, on every page (``altfusion evaluate``'s
page and table, ``altfusion report``'s table): :func:`pooled_rms` of the runs' mean
squares."""


def pooled_rms(mean_squares: np.ndarray) -> float:
    """The RMS over runs (:data:`RMS_DEFINITION`) from each run's mean squared error; NaN
    without a run or with a non-finite run."""
    mean_squares = np.asarray(mean_squares, dtype=float)
    return float(np.sqrt(np.mean(mean_squares))) if mean_squares.size else math.nan


def window_rms(time: np.ndarray, error: np.ndarray, valid: np.ndarray | None,
               start: float, end: float = math.inf) -> float:
    """RMS of the valid samples of ``error`` in [start, end); NaN if there is none."""
    mask = (time >= start) & (time < end)
    if valid is not None:
        mask &= np.asarray(valid) > 0.5
    return rms(error, mask)


def recovered(time: np.ndarray, error: np.ndarray, valid: np.ndarray,
              nominal_error: np.ndarray, nominal_valid: np.ndarray,
              after: float, end: float = math.inf) -> tuple[bool, float, float]:
    """Whether the error is back within :data:`RECOVERY_FACTOR` times its nominal RMS over
    [after, end): (passed, RMS of the faulty run's valid samples, nominal RMS over the same
    window). A run whose output is invalid over the whole window passes (``h_valid`` false
    is an honest answer)."""
    faulty = window_rms(time, error, valid, after, end)
    nominal = window_rms(time, nominal_error, nominal_valid, after, end)
    if math.isnan(faulty):
        return True, faulty, nominal
    return bool(faulty <= RECOVERY_FACTOR * nominal), faulty, nominal


MAX_HEIGHT_RESETS = 1
"""docs/faults.md, ``all_fail`` (PX4 EKF2's *AllHgtFailReset*): at most one height reset."""


def follows_reference(time: np.ndarray, error: np.ndarray, resets: np.ndarray,
                      nominal_error: np.ndarray, nominal_valid: np.ndarray,
                      reference_offset: float, start: float, after: float,
                      ) -> tuple[bool, str]:
    """docs/faults.md's ``all_fail`` criterion for an estimator whose height reference is a
    failed source and which has no third height sensor in range (PX4 EKF2's
    *AllHgtFailReset*): from ``after`` on, the RMS error within ``reference_offset`` (the
    reference's own offset) plus :data:`RECOVERY_FACTOR` times the nominal RMS over the
    same window, at most :data:`MAX_HEIGHT_RESETS` height reset (``resets``: the
    estimator's reset counter) from ``start`` on, no NaN; ``h_valid`` may stay true.
    (passed, what was measured)."""
    if not np.all(np.isfinite(error)):
        return False, "NaN or infinite error"
    window = time >= after
    nominal = window_rms(time, nominal_error, nominal_valid, after)
    faulty = rms(error, window)
    bound = abs(reference_offset) + RECOVERY_FACTOR * nominal
    resets = np.asarray(resets)
    before = resets[time < start]
    reset_count = int(resets[-1] - (before[-1] if before.size else 0.0))
    passed = faulty <= bound and reset_count <= MAX_HEIGHT_RESETS
    return bool(passed), (f"RMS {faulty:.3g} m against |offset| {abs(reference_offset):g} m + "
                          f"3 x nominal {nominal:.3g} m = {bound:.3g} m; {reset_count} height "
                          f"reset(s)")
