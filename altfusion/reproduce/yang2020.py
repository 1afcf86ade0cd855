"""``altfusion reproduce yang2020``: yang2020 Section 4 (Yang et al. 2020), Fig. 2.

Two campaigns with the same master seed, so run i of both sees the same sensor noise
(``altfusion.systems.yang2020`` describes the scenario):

* ``YangFusionKF/``: catalog system ``yang2020``, the paper's method (time-unified optimal
  weighted fusion of GPS, baro and radio altimeter, eqs. 5-8, then the Kalman filter of eqs.
  9-14) flying the closed loop;
* ``BaselineKF/``: catalog system ``yang2020_baseline``, the same loop flown on BaselineKF
  (baro and GPS). Its trajectory differs from the first campaign's by the two estimators'
  errors; the sensor noise draws are the same, so run i of both is a paired comparison.

Statistics. The paper's accuracy σ of eq. (15), sqrt(Σ_p e(p)²/(M - 1)), is computed per run
for every "way" of measuring the height, each at its own sampling instants p within the
recorded rows (every 0.1 s, t > 0): the GPS and the barometer at every row (each row holds a
sample taken at that instant), the radio altimeter and the weighted fusion y (eq. 7) at the
radio altimeter's samples (the fusion's benchmark, Section 4.2: every 0.2 s), the Kalman
filters at every row. The error is against the plant's altitude at the same instant.

* Weighted fusion (Section 3.2): its errors are white and Gaussian with the theory's
  σ_Y = [Σ 1/σ_i²]^(-1/2) = 8.57 m, so the pooled RMS of all fusion instants of all runs
  gets a chi-square interval (``rms_chi2_bounds``) that must contain σ_Y.
* The Kalman filters' errors are correlated in time: their RMS over the runs gets the
  interval that takes each run as one sample (``rms_over_runs``).
* "499 times better than GPS, 491 than the barometric altimeter, 388 than the radio
  altimeter" read as counts of runs (docs/papers.md): the runs in which the filter's σ of eq. (15)
  is below that sensor's σ in the same run; likewise against the weighted fusion alone.

Written to the output folder: ``yang2020_fig2.png`` (Fig. 2's equivalent: every run's
accuracy σ of eq. (15), by way of measuring), ``yang2020_errors.png`` (run 0's trajectory
above the RMS over runs versus time, 95 % chi-square bands) and ``yang2020.md`` (the tables
printed at the end).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.montecarlo.statistics import Interval, rms_chi2_bounds
from altfusion.reproduce import ReproduceOptions
from altfusion.reproduce.common import (
    CONFIDENCE,
    Campaign,
    Estimate,
    Reference,
    RmsCurve,
    figure,
    load_runs,
    markdown_table,
    rms_curve,
    rms_over_runs,
    run_reproduction,
    save_figure,
)
from altfusion.systems.sensors import SEED_003_SENSORS

DEFAULT_RUNS = 500
"""Section 4.2: 500 Monte Carlo experiments."""

RECORD_INTERVAL = 0.1
"""Output interval of the ``yang2020`` systems, s."""

FUSION_PERIOD = SEED_003_SENSORS["radar"]["sample_period"]
"""Section 4.2: the radio altimeter's 200 ms, the largest sampling period, is the time
benchmark of the fusion (Section 3.1.1)."""

SENSOR_SIGMAS = {
    "GPS": SEED_003_SENSORS["gnss"]["user_range_error"] * SEED_003_SENSORS["gnss"]["vdop"],
    "baro": SEED_003_SENSORS["air_data"]["height_noise_std"],
    "radio altimeter": SEED_003_SENSORS["radar"]["noise_std"],
}
"""Section 4.2: 30 m, 20 m, 10 m."""

FUSED_SIGMA = float(sum(1.0 / s**2 for s in SENSOR_SIGMAS.values()) ** -0.5)
"""Section 3.2: σ_Y = [Σ 1/σ_i²]^(-1/2) = 8.57 m."""

PAPER_COUNTS = {"GPS": 499, "baro": 491, "radio altimeter": 388}
"""Section 4.2: in how many of the 500 runs the fusion filter beat each sensor."""

SENSOR_SIGNALS = {"GPS": "gnss.gps_h", "baro": "air_data.baro_h",
                  "radio altimeter": "radar.radar_h", "weighted fusion": "estimator.h_fused"}
SENSORS = ("GPS", "baro", "radio altimeter")
WAYS = (*SENSOR_SIGNALS, "YangFusionKF", "BaselineKF")
"""The ways of measuring the height, in the tables' and figures' order."""
ESTIMATORS = ("YangFusionKF", "BaselineKF")
LABELS = {"GPS": "GPS", "baro": "barometric altimeter", "radio altimeter": "radio altimeter",
          "weighted fusion": "weighted fusion y (eq. 7)",
          "YangFusionKF": "fusion filter (YangFusionKF, eqs. 9-14)",
          "BaselineKF": "BaselineKF (baro + GPS)"}

CAMPAIGNS = (
    Campaign("YangFusionKF", "YangFusionKF", "yang2020"),
    Campaign("BaselineKF", "BaselineKF", "yang2020_baseline"),
)

REFERENCES = (
    Reference("yang2020", ("plant.h", "controller.h_ref", "air_data.baro_h", "gnss.gps_h",
                           "gnss.gps_vz", "radar.radar_h", "accelerometer.acc_z",
                           "estimator.h_fused", "estimator.h_est", "estimator.vz_est",
                           "estimator.h_std"), interval=10.0),
    Reference("yang2020_baseline", ("plant.h", "controller.h_ref", "air_data.baro_h",
                                    "gnss.gps_h", "estimator.h_est", "estimator.vz_est",
                                    "estimator.h_std"), interval=10.0),
)
"""Reference CSVs in tests/data/reference (see ``altfusion.reproduce.common``)."""

YANG_SIGNALS = ("plant.h", "controller.h_ref", *(SENSOR_SIGNALS.values()),
                "estimator.fused_std", "estimator.h_est", "estimator.h_std",
                "estimator.n_rejected")
BASELINE_SIGNALS = ("plant.h", "controller.h_ref", "air_data.baro_h", "estimator.h_est",
                    "estimator.h_std")


# ------------------------------------------------------------------------------ statistics


def eq15_sigma(errors: np.ndarray) -> np.ndarray:
    """Eq. (15) for each run (row): sqrt(Σ_p e(p)² / (M - 1)) over its M samples."""
    return np.sqrt(np.sum(errors**2, axis=1) / (errors.shape[1] - 1))


def on_period(time: np.ndarray, period: float) -> np.ndarray:
    """Rows at positive multiples of ``period``."""
    return (time > 0) & np.isclose(time / period, np.round(time / period))


@dataclass
class YangAnalysis:
    """What the figures and the tables show."""

    runs: list[int]
    time: np.ndarray
    altitude: np.ndarray
    """Run 0's true altitude (Section 4.1's trajectory)."""
    reference: np.ndarray
    """Run 0's commanded altitude (profile ``yang2020``)."""
    errors: dict[str, tuple[np.ndarray, np.ndarray]]
    """By way (``WAYS``): (sampling instants, errors runs × instants)."""
    sigmas: dict[str, np.ndarray]
    """By way: each run's σ of eq. (15)."""
    fused_pooled: Estimate
    """RMS of all weighted-fusion errors with its chi-square interval (white errors)."""
    fused_std: np.ndarray
    """σ_Y that YangFusionKF reports at the fusion instants (runs × instants)."""
    filter_std: dict[str, float]
    """By estimator: RMS over runs and rows of its own h_std."""
    tracking: dict[str, Estimate]
    """By estimator: RMS of the closed loop's tracking error plant.h - h_ref."""
    rejected: float
    """Mean height samples per run that YangFusionKF's gate rejected."""

    @property
    def count(self) -> int:
        return len(self.runs)

    def rms(self, way: str) -> Estimate:
        """RMS over runs and instants, each run one sample (see ``rms_over_runs``)."""
        return rms_over_runs(self.errors[way][1])

    def beats(self, estimator: str, way: str) -> int:
        """Runs in which ``estimator``'s σ of eq. (15) is below that of ``way``."""
        return int(np.sum(self.sigmas[estimator] < self.sigmas[way]))

    def curve(self, way: str) -> RmsCurve:
        return rms_curve(LABELS[way], *self.errors[way])


