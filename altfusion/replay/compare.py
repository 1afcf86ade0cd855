"""Estimators against PX4 EKF2, the raw sensors and the rangefinder, after a replay run.

Everything is read from the recorded results (one row per base step): a new sample of a
stream is a row where ``replay.<prefix>_count`` increased. Statistics are taken from
``settle_time`` on, :data:`SETTLE_TIME` after the first valid GPS sample, once the estimators
have learnt the baro offset (the learning transients are in the plot, not in the numbers).

* vs EKF2, at each valid EKF2 sample: d = h_est - ekf_h. Both are MSL, but in different
  realisations of it: the estimators follow the GNSS altitude (their bias states absorb the baro
  offset), EKF2 (height reference: baro) holds the GNSS altitude of its origin and then follows
  the baro. ``mean`` is therefore mostly that datum difference, compared in the table with
  mean(gps_h - ekf_h); ``std`` is d in the common datum (mean removed); ``rms`` and ``max``
  are of d as it is.
* GPS innovations, at each valid GPS sample: gps_h - h_est of the row before (the prior);
  ``nis`` is their mean square over h_std² + gps_epv² (1 for a consistent filter).
* baro residuals, at each baro sample: baro_h - h_est (mean: the baro offset; std: scatter).
* rangefinder, at each valid sample: h_est - laser_h (or radar_h), the ground's MSL height the
  estimate implies: over flat ground its std is the estimate's relative height error plus the
  terrain's roughness and the rangefinder's noise.
* valid: the fraction of rows from ``start`` on where the estimate is valid: the estimator's
  own ``h_valid`` where it has one, else where a height sample (baro, GPS with a fix, a valid
  rangefinder sample) arrived at most ``AIDING_TIMEOUT`` s before. The replay stops where the
  log's sensor data stop (:func:`~altfusion.replay.extract.extract_streams`).
* diverged: flagged when, at some row from ``start`` on, the estimate is further than
  ``DIVERGENCE_BOUND`` from every height sensor (GPS, the baro moved into the GPS datum by
  its median offset, and the baro as it reads: an estimator whose height reference is the
  baro, AltitudeEKF with ``height_ref`` baro, gives its height in the baro's datum), or its
  ``h_std`` exceeds that bound.
"""

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.atomic import write_text
from altfusion.cosim.results import Results

REPLAY = "replay"
EKF2 = "PX4 EKF2 (reference)"
"""The name of EKF2's own row in the comparison."""
SETTLE_TIME = 5.0
"""Offset-learning time after the first valid GPS sample, s: 25 GPS samples at 5 Hz bring the
bias σ of the replay tuning to ~√(0.6² + 0.8²)/√25 = 0.2 m; Whang's alpha-beta filter, which
starts before its bias is known, is settled after 1.6 s on the Auterion log."""


AIDING_TIMEOUT = 5.0
"""Seconds without a height sample after which an estimate without ``h_valid`` counts as
invalid (PX4 EKF2's default aiding timeout)."""
DIVERGENCE_BOUND = 50.0
"""m: ten times a consumer GNSS receiver's vertical 1-sigma error (about 5 m) and far beyond
the baro's scatter about the GPS datum (< 2 m on the bundled logs): an estimate this far from
every height sensor, or this unsure, has left the flight."""


@dataclass(frozen=True)
class Stats:
    """Mean, standard deviation, RMS and max |x| of a set of differences, and their number."""

    mean: float
    std: float
    rms: float
    max_abs: float
    n: int

    @classmethod
    def of(cls, values: np.ndarray) -> "Stats":
        values = np.asarray(values, dtype=float)
        if not len(values):
            return cls(*(4 * (float("nan"),)), 0)
        return cls(float(values.mean()), float(values.std()),
                   float(np.sqrt(np.mean(values**2))), float(np.max(np.abs(values))),
                   len(values))


@dataclass(frozen=True)
class EstimatorReport:
    """How one estimate (an estimator's h_est or EKF2's ekf_h) compares."""

    name: str
    vs_ekf: Stats
    gps_innovation: Stats
    nis: float
    baro_residual: Stats
    ground: Stats
    rejected: int | None
    valid_fraction: float = float("nan")
    diverged: str = ""
    """Why the estimate counts as diverged ('' if it does not)."""


def new_sample_rows(results: Results, prefix: str, valid: str | None = None) -> np.ndarray:
    """Rows at which a new ``prefix`` sample arrived (and, if given, its flag is true)."""
    count = results[f"{REPLAY}.{prefix}_count"]
    rows = np.flatnonzero(np.diff(count, prepend=0.0) > 0)
    if valid is not None:
        rows = rows[results[f"{REPLAY}.{valid}"][rows] > 0.5]
    return rows


def settle_time(results: Results) -> float:
    """``SETTLE_TIME`` after the first valid GPS sample (the start if there is none)."""
    rows = new_sample_rows(results, "gps", "gps_fix")
    return float(results.time[rows[0]]) + SETTLE_TIME if len(rows) else float(results.time[0])


