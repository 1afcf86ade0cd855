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
"""

from dataclasses import dataclass

import numpy as np

from altfusion.cosim.results import Results

REPLAY = "replay"
SETTLE_TIME = 5.0
"""Offset-learning time after the first valid GPS sample, s: 25 GPS samples at 5 Hz bring the
bias σ of the replay tuning to ~√(0.6² + 0.8²)/√25 = 0.2 m; Whang's alpha-beta filter, which
starts before its bias is known, is settled after 1.6 s on the Auterion log."""


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
        if len(new_sample_rows(results, prefix, f"{prefix}_valid")):
            return prefix
    return None


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
    return EstimatorReport(
        name=name,
        vs_ekf=Stats.of(h[ekf] - results[f"{REPLAY}.ekf_h"][ekf]),
        gps_innovation=Stats.of(innovation),
        nis=nis,
        baro_residual=Stats.of(results[f"{REPLAY}.baro_h"][baro] - h[baro]),
        ground=Stats.of(ground),
        rejected=int(rejected[-1]) if rejected is not None else None,
    )


def compare_all(results: Results, estimators: list[str], start: float | None = None,
                ) -> list[EstimatorReport]:
    """EKF2's own row (as a peer: its GPS innovations, baro residuals, ground) and one per
    estimator component."""
    start = settle_time(results) if start is None else start
    rows = [compare(results, f"{REPLAY}.ekf_h", "PX4 EKF2 (reference)", start)]
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
            f"{'h-range: std':>14}{'rejected':>10}")
    lines = [head, "-" * len(head)]
    for r in reports:
        rejected = "" if r.rejected is None else str(r.rejected)
        lines.append(
            f"{r.name:<27}{r.vs_ekf.rms:13.3f}{r.vs_ekf.mean:8.3f}{r.vs_ekf.std:7.3f}"
            f"{r.vs_ekf.max_abs:7.3f}{r.gps_innovation.mean:17.3f}{r.gps_innovation.std:7.3f}"
            f"{r.nis:7.2f}{r.baro_residual.mean:14.3f}{r.baro_residual.std:7.3f}"
            f"{r.ground.std:14.3f}{rejected:>10}")
    return "\n".join(lines).replace("nan", "  -")