def analyse(out: Path) -> YangAnalysis:
    """The statistics of the two campaigns in ``out``."""
    yang = load_runs(Path(out) / "YangFusionKF", YANG_SIGNALS)
    baseline = load_runs(Path(out) / "BaselineKF", BASELINE_SIGNALS)
    if yang.runs != baseline.runs or not np.array_equal(yang.time, baseline.time):
        raise ValueError(f"the campaigns in {out} do not hold the same runs")
    time = yang.time
    every, fusion = on_period(time, RECORD_INTERVAL), on_period(time, FUSION_PERIOD)
    rows = {"GPS": every, "baro": every, "radio altimeter": fusion, "weighted fusion": fusion}
    errors = {way: (time[rows[way]], yang.error(signal, "plant.h")[:, rows[way]])
              for way, signal in SENSOR_SIGNALS.items()}
    errors["YangFusionKF"] = (time[every], yang.error("estimator.h_est", "plant.h")[:, every])
    errors["BaselineKF"] = (time[every],
                            baseline.error("estimator.h_est", "plant.h")[:, every])
    fused = errors["weighted fusion"][1]
    low, high = rms_chi2_bounds(np.mean(fused**2), fused.size, CONFIDENCE)
    filter_std = {name: float(np.sqrt(np.mean(runs["estimator.h_std"][:, every] ** 2)))
                  for name, runs in (("YangFusionKF", yang), ("BaselineKF", baseline))}
    tracking = {name: rms_over_runs(runs.error("plant.h", "controller.h_ref")[:, every])
                for name, runs in (("YangFusionKF", yang), ("BaselineKF", baseline))}
    return YangAnalysis(
        runs=yang.runs, time=time, altitude=yang["plant.h"][0],
        reference=yang["controller.h_ref"][0], errors=errors,
        sigmas={way: eq15_sigma(e) for way, (_, e) in errors.items()},
        fused_pooled=Estimate(float(np.sqrt(np.mean(fused**2))),
                              Interval(float(low), float(high))),
        fused_std=yang["estimator.fused_std"][:, fusion], filter_std=filter_std,
        tracking=tracking, rejected=float(yang["estimator.n_rejected"][:, -1].mean()))