def range_prefix(results: Results) -> str | None:
    """'laser' or 'radar', whichever delivered valid samples (None: no rangefinder)."""
    for prefix in ("laser", "radar"):
        if f"{REPLAY}.{prefix}_count" in results.columns and \
                len(new_sample_rows(results, prefix, f"{prefix}_valid")):
            return prefix
    return None


def _held(results: Results, prefix: str, value: str, valid: str | None) -> np.ndarray:
    """Per row, the last ``prefix`` sample's ``value`` (NaN before the first usable one)."""
    rows = new_sample_rows(results, prefix, valid) if f"{REPLAY}.{prefix}_count" in \
        results.columns else np.array([], dtype=int)
    held = np.full(len(results.time), np.nan)
    if len(rows):
        index = np.searchsorted(rows, np.arange(len(results.time)), side="right") - 1
        held[index >= 0] = results[f"{REPLAY}.{value}"][rows[index[index >= 0]]]
    return held


def aided_rows(results: Results) -> np.ndarray:
    """Rows at which a height sample arrived at most ``AIDING_TIMEOUT`` s before."""
    last = np.full(len(results.time), -np.inf)
    for prefix, valid in (("baro", None), ("gps", "gps_fix"), ("laser", "laser_valid"),
                          ("radar", "radar_valid")):
        if f"{REPLAY}.{prefix}_count" not in results.columns:
            continue
        rows = new_sample_rows(results, prefix, valid)
        if len(rows):
            index = np.searchsorted(rows, np.arange(len(results.time)), side="right") - 1
            seen = np.where(index >= 0, results.time[rows[np.maximum(index, 0)]], -np.inf)
            last = np.maximum(last, seen)
    return results.time - last <= AIDING_TIMEOUT


def divergence(results: Results, h: np.ndarray, h_std: np.ndarray | None,
               after: np.ndarray) -> str:
    """Why ``h`` counts as diverged from ``after`` on ('' if it does not)."""
    gps = _held(results, "gps", "gps_h", "gps_fix")
    baro = _held(results, "baro", "baro_h", None)
    both = np.isfinite(gps) & np.isfinite(baro)
    offset = float(np.median(baro[both] - gps[both])) if both.any() else 0.0
    distance = np.fmin(np.abs(h - gps), np.fmin(np.abs(h - (baro - offset)), np.abs(h - baro)))
    distance = np.where(np.isfinite(h), distance, np.inf)[after]
    distance[np.isnan(distance)] = 0.0                  # no height sensor yet: nothing to say
    if len(distance) and distance.max() > DIVERGENCE_BOUND:
        worst = int(np.argmax(distance))
        return (f"|h - sensors| {distance[worst]:.4g} m at "
                f"{results.time[after][worst]:.1f} s")
    if h_std is not None and len(h_std[after]) and not np.max(h_std[after]) <= \
            DIVERGENCE_BOUND:
        return f"h_std {np.max(h_std[after]):.4g} m"
    return ""


def compare(results: Results, estimate: str, name: str, start: float) -> EstimatorReport:
    """Statistics of the column ``estimate`` (e.g. 'BaselineKF.h_est') from ``start`` on."""
    h = results[estimate]
    after = results.time >= start
    ekf = new_sample_rows(results, "ekf", "ekf_valid")
    ekf = ekf[after[ekf]]
    gps = new_sample_rows(results, "gps", "gps_fix")
    gps = gps[after[gps] & (gps > 0)]
    prior = h[gps - 1]
    innovation = results[f"{REPLAY}.gps_h"][gps] - prior
    component = estimate.split(".", 1)[0]
    std_column = f"{component}.h_std" if component != REPLAY else None
    h_var = results[std_column][gps - 1] ** 2 if std_column in results.columns else 0.0
    variance = h_var + results[f"{REPLAY}.gps_epv"][gps] ** 2
    nis = float(np.mean(innovation**2 / variance)) if len(gps) else float("nan")
    baro = new_sample_rows(results, "baro")
    baro = baro[after[baro]]
    ground = np.array([])
    prefix = range_prefix(results)
    if prefix is not None:
        rows = new_sample_rows(results, prefix, f"{prefix}_valid")
        rows = rows[after[rows]]
        ground = h[rows] - results[f"{REPLAY}.{prefix}_h"][rows]
    rejected = results.columns.get(f"{component}.n_rejected")
    h_valid = results.columns.get(f"{component}.h_valid")
    valid = h_valid > 0.5 if h_valid is not None else aided_rows(results)
    h_std = results.columns.get(std_column) if std_column else None
    return EstimatorReport(
        name=name,
        vs_ekf=Stats.of(h[ekf] - results[f"{REPLAY}.ekf_h"][ekf]),
        gps_innovation=Stats.of(innovation),
        nis=nis,
        baro_residual=Stats.of(results[f"{REPLAY}.baro_h"][baro] - h[baro]),
        ground=Stats.of(ground),
        rejected=int(rejected[-1]) if rejected is not None else None,
        valid_fraction=float(np.mean(valid[after])) if after.any() else float("nan"),
        diverged=divergence(results, h, h_std, after),
    )


