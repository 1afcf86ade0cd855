"""``altfusion reproduce bao2017``: bao2017 Section 4.3 (Bao et al. 2017), Figs. 7-8.

Campaigns of catalog system ``bao2017`` (``altfusion.systems.bao2017`` describes the
one-hour static test) with the same master seed, so run i of each sees the same drift, baro
noise and GPS noise:

* ``adaptive/``: BaoDriftEstimator with the adaptive R_k = η_k·C of eq. (14), the paper's
  method;
* ``constant_R<R>/``: the "normal Kalman filter" (``adaptive_R`` false) with a constant R
  from :data:`CONSTANT_R`, a grid around the best constant R (σ 3 to 7 m);
* ``BaselineKF/``: BaselineKF swapped in as ``estimator`` (:data:`BASELINE`), beside the
  paper's estimator.

Statistics. Errors are the estimators' corrected baro height h_est minus the true altitude,
every 1 s over (0, 3600] s; windows: the whole test, the poor-GPS phase (600, 1200] s and the
good-GPS phase (2400, 3000] s (Fig. 8's left and right ellipses). RMS over a window pools
the window's samples of every run, with a 95 % interval that takes each run as one sample.
The best constant R is the grid's smallest RMS over the whole test; it has to lie inside the
grid (else the grid does not bracket the best constant). Paired comparison: in each run and
window, the adaptive filter wins if its mean square error is below the other filter's in the
same run; the count of runs won has a 95 % Clopper-Pearson interval, and the claim holds if
that interval lies above 75 % (:data:`LARGE_MAJORITY`).

The paper shows one run and no numbers: Fig. 8's reading is that the proposed method "has
smaller error than that one corrected by the normal Kalman filter, especially at the two
places circled", where the GPS is poor (larger R) and good (smaller R). The claims table
checks that against the best constant R in the large majority of runs and in both windows.

Written to the output folder: ``bao2017_fig8.png`` (run 0's GPS quality and R_k, its baro and
GPS heights (Fig. 7), its heights corrected with the best constant R and the adaptive R
(Fig. 8), and the RMS over runs versus time with 95 % chi-square bands) and ``bao2017.md``
(the tables printed at the end).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.montecarlo.statistics import mean_interval
from altfusion.reproduce import ReproduceOptions
from altfusion.reproduce.common import (
    CONFIDENCE,
    Campaign,
    Estimate,
    Reference,
    RmsCurve,
    RunArrays,
    WinCount,
    figure,
    load_runs,
    markdown_table,
    paired_wins,
    rms_curve,
    rms_over_runs,
    run_reproduction,
    save_figure,
)
from altfusion.systems.bao2017 import DRIFT_PSD, GOOD_WINDOW, POOR_WINDOW, STOP_TIME

DEFAULT_RUNS = 100
"""The paper shows one run. 100 paired runs bound the fraction of runs the adaptive R wins
within a 95 % Clopper-Pearson interval of ±6 % at 90 % (96.4-100 % if it wins all)."""

CONSTANT_R = (9.0, 16.0, 25.0, 36.0, 49.0)
"""R of the normal Kalman filter, m²: σ 3 (the nominal phases' σ_G) to 7 m."""

BASELINE = {"R_baro": 0.01, "R_gps": 9.0, "bias_psd": DRIFT_PSD, "gate_sigma": 0.0}
"""BaselineKF given the baro's 0.1 m noise, the nominal GPS σ_G of 3 m (VDOP 1.5, 9
satellites), eq. (6)'s σ² as its bias random walk, and no gate (as the paper's filters)."""

WINDOWS = {"test": (0.0, STOP_TIME), "poor": POOR_WINDOW, "good": GOOD_WINDOW}
"""Time windows (start, end] of the RMS and the paired comparisons, s."""

WINDOW_LABELS = {"test": "whole test", "poor": "poor GPS", "good": "good GPS"}

LARGE_MAJORITY = 0.75
"""The adaptive R wins "the large majority" of the runs if the 95 % interval of the fraction
of runs it wins lies above three in four."""


def constant_name(R: float) -> str:
    return f"constant R = {R:g} m²"


def _campaigns() -> tuple[Campaign, ...]:
    adaptive = Campaign("adaptive R (eq. 14)", "adaptive", "bao2017",
                        parameters={"estimator.adaptive_R": True})
    constants = tuple(
        Campaign(constant_name(R), f"constant_R{R:g}", "bao2017",
                 parameters={"estimator.adaptive_R": False, "estimator.R_gps": R})
        for R in CONSTANT_R)
    baseline = Campaign("BaselineKF", "BaselineKF", "bao2017", estimator="BaselineKF",
                        parameters={f"estimator.{k}": v for k, v in BASELINE.items()})
    return (adaptive, *constants, baseline)


CAMPAIGNS = _campaigns()

REFERENCES = (
    Reference("bao2017", ("plant.h", "air_data.baro_h", "air_data.baro_drift", "gnss.gps_h",
                          "gnss.gps_vdop", "gnss.gps_nsat", "estimator.h_est",
                          "estimator.drift", "estimator.drift_std", "estimator.eta",
                          "estimator.R"), interval=20.0),
)
"""Reference CSV in tests/data/reference (see ``altfusion.reproduce.common``)."""

SIGNALS = ("plant.h", "air_data.baro_h", "estimator.h_est")
ADAPTIVE_SIGNALS = ("air_data.baro_drift", "gnss.gps_h", "gnss.gps_vdop", "gnss.gps_nsat",
                    "estimator.R")


@dataclass
class BaoAnalysis:
    """What the figure and the tables show."""

    runs: int
    time: np.ndarray
    """Output times (0, 3600] s."""
    errors: dict[str, np.ndarray]
    """Errors (runs × times) of the raw ``baro``, the ``GPS``, ``adaptive``, each
    :func:`constant_name` and ``BaselineKF``."""
    run0: dict[str, np.ndarray]
    """Run 0's true altitude, GPS quality and adaptive R for the figure."""
    drift_end: np.ndarray
    """Each run's baro drift at 3600 s, m."""

    @property
    def best(self) -> float:
        """The constant R with the smallest RMS over the whole test."""
        return min(CONSTANT_R, key=lambda R: self.rms(constant_name(R)).value)

    def window(self, name: str, window: str) -> np.ndarray:
        start, end = WINDOWS[window]
        return self.errors[name][:, (self.time > start) & (self.time <= end)]

    def rms(self, name: str, window: str = "test") -> Estimate:
        return rms_over_runs(self.window(name, window))

    def wins(self, other: str, window: str = "test") -> WinCount:
        """Runs in which the adaptive R's mean square error in ``window`` is below
        ``other``'s."""
        return paired_wins(self.window("adaptive", window), self.window(other, window))

    def curve(self, name: str) -> RmsCurve:
        return rms_curve(name, self.time, self.errors[name])


def _load(out: Path, campaign: Campaign, extra: tuple[str, ...] = ()) -> RunArrays:
    return load_runs(Path(out) / campaign.folder, SIGNALS + extra)


def analyse(out: Path) -> BaoAnalysis:
    """The errors of the campaigns in ``out``, checked to be the same runs (identical baro
    samples)."""
    adaptive, *constants, baseline = CAMPAIGNS
    first = _load(out, adaptive, ADAPTIVE_SIGNALS)
    loaded = {"adaptive": first, "BaselineKF": _load(out, baseline)}
    loaded.update({constant_name(R): _load(out, campaign)
                   for R, campaign in zip(CONSTANT_R, constants, strict=True)})
    for name, arrays in loaded.items():
        if arrays.runs != first.runs or not np.array_equal(arrays["air_data.baro_h"],
                                                           first["air_data.baro_h"]):
            raise ValueError(f"{out}: the {name} campaign has other runs or other sensor "
                             f"noise than the adaptive one")
    rows = first.time > 0.0  # before the first samples the outputs are placeholders
    truth = first["plant.h"][:, rows]
    errors = {"baro": first["air_data.baro_h"][:, rows] - truth,
              "GPS": first["gnss.gps_h"][:, rows] - truth}
    errors.update({name: arrays["estimator.h_est"][:, rows] - truth
                   for name, arrays in loaded.items()})
    run0 = {"truth": truth[0], "R": first["estimator.R"][0, rows],
            "vdop": first["gnss.gps_vdop"][0, rows], "nsat": first["gnss.gps_nsat"][0, rows]}
    return BaoAnalysis(len(first.runs), first.time[rows], errors, run0,
                       first["air_data.baro_drift"][:, -1])


# ------------------------------------------------------------------------------ tables


def rms_table(analysis: BaoAnalysis) -> str:
    """RMS error by window, with intervals; the best constant R in bold."""
    names = ("baro", "GPS", "adaptive", *(constant_name(R) for R in CONSTANT_R), "BaselineKF")
    labels = {"baro": "raw baro height (drifting)", "GPS": "GPS height",
              "adaptive": "corrected, adaptive R (eq. 14)",
              constant_name(analysis.best): f"**corrected, {constant_name(analysis.best)} "
                                            f"(best constant)**",
              "BaselineKF": "BaselineKF"}
    header = ("error", *(f"RMS {WINDOW_LABELS[w]} ({s:g}-{e:g} s) [m]"
                         for w, (s, e) in WINDOWS.items()))
    rows = [(labels.get(name, f"corrected, {name}"),
             *(analysis.rms(name, w).text(3) for w in WINDOWS)) for name in names]
    return markdown_table(header, rows)


def wins_table(analysis: BaoAnalysis) -> str:
    """Runs won by the adaptive R against each constant R and BaselineKF, by window."""
    others = (*(constant_name(R) for R in CONSTANT_R), "BaselineKF")
    header = ("adaptive R against", *(f"runs won, {WINDOW_LABELS[w]} [95 % CI]"
                                      for w in WINDOWS))
    rows = [(name, *(analysis.wins(name, w).text() for w in WINDOWS)) for name in others]
    return markdown_table(header, rows)


def claims_table(analysis: BaoAnalysis) -> str:
    """The paper's reading of Figs. 1 and 8 beside our numbers."""
    a = analysis
    best = constant_name(a.best)
    inside = CONSTANT_R[0] < a.best < CONSTANT_R[-1]

    def verdict(holds: bool) -> str:
        return "yes" if holds else "**no**"


    drift = Estimate(float(a.drift_end.mean()), mean_interval(a.drift_end, CONFIDENCE))
    low, high = np.percentile(a.drift_end, [5, 95])
    rows = [
        ("baro drift after 1 h, m", "about +10 (Fig. 1)",
         f"{drift.text(3)}; single runs {low:.3g} to {high:.3g}", "-"),
        ("best constant R of the grid (smallest RMS over the test), m²", "-",
         f"{a.best:g} (grid {', '.join(f'{R:g}' for R in CONSTANT_R)}; inside the grid: "
         f"{'yes' if inside else 'no'})", verdict(inside)),
    ]
    for window, paper in (("test", "smaller error than the normal KF (Fig. 8)"),
                          ("poor", "smaller error where the GPS is poor (left ellipse)"),
                          ("good", "smaller error where the GPS is good (right ellipse)")):
        wins = a.wins(best, window)
        rows.append((
            f"adaptive R beats the best constant R in the large majority of runs, "
            f"{WINDOW_LABELS[window]}: RMS; runs won",
            paper,
            f"{a.rms('adaptive', window).text(3)} m vs {a.rms(best, window).text(3)} m; "
            f"{wins.text()}", verdict(wins.interval.low > LARGE_MAJORITY)))
    rows.append(("BaselineKF (not in the paper), whole test / poor / good, m", "-",
                 " / ".join(a.rms("BaselineKF", w).text(3) for w in WINDOWS), "-"))
    return markdown_table(("claim", "paper", f"ours ({a.runs} runs, [95 % CI])", "holds"),
                          rows)


def format_tables(analysis: BaoAnalysis) -> str:
    return (f"bao2017 (Bao et al. 2017) Section 4.3, {analysis.runs} Monte Carlo runs of the "
            f"1 h static test. Runs won: Clopper-Pearson 95 % interval.\n\n"
            f"{claims_table(analysis)}\n\n{rms_table(analysis)}\n\n{wins_table(analysis)}\n")


# ------------------------------------------------------------------------------ figure


def plot_fig8(analysis: BaoAnalysis, path: Path) -> Path:
    """Run 0's GPS quality and R (Fig. 4), baro and GPS heights (Fig. 7), corrected heights
    (Fig. 8); the RMS over runs versus time."""
    a, run0 = analysis, analysis.run0

    def height(name: str) -> np.ndarray:
        """Run 0's height: its error plus the truth."""
        return a.errors[name][0] + run0["truth"]

    fig, (quality, raw, corrected, rms) = figure(4, height_ratios=(0.8, 1, 1, 1.2))
    for ax in (quality, raw, corrected, rms):
        for start, end in (POOR_WINDOW, GOOD_WINDOW):
            ax.axvspan(start, end, color="grey", alpha=0.12, linewidth=0)
    quality.plot(a.time, run0["vdop"], color="black", linewidth=1, label="VDOP")
    quality.plot(a.time, run0["nsat"] / 10, color="tab:blue", linewidth=1,
                 label="satellites / 10")
    quality.set_ylabel("GPS quality")
    quality.set_ylim(0, 1.5 * max(run0["vdop"].max(), run0["nsat"].max() / 10))
    twin = quality.twinx()
    twin.semilogy(a.time, run0["R"], color="tab:red", linewidth=1, label="R_k (eq. 14)")
    twin.axhline(a.best, color="tab:red", linestyle="--", linewidth=0.8,
                 label=f"best constant R = {a.best:g} m²")
    twin.set_ylabel("R [m²]")
    lines = quality.get_legend_handles_labels()
    twin_lines = twin.get_legend_handles_labels()
    quality.legend(lines[0] + twin_lines[0], lines[1] + twin_lines[1], loc="upper right",
                   fontsize=7, ncol=4)
    quality.set_title("GPS quality of run 0 (Fig. 4) and the measurement noise R; shaded: "
                      "the poor-GPS and good-GPS windows", fontsize=9)
    raw.plot(a.time, height("GPS"), color="tab:orange", linewidth=0.5, label="GPS height")
    raw.plot(a.time, height("baro"), color="tab:blue", linewidth=1, label="baro height")
    raw.plot(a.time, run0["truth"], color="black", linestyle="--", linewidth=0.8,
             label="true altitude")
    raw.set_ylabel("height [m]")
    raw.legend(loc="upper left", fontsize=7, ncol=3)
    raw.set_title("Fig. 7 equivalent: run 0's drifting baro height and GPS height", fontsize=9)
    corrected.plot(a.time, height(constant_name(a.best)), linewidth=0.8,
                   label=f"normal KF, {constant_name(a.best)}")
    corrected.plot(a.time, height("adaptive"), linewidth=0.8, label="adaptive R (eq. 14)")
    corrected.plot(a.time, run0["truth"], color="black", linestyle="--", linewidth=0.8,
                   label="true altitude")
    corrected.set_ylabel("height [m]")
    corrected.legend(loc="upper left", fontsize=7, ncol=3)
    corrected.set_title("Fig. 8 equivalent: run 0's baro height corrected by the normal KF "
                        "and by the proposed method", fontsize=9)
    for name, label in (("adaptive", "adaptive R (eq. 14)"),
                        (constant_name(a.best), f"normal KF, {constant_name(a.best)}"),
                        ("BaselineKF", "BaselineKF")):
        curve = a.curve(name)
        line, = rms.plot(curve.time, curve.rms, linewidth=0.8, label=label)
        rms.fill_between(curve.time, curve.low, curve.high, color=line.get_color(),
                         alpha=0.18, linewidth=0)
    rms.set_ylabel("RMS error [m]")
    rms.set_xlabel("time [s]")
    rms.set_ylim(0, 1.5 * max(a.curve(name).rms.max() for name in ("adaptive", "BaselineKF")))
    rms.legend(loc="upper left", fontsize=7, ncol=3)
    rms.set_title(f"RMS error of the corrected baro height over {a.runs} runs (95 % "
                  f"chi-square bands)", fontsize=9)
    return save_figure(fig, path)


# ------------------------------------------------------------------------------ command


def reproduce(options: ReproduceOptions) -> int:
    """Run (or complete) the campaigns, write the figure and the tables, print them."""
    return run_reproduction(options, "bao2017", CAMPAIGNS, DEFAULT_RUNS, analyse,
                            format_tables,
                            lambda a, out: [plot_fig8(a, out / "bao2017_fig8.png")])