# ------------------------------------------------------------------------------ tables


def _percentiles(values: np.ndarray) -> str:
    low, median, high = np.percentile(values, [5, 50, 95])
    return f"{median:.3g} ({low:.3g}-{high:.3g})"


def accuracy_table(a: YangAnalysis) -> str:
    """Each way's accuracy: theory, RMS over runs [95 % CI], single runs' σ of eq. (15)."""
    theory = {**SENSOR_SIGMAS, "weighted fusion": FUSED_SIGMA}
    rows = []
    for way in WAYS:
        rms = a.fused_pooled if way == "weighted fusion" else a.rms(way)
        expected = f"{theory[way]:.4g}" if way in theory else \
            f"its own h_std: {a.filter_std[way]:.3g}"
        rows.append((LABELS[way], expected, rms.text(4), _percentiles(a.sigmas[way])))
    return markdown_table(
        ("way", "σ, theory [m]", f"RMS over {a.count} runs [95 % CI] [m]",
         "single runs' σ of eq. (15): median (5-95 %) [m]"), rows)


def counts_table(a: YangAnalysis) -> str:
    """In how many runs each estimator's σ of eq. (15) beats each sensor and the fusion."""
    header = ("runs in which the filter beats", f"paper (of {DEFAULT_RUNS})",
              *(f"{LABELS[e]} (of {a.count})" for e in ESTIMATORS))
    rows = [(LABELS[way], str(PAPER_COUNTS.get(way, "-")),
             *(str(a.beats(e, way)) for e in ESTIMATORS))
            for way in (*SENSORS, "weighted fusion")]
    rows.append(("the other estimator (same run)", "-",
                 str(a.beats("YangFusionKF", "BaselineKF")),
                 str(a.beats("BaselineKF", "YangFusionKF"))))
    return markdown_table(header, rows)


def claims_table(a: YangAnalysis) -> str:
    """The paper's claims beside our numbers."""
    fused = a.fused_pooled
    kf, fusion = a.rms("YangFusionKF"), a.fused_pooled
    worst = min(a.beats("YangFusionKF", way) for way in (*SENSORS, "weighted fusion"))

    def verdict(holds: bool) -> str:
        return "yes" if holds else "**no**"

    rows = [
        ("weighted fusion's σ = [Σ 1/σ_i²]^(-1/2) (Section 3.2)", f"{FUSED_SIGMA:.4g} m",
         f"{fused.text(4)} m (chi-square, {fused_samples(a)} samples); reported σ_Y "
         f"{np.median(a.fused_std):.4g} m",
         verdict(fused.interval.low <= FUSED_SIGMA <= fused.interval.high)),
        ("fusion filter beats every sensor (Section 4.2, counts of runs)",
         "GPS 499, baro 491, radio altimeter 388 of 500",
         f"GPS {a.beats('YangFusionKF', 'GPS')}, baro {a.beats('YangFusionKF', 'baro')}, "
         f"radio altimeter {a.beats('YangFusionKF', 'radio altimeter')} of {a.count}",
         verdict(worst == a.count)),
        ("fusion filter beats the weighted fusion alone (Section 2.1, 3.3)",
         "yes (\"more accurate\")",
         f"{kf.text(3)} m vs {fusion.value:.3g} m (factor "
         f"{fusion.value / kf.value:.3g}); in {a.beats('YangFusionKF', 'weighted fusion')} "
         f"of {a.count} runs", verdict(kf.interval.high < fusion.interval.low)),
        ("(not in the paper) BaselineKF, closed loop on its own estimate", "-",
         f"{a.rms('BaselineKF').text(3)} m; beats the radio altimeter in "
         f"{a.beats('BaselineKF', 'radio altimeter')} of {a.count} runs", "-"),
    ]
    return markdown_table(("claim", "paper", f"ours ({a.count} runs, [95 % CI])", "holds"),
                          rows)