def compare_all(results: Results, estimators: list[str], start: float | None = None,
                ) -> list[EstimatorReport]:
    """EKF2's own row (as a peer: its GPS innovations, baro residuals, ground) and one per
    estimator component."""
    start = settle_time(results) if start is None else start
    rows = [compare(results, f"{REPLAY}.ekf_h", EKF2, start)]
    rows += [compare(results, f"{name}.h_est", name, start) for name in estimators]
    return rows


def sample_counts(results: Results) -> dict[str, int]:
    """Samples LogReplay delivered per stream over the run."""
    prefixes = ("baro", "gps", "acc", "laser", "radar", "ekf")
    return {p: int(results[f"{REPLAY}.{p}_count"][-1]) for p in prefixes
            if f"{REPLAY}.{p}_count" in results.columns}


def format_table(reports: list[EstimatorReport]) -> str:
    """The comparison as a plain-text table (m; NIS dimensionless)."""
    head = (f"{'estimate':<27}{'vs EKF2: RMS':>13}{'mean':>8}{'std':>7}{'max':>7}"
            f"{'GPS innov: mean':>17}{'std':>7}{'NIS':>7}{'baro-h: mean':>14}{'std':>7}"
            f"{'h-range: std':>14}{'rejected':>10}{'valid':>7}  diverged")
    lines = [head, "-" * len(head)]
    for r in reports:
        rejected = "" if r.rejected is None else str(r.rejected)
        lines.append(
            f"{r.name:<27}{r.vs_ekf.rms:13.3f}{r.vs_ekf.mean:8.3f}{r.vs_ekf.std:7.3f}"
            f"{r.vs_ekf.max_abs:7.3f}{r.gps_innovation.mean:17.3f}{r.gps_innovation.std:7.3f}"
            f"{r.nis:7.2f}{r.baro_residual.mean:14.3f}{r.baro_residual.std:7.3f}"
            f"{r.ground.std:14.3f}{rejected:>10}{r.valid_fraction:7.0%}  "
            f"{r.diverged or 'no'}")
    return "\n".join(lines).replace("nan", "  -")


SUMMARY_COLUMNS = ("estimate", "vs EKF2: RMS [m]", "mean [m]", "std (common datum) [m]",
                   "max [m]", "GPS innovation: mean [m]", "std [m]", "NIS",
                   "baro - h: mean [m]", "std [m]", "h - range: std [m]", "rejected",
                   "valid", "diverged")
"""The columns of the saved summary (``<system>_summary.csv`` and ``.md``), as printed."""


def summary_values(report: EstimatorReport) -> tuple:
    """One row of the summary: numbers (nan where nothing was measured; EKF2's own row has
    no difference to itself), the rejected count (None without one) and the diverged text."""
    nan = float("nan")
    versus = (nan,) * 4 if report.name == EKF2 else (
        report.vs_ekf.rms, report.vs_ekf.mean, report.vs_ekf.std, report.vs_ekf.max_abs)
    return (report.name, *versus, report.gps_innovation.mean, report.gps_innovation.std,
            report.nis, report.baro_residual.mean, report.baro_residual.std,
            report.ground.std, report.rejected, report.valid_fraction,
            report.diverged or "no")


def _text(value, digits: int) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "-"
    return f"{value:.{digits}f}" if isinstance(value, float) else str(value)


def format_markdown(reports: list[EstimatorReport]) -> str:
    """The comparison as a markdown table (m, 3 decimals; NIS 2; valid in %)."""
    lines = ["| " + " | ".join(SUMMARY_COLUMNS) + " |", "|" + "---|" * len(SUMMARY_COLUMNS)]
    for report in reports:
        values = summary_values(report)
        cells = [values[0], *(_text(v, 2 if i == 6 else 3) for i, v in enumerate(values[1:10])),
                 _text(values[10], 3), _text(values[11], 0),
                 f"{100 * values[12]:.0f} %" if values[12] == values[12] else "-", values[13]]
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"


def write_summary(reports: list[EstimatorReport], stem: Path) -> list[Path]:
    """``<stem>_summary.csv`` (full precision, empty where nothing was measured) and
    ``<stem>_summary.md`` (the table as printed)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(SUMMARY_COLUMNS)
    for report in reports:
        writer.writerow("" if v is None or (isinstance(v, float) and v != v) else
                        (repr(v) if isinstance(v, float) else v)
                        for v in summary_values(report))
    stem = Path(stem)
    return [write_text(stem.with_name(f"{stem.name}_summary.csv"), buffer.getvalue()),
            write_text(stem.with_name(f"{stem.name}_summary.md"), format_markdown(reports))]
