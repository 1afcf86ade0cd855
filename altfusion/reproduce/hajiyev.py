"""``altfusion reproduce hajiyev``: hajiyev Section 5 (Hajiyev et al.), Figs. 4-10, Table 1.

Six campaigns with the same master seed, so run i of each sees the same sensor noise
(``altfusion.systems.hajiyev`` describes the scenarios):

* ``constant/``: catalog system ``hajiyev`` (true atmosphere = the baro's calibration), with
  HajiyevAdaptiveEstimator non-adaptive (the paper's conventional fusion, eqs. 15-19),
  adaptive (eqs. 26-31), and BaselineKF swapped in as ``estimator``;
* ``drift/``: catalog system ``hajiyev_drift`` (p0 and T0 drift from k = 23), the same three.

Statistics are over the paper's iterations k = 1..1560 (the samples at t = k s). The paper
reports single runs; docs/papers.md reads Table 1's "error variance" as a run's sample variance of
the error. So for each run we take the sample variance of its errors over k = 1..n (n = 1560,
or Table 1's iterations), and report the mean over runs with its 95 % t interval (each run
one sample) and the 5-95 % range of the single runs, which is where a single run such as
the paper's should fall. For the constant case, the theory's value R_B·R_GPS/(R_B + R_GPS)
= 54.756 m² (eq. 13) also gets its 95 % sampling interval: with N runs the pooled variance
of white Gaussian errors is σ²·χ²(ν)/ν, ν = N·(1560 - 1).

Written to the output folder: ``hajiyev_fig4.png`` (constant case: |errors| of the baro, GPS
and the non-adaptive fusion of run 0 with the RMS over runs; Figs. 2-4), ``hajiyev_fig6.png``
(drift, non-adaptive), ``hajiyev_fig8.png`` (drift, adaptive), ``hajiyev_fig9.png``
(adaptive versus non-adaptive, BaselineKF beside), ``hajiyev_fig10.png`` (the adaptive
factor S(k)) and ``hajiyev.md`` (the table printed at the end).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from altfusion.montecarlo.statistics import Interval, mean_interval
from altfusion.reproduce import ReproduceOptions
from altfusion.reproduce.common import (
    CONFIDENCE,
    Campaign,
    Estimate,
    Reference,
    RunArrays,
    figure,
    load_runs,
    markdown_table,
    run_reproduction,
    save_figure,
)
from altfusion.systems.hajiyev import R_BARO, R_GPS

DEFAULT_RUNS = 50
"""The paper shows single runs; 50 runs put the single-run statistics in context (a 95 %
interval of ±1 % on the constant case's fused variance) in a few minutes on two cores."""

FUSED_VARIANCE = R_BARO * R_GPS / (R_BARO + R_GPS)
"""Eq. (13): 54.756 m² with R_B = 81 m², R_GPS = 169 m²."""

TABLE_1 = {400: 160.693, 600: 159.417, 800: 163.447, 1000: 159.054, 1300: 164.408,
           1500: 164.772}
"""Table 1: error variance of the adaptive fusion in the drift case at these iterations, m²."""

PAPER_DRIFT_BARO_ERROR = -1337.0
"""The baro error at k = 1560 that the paper's drift of the baro computation gives (eq. 31
with p0(k), T0(k) drifting from k = 23, computed in ``altfusion.systems.hajiyev``), m."""

CASES = {"constant": "hajiyev", "drift": "hajiyev_drift"}
VARIANTS = {"non-adaptive": False, "adaptive": True}
"""HajiyevAdaptiveEstimator's ``adaptive``, set in every run of each variant's campaigns."""


def _campaigns() -> tuple[Campaign, ...]:
    campaigns = []
    for case, system in CASES.items():
        for variant, adaptive in VARIANTS.items():
            campaigns.append(Campaign(f"{case}, {variant}", f"{case}/{variant}", system,
                                      parameters={"estimator.adaptive": adaptive}))
        campaigns.append(Campaign(f"{case}, BaselineKF", f"{case}/BaselineKF", system,
                                  estimator="BaselineKF"))
    return tuple(campaigns)


CAMPAIGNS = _campaigns()
ESTIMATORS = ("non-adaptive", "adaptive", "BaselineKF")

REFERENCES = (
    Reference("hajiyev", ("truth.gps_h", "air_data.baro_h", "gnss.gps_h", "estimator.h_est",
                          "estimator.adaptive_factor", "estimator.gain"), interval=20.0),
    Reference("hajiyev_drift", ("truth.gps_h", "atmosphere.p0_actual", "atmosphere.T0_actual",
                                "air_data.baro_h", "gnss.gps_h", "estimator.h_est",
                                "estimator.adaptive_factor", "estimator.gain"),
              interval=20.0),
)
"""Reference CSVs in tests/data/reference (see ``altfusion.reproduce.common``)."""

SIGNALS = ("truth.gps_h", "air_data.baro_h", "gnss.gps_h", "estimator.h_est",
           "estimator.n_rejected")
HAJIYEV_SIGNALS = ("estimator.adaptive_factor",)


# ------------------------------------------------------------------------------ statistics


@dataclass(frozen=True)
class SingleRunStatistic:
    """A statistic computed on each run: mean over runs [t interval] and the single runs'
    5-95 % range."""

    per_run: np.ndarray

    @property
    def mean(self) -> Estimate:
        return Estimate(float(self.per_run.mean()), mean_interval(self.per_run, CONFIDENCE))

    @property
    def range(self) -> tuple[float, float]:
        low, high = np.percentile(self.per_run, [5, 95])
        return float(low), float(high)

    def text(self, digits: int = 4) -> str:
        low, high = self.range
        return f"{self.mean.text(digits)}; single runs {low:.{digits}g} to {high:.{digits}g}"


def run_variance(errors: np.ndarray, n: int | None = None) -> SingleRunStatistic:
    """Each run's sample variance of its errors at iterations 1..n (all if None)."""
    return SingleRunStatistic(np.var(errors[:, :n], axis=1, ddof=1))


def variance_sampling_interval(variance: float, runs: int, samples: int,
                               confidence: float = CONFIDENCE) -> Interval:
    """Where the mean of ``runs`` single-run sample variances of ``samples`` white Gaussian
    errors of variance ``variance`` falls with probability ``confidence``: σ²·χ²(ν)/ν."""
    dof = runs * (samples - 1)
    low, high = stats.chi2.ppf([0.5 - confidence / 2, 0.5 + confidence / 2], dof)
    return Interval(float(variance * low / dof), float(variance * high / dof))


@dataclass
class CaseErrors:
    """Errors at the iterations k = 1..1560 (runs × iterations) of one case."""

    iterations: np.ndarray
    baro: np.ndarray
    gps: np.ndarray
    fused: dict[str, np.ndarray]
    """By estimator (``ESTIMATORS``)."""
    adaptive_factor: dict[str, np.ndarray]
    """S(k) by Hajiyev variant."""
    rejected: dict[str, float]
    """Mean samples per run rejected by each estimator's gate."""


@dataclass
class HajiyevAnalysis:
    runs: int
    cases: dict[str, CaseErrors]


def _case_errors(out: Path, case: str) -> CaseErrors:
    loaded: dict[str, RunArrays] = {}
    for estimator in ESTIMATORS:
        names = SIGNALS + (HAJIYEV_SIGNALS if estimator != "BaselineKF" else ())
        loaded[estimator] = load_runs(Path(out) / case / estimator, names)
    first = loaded[ESTIMATORS[0]]
    for estimator, arrays in loaded.items():
        if arrays.runs != first.runs or not np.array_equal(arrays["air_data.baro_h"],
                                                           first["air_data.baro_h"]):
            raise ValueError(f"{out}/{case}: the {estimator} campaign has other runs or "
                             f"other sensor noise than the {ESTIMATORS[0]} one")
    rows = slice(1, None)  # the row at t = 0 precedes the first sample
    truth = first["truth.gps_h"][:, rows]
    return CaseErrors(
        iterations=np.round(first.time[rows]).astype(int),
        baro=first["air_data.baro_h"][:, rows] - truth,
        gps=first["gnss.gps_h"][:, rows] - truth,
        fused={e: a["estimator.h_est"][:, rows] - truth for e, a in loaded.items()},
        adaptive_factor={e: a["estimator.adaptive_factor"][:, rows]
                         for e, a in loaded.items() if e != "BaselineKF"},
        rejected={e: float(a["estimator.n_rejected"][:, -1].mean())
                  for e, a in loaded.items()},
    )


def analyse(out: Path) -> HajiyevAnalysis:
    """The errors of the six campaigns in ``out``."""
    cases = {case: _case_errors(out, case) for case in CASES}
    return HajiyevAnalysis(cases["constant"].baro.shape[0], cases)


# ------------------------------------------------------------------------------ table


def _paired_variance_difference(drift: CaseErrors) -> np.ndarray:
    """Each run's adaptive-fusion error variance minus its GPS error variance."""
    return (run_variance(drift.fused["adaptive"]).per_run - run_variance(drift.gps).per_run)


def _rms(errors: np.ndarray) -> float:
    return float(np.sqrt(np.mean(errors**2)))


def result_rows(analysis: HajiyevAnalysis) -> list[tuple[str, str, str, str]]:
    """(case, quantity, paper, ours) rows of the table."""
    constant, drift = analysis.cases["constant"], analysis.cases["drift"]
    samples = constant.iterations.size
    sampling = variance_sampling_interval(FUSED_VARIANCE, analysis.runs, samples)
    rows = [
        ("constant", "baro error variance, m²", "81 (R_B, eq. 32)",
         run_variance(constant.baro).text()),
        ("constant", "GPS error variance, m²", "169 (R_GPS, eq. 33)",
         run_variance(constant.gps).text()),
        ("constant", "fused error variance, non-adaptive (eqs. 15-19), m²",
         f"54.756 (eq. 13); 95 % sampling interval of {analysis.runs} runs: "
         f"{sampling.low:.4g}-{sampling.high:.4g}",
         run_variance(constant.fused["non-adaptive"]).text()),
        ("constant", "fused error variance, adaptive (eqs. 26-31), m²", "-",
         run_variance(constant.fused["adaptive"]).text()),
        ("constant", "fused error variance, BaselineKF, m²", "-",
         run_variance(constant.fused["BaselineKF"]).text()),
    ]
    for n, paper in TABLE_1.items():
        rows.append(("drift", f"Table 1: adaptive fusion's error variance over k = 1..{n}, m²",
                     f"{paper:g}", run_variance(drift.fused["adaptive"], n).text()))
    final = {name: SingleRunStatistic(errors[:, -1]) for name, errors in
             (("baro", drift.baro), *drift.fused.items())}
    rows += [
        ("drift", "baro error at k = 1560, m",
         f"{PAPER_DRIFT_BARO_ERROR:g} (the paper's drift of p0, T0 in eq. 31)",
         final["baro"].text()),
        ("drift", "non-adaptive fused error at k = 1560, m",
         "grows to large values (Figs. 6, 9)", final["non-adaptive"].text()),
        ("drift", "adaptive fused error variance, whole run, m²",
         "below the GPS's (Table 1, Fig. 9)",
         f"{run_variance(drift.fused['adaptive']).text()}; GPS "
         f"{run_variance(drift.gps).mean.text()}"),
        ("drift", "adaptive minus GPS error variance of the same run, whole run, m²",
         "< 0: \"lesser than the error variances of the GPS\" (Table 1)",
         f"{SingleRunStatistic(_paired_variance_difference(drift)).text(3)}; below 0 in "
         f"{100 * np.mean(_paired_variance_difference(drift) < 0):.0f} % of the runs"),
        ("drift", "adaptive factor S(k) at k = 1560",
         "grows with the drift (Fig. 10)",
         SingleRunStatistic(drift.adaptive_factor["adaptive"][:, -1]).text(3)),
        ("drift", "BaselineKF fused error at k = 1560, m; RMS over the run, m", "-",
         f"{final['BaselineKF'].text()}; RMS {_rms(drift.fused['BaselineKF']):.4g}"),
    ]
    return rows


def format_table(analysis: HajiyevAnalysis) -> str:
    rejected = "; ".join(
        f"{case}: " + ", ".join(f"{e} {n:.3g}" for e, n in errors.rejected.items())
        for case, errors in analysis.cases.items())
    return (f"hajiyev (Hajiyev et al.) Section 5, {analysis.runs} Monte Carlo runs of "
            f"k = 1..{analysis.cases['constant'].iterations[-1]}. Ours: mean over runs "
            f"[95 % CI]; single runs: 5-95 % range of the runs.\n\n"
            + markdown_table(("case", "quantity", "paper", "ours"), result_rows(analysis))
            + f"\n\nSamples rejected by the estimators' gates, mean per run: {rejected}.\n")


# ------------------------------------------------------------------------------ figures


def _rms_over_runs(errors: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(errors**2, axis=0))


def _absolute_errors(ax, k, series: list[tuple[str, np.ndarray]], runs: int) -> None:
    """|error| of run 0 (thin) and the RMS over runs (thick) of each series."""
    for label, errors in series:
        line, = ax.plot(k, np.abs(errors[0]), linewidth=0.6, alpha=0.7,
                        label=f"{label}: |error|, run 0")
        ax.plot(k, _rms_over_runs(errors), linewidth=1.6, color=line.get_color(),
                label=f"{label}: RMS over {runs} runs")
    ax.set_ylabel("absolute error [m]")
    ax.set_ylim(bottom=0)
    ax.legend(loc="upper left", fontsize=7)


def plot_figures(analysis: HajiyevAnalysis, out: Path) -> list[Path]:
    """The equivalents of Figs. 4, 6, 8, 9 and 10."""
    constant, drift, runs = analysis.cases["constant"], analysis.cases["drift"], analysis.runs
    k = constant.iterations
    paths = []

    fig, axes = figure(3)
    for ax, (label, errors, sigma) in zip(axes, (
            ("baro", constant.baro, R_BARO**0.5), ("GPS", constant.gps, R_GPS**0.5),
            ("fused, non-adaptive", constant.fused["non-adaptive"], FUSED_VARIANCE**0.5)),
            strict=True):
        _absolute_errors(ax, k, [(label, errors)], runs)
        ax.axhline(sigma, color="black", linestyle=":", linewidth=0.9,
                   label=f"σ = {sigma:.3g} m")
        ax.legend(loc="upper left", fontsize=7)
    axes[0].set_title("Figs. 2-4 equivalent, constant p0 and T0: absolute errors of the baro, "
                      "the GPS and the Baro/GPS fusion", fontsize=9)
    axes[-1].set_xlabel("iteration k (1 s)")
    paths.append(save_figure(fig, out / "hajiyev_fig4.png"))

    for variant, number in (("non-adaptive", 6), ("adaptive", 8)):
        fig, axes = figure(2)
        series = [("baro", drift.baro), ("GPS", drift.gps),
                  (f"fused, {variant}", drift.fused[variant])]
        for ax in axes:
            _absolute_errors(ax, k, series, runs)
        axes[1].set_ylim(0, 80)
        axes[1].set_title("the same, up to 80 m", fontsize=8)
        axes[0].set_title(f"Fig. {number} equivalent, p0 and T0 drifting from k = 23: absolute "
                          f"errors, {variant} fusion", fontsize=9)
        axes[-1].set_xlabel("iteration k (1 s)")
        paths.append(save_figure(fig, out / f"hajiyev_fig{number}.png"))

    fig, axes = figure(2)
    series = [(f"fused, {e}", drift.fused[e]) for e in ("non-adaptive", "adaptive", "BaselineKF")]
    for ax in axes:
        _absolute_errors(ax, k, series, runs)
    axes[1].set_ylim(0, 80)
    axes[1].set_title("the same, up to 80 m", fontsize=8)
    axes[0].set_title("Fig. 9 equivalent, drift: adaptive versus non-adaptive fusion "
                      "(BaselineKF beside)", fontsize=9)
    axes[-1].set_xlabel("iteration k (1 s)")
    paths.append(save_figure(fig, out / "hajiyev_fig9.png"))

    fig, axes = figure(1)
    factor = drift.adaptive_factor["adaptive"]
    ax = axes[0]
    ax.semilogy(k, factor[0], linewidth=0.7, label="S(k), run 0")
    low, median, high = np.percentile(factor, [5, 50, 95], axis=0)
    ax.semilogy(k, median, linewidth=1.6, label=f"median over {runs} runs")
    ax.fill_between(k, low, high, alpha=0.2, linewidth=0, label="5-95 % of the runs")
    ax.set_ylabel("adaptive factor S(k)")
    ax.set_xlabel("iteration k (1 s)")
    ax.legend(loc="upper left", fontsize=7)
    ax.set_title("Fig. 10 equivalent, drift: adaptive factor S(k) (eq. 30; 1 when eq. 28 "
                 "fails)", fontsize=9)
    paths.append(save_figure(fig, out / "hajiyev_fig10.png"))
    return paths


# ------------------------------------------------------------------------------ command


def reproduce(options: ReproduceOptions) -> int:
    """Run (or complete) the campaigns, write the figures and the table, print it."""
    return run_reproduction(options, "hajiyev", CAMPAIGNS, DEFAULT_RUNS, analyse,
                            format_table, plot_figures)