def fused_samples(a: YangAnalysis) -> int:
    return a.errors["weighted fusion"][1].size


def format_tables(a: YangAnalysis) -> str:
    tracking = ", ".join(f"{e} {a.tracking[e].text(3)} m" for e in ESTIMATORS)
    return (f"yang2020 (Yang et al. 2020) Section 4, {a.count} Monte Carlo runs.\n\n"
            f"{claims_table(a)}\n\n{accuracy_table(a)}\n\n{counts_table(a)}\n\n"
            f"Closed-loop tracking error RMS (plant.h - h_ref, [95 % CI]): {tracking}. "
            f"Height samples rejected by YangFusionKF's gate, mean per run: "
            f"{a.rejected:.3g}.\n")


# ------------------------------------------------------------------------------ figures

STYLES = {"weighted fusion": {"linestyle": "--"}, "BaselineKF": {"linestyle": ":"}}


def plot_fig2(a: YangAnalysis, path: Path) -> Path:
    """Fig. 2's equivalent: every run's accuracy σ of eq. (15), by way of measuring."""
    fig, (ax,) = figure(1, height=4.2)
    for way in WAYS:
        ax.semilogy(a.runs, a.sigmas[way], linewidth=0.9, label=LABELS[way],
                    **STYLES.get(way, {}))
    ax.axhline(FUSED_SIGMA, color="grey", linewidth=0.8, linestyle=":",
               label=f"σ_Y theory ({FUSED_SIGMA:.3g} m)")
    ax.set_xlabel("Monte Carlo run")
    ax.set_ylabel("accuracy σ, eq. (15) [m]")
    ax.legend(loc="center right", fontsize=7, ncol=2)
    ax.set_title(f"Fig. 2 equivalent: accuracy of each way of measuring the height, "
                 f"{a.count} runs", fontsize=9)
    return save_figure(fig, path)


def plot_errors(a: YangAnalysis, path: Path) -> Path:
    """Run 0's trajectory above the RMS over runs versus time of every way."""
    fig, (top, bottom) = figure(2, height_ratios=(1, 3))
    top.plot(a.time, a.altitude, color="black", linewidth=1, label="plant.h, run 0")
    top.plot(a.time, a.reference, color="grey", linewidth=0.8, linestyle="--",
             label="h_ref (profile 'yang2020')")
    top.set_ylabel("altitude [m]")
    top.legend(loc="upper right", fontsize=7)
    top.set_title("Section 4.1: climb, cruise, descent (YangFusionKF flies the loop)",
                  fontsize=9)
    for way in WAYS:
        curve = a.curve(way)
        line, = bottom.semilogy(curve.time, curve.rms, linewidth=0.9, label=curve.label,
                                **STYLES.get(way, {}))
        bottom.fill_between(curve.time, curve.low, curve.high, color=line.get_color(),
                            alpha=0.18, linewidth=0)
    bottom.set_ylabel("RMS error [m]")
    bottom.set_xlabel("time [s]")
    bottom.legend(loc="center right", fontsize=7, ncol=2)
    bottom.set_title(f"RMS errors over {a.count} runs (95 % chi-square bands)", fontsize=9)
    return save_figure(fig, path)


def plot_figures(a: YangAnalysis, out: Path) -> list[Path]:
    """Fig. 2's equivalent and the error curves."""
    return [plot_fig2(a, out / "yang2020_fig2.png"), plot_errors(a, out / "yang2020_errors.png")]


# ------------------------------------------------------------------------------ command


def reproduce(options: ReproduceOptions) -> int:
    """Run (or complete) the campaigns, write the figures and the tables, print them."""
    return run_reproduction(options, "yang2020", CAMPAIGNS, DEFAULT_RUNS, analyse,
                            format_tables, plot_figures)

