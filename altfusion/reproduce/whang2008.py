"""``altfusion reproduce whang2008``: whang2008 Section 3 (Whang & Ra 2008), Fig. 3.

Two campaigns with the same master seed, so run i of both sees the same weather and sensor
noise (``altfusion.systems.whang2008`` describes the scenario):

* ``WhangGAEstimator/``: catalog system ``whang2008``, the paper's estimator with the
  paper's parameters;
* ``BaselineKF/``: catalog system ``whang2008_baseline``, the same scenario with BaselineKF.

Written to the output folder: ``whang2008_fig3.png`` (Fig. 2's trajectory of run 0 above the
Fig. 3 equivalent: RMS over runs versus time of the baro-height, GPS, compensated-height
(h^c, eq. 32) and final-height errors, and BaselineKF's final height, with 95 % chi-square
bands) and ``whang2008.md`` (the tables printed at the end).

Statistics. RMS versus time over runs at every output time (0.2 s); the GPS error only at
its samples (whole seconds: between them the GPS output holds while the vehicle climbs at
10 m/s). RMS over a time window pools the window's samples of every run, with a 95 %
interval that takes each run as one independent sample. Windows: the flight (0, 600] s,
below 1800 m (0, 200] s, the climb to 4000 m (200, 440] s and the cruise at 4000 m
(440, 600] s, where the weather has changed the baro's scale factor most; and consecutive
10 s windows, for "below the GPS level at every time".

The paper gives no numbers, only Fig. 3 and its reading: the estimator "can suppress the
height estimation errors under the GPS error level" (R_GPS = 70² m²). The claims table
checks that, and how the final height compares with the compensated height and with the raw
baro-height once the weather has drifted.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.reproduce import ReproduceOptions
from altfusion.reproduce.common import (
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
from altfusion.systems.whang2008 import GPS_PERIOD, STOP_TIME

DEFAULT_RUNS = 50
"""Section 3: 50 Monte Carlo trials."""

GPS_SIGMA = 70.0
"""Section 3: R_GPS = 70² m², the "GPS error level" of Fig. 3."""

CLIMB_END = 440.0
"""Profile ``whang2008`` reaches 4000 m at 440 s."""

LOW_END = 200.0
"""Below 1800 m (the first 200 s) the weather has changed the baro's error little."""

WINDOWS = {"flight": (0.0, STOP_TIME), "low": (0.0, LOW_END), "climb": (LOW_END, CLIMB_END),
           "cruise": (CLIMB_END, STOP_TIME)}
"""Time windows (start, end] of the overall RMS, s."""

WINDOW_LABELS = {"flight": "flight", "low": "below 1800 m", "climb": "climb to 4000 m",
                 "cruise": "cruise at 4000 m"}

SHORT_WINDOW = 10.0
"""Width of the windows over which "below the GPS level at every time" is checked, s: one
lapse-rate period, 50 air-data samples per run (the RMS of single instants over 50 runs
scatters by ±20 % at 95 %)."""

CAMPAIGNS = (
    Campaign("WhangGAEstimator", "WhangGAEstimator", "whang2008"),
    Campaign("BaselineKF", "BaselineKF", "whang2008_baseline"),
)

CURVES = ("baro", "GPS", "compensated", "final", "BaselineKF final")
LABELS = {"baro": "baro-height error", "GPS": "GPS height error",
          "compensated": "compensated height h^c error (eq. 32)",
          "final": "final height error (WhangGAEstimator)",
          "BaselineKF final": "final height error (BaselineKF)"}

REFERENCES = (
    Reference("whang2008", ("plant.h", "atmosphere.lapse_rate_actual", "air_data.baro_h",
                            "air_data.baro_T", "gnss.gps_h", "estimator.h_est",
                            "estimator.h_comp", "estimator.scale_factor", "estimator.bias"),
              interval=10.0),
    Reference("whang2008_baseline", ("plant.h", "air_data.baro_h", "gnss.gps_h",
                                     "estimator.h_est", "estimator.bias"), interval=10.0),
)
"""Reference CSVs in tests/data/reference (see ``altfusion.reproduce.common``)."""


@dataclass
class WhangAnalysis:
    """What the figure and the tables show."""

    runs: int
    time: np.ndarray
    altitude: np.ndarray
    """Run 0's true altitude (Fig. 2's trajectory)."""
    curves: dict[str, RmsCurve]
    """RMS versus time, by the names of ``CURVES``."""
    windows: dict[tuple[str, str], Estimate]
    """RMS over (curve, window of ``WINDOWS``)."""
    short_windows: dict[str, tuple[np.ndarray, np.ndarray]]
    """By curve: (end times, RMS over runs) of consecutive ``SHORT_WINDOW`` windows."""
    rejected: dict[str, float]
    """Mean GPS or baro samples per run rejected by each estimator's innovation gate."""

    def rms(self, curve: str, window: str = "flight") -> float:
        return self.windows[curve, window].value


def analyse(out: Path) -> WhangAnalysis:
    """The statistics of the two campaigns in ``out``."""
    whang = load_runs(Path(out) / "WhangGAEstimator",
                      ("plant.h", "air_data.baro_h", "gnss.gps_h", "estimator.h_comp",
                       "estimator.h_est", "estimator.n_rejected"))
    baseline = load_runs(Path(out) / "BaselineKF",
                         ("plant.h", "estimator.h_est", "estimator.n_rejected"))
    if whang.runs != baseline.runs or not np.array_equal(whang["plant.h"], baseline["plant.h"]):
        raise ValueError(f"the campaigns in {out} are not the same runs of one scenario")
    time = whang.time
    gps_rows = np.isclose(time / GPS_PERIOD, np.round(time / GPS_PERIOD))
    errors = {
        "baro": (time, whang.error("air_data.baro_h", "plant.h")),
        "GPS": (time[gps_rows], whang.error("gnss.gps_h", "plant.h")[:, gps_rows]),
        "compensated": (time, whang.error("estimator.h_comp", "plant.h")),
        "final": (time, whang.error("estimator.h_est", "plant.h")),
        "BaselineKF final": (time, baseline.error("estimator.h_est", "plant.h")),
    }
    curves = {name: rms_curve(LABELS[name], t, e) for name, (t, e) in errors.items()}
    windows = {}
    for name, (t, e) in errors.items():
        for window, (start, end) in WINDOWS.items():
            inside = (t > start) & (t <= end)
            windows[name, window] = rms_over_runs(e[:, inside])
    short_windows = {name: short_window_rms(t, e) for name, (t, e) in errors.items()}
    rejected = {"WhangGAEstimator": float(whang["estimator.n_rejected"][:, -1].mean()),
                "BaselineKF": float(baseline["estimator.n_rejected"][:, -1].mean())}
    return WhangAnalysis(len(whang.runs), time, whang["plant.h"][0], curves, windows,
                         short_windows, rejected)


def short_window_rms(time: np.ndarray, errors: np.ndarray,
                     width: float = SHORT_WINDOW) -> tuple[np.ndarray, np.ndarray]:
    """RMS over runs and the samples of each window (end - width, end], end = width, 2·width,
    ..., up to the last time."""
    ends = np.arange(width, time[-1] + width / 2, width)
    rms = [np.sqrt(np.mean(errors[:, (time > end - width) & (time <= end)] ** 2))
           for end in ends]
    return ends, np.array(rms)


# ------------------------------------------------------------------------------ tables


def window_table(analysis: WhangAnalysis) -> str:
    """RMS error by window, with intervals."""
    header = ("error", *(f"RMS {WINDOW_LABELS[w]} ({s:g}-{e:g} s) [m]"
                         for w, (s, e) in WINDOWS.items()))
    rows = [(LABELS[name], *(analysis.windows[name, w].text(3) for w in WINDOWS))
            for name in CURVES]
    return markdown_table(header, rows)


def clearly_below(a: Estimate, b: Estimate) -> bool:
    """a < b with non-overlapping intervals (values alone for a single run)."""
    if a.interval is None or b.interval is None:
        return a.value < b.value
    return a.interval.high < b.interval.low


def claims_table(analysis: WhangAnalysis) -> str:
    """The paper's reading of Fig. 3 beside our numbers."""
    a = analysis
    final_curve = a.curves["final"]
    worst = int(np.argmax(final_curve.rms))
    ends, short = a.short_windows["final"]
    worst_window = int(np.argmax(short))

    def verdict(holds: bool) -> str:
        return "yes" if holds else "**no**"

    rows = [
        ("final height RMS below the GPS error level (70 m), whole flight",
         "yes (Fig. 3: \"under the GPS error level\")",
         f"{a.windows['final', 'flight'].text(3)} m vs GPS "
         f"{a.windows['GPS', 'flight'].text(3)} m",
         verdict(a.rms("final") < min(GPS_SIGMA, a.rms("GPS")))),
        (f"final height RMS below the GPS level at every time ({SHORT_WINDOW:g} s windows)",
         "yes (Fig. 3)",
         f"largest {short[worst_window]:.3g} m ({ends[worst_window] - SHORT_WINDOW:g}-"
         f"{ends[worst_window]:g} s); single instants: largest {final_curve.rms[worst]:.3g} m "
         f"at {a.time[worst]:g} s, band {final_curve.low[worst]:.3g}-"
         f"{final_curve.high[worst]:.3g} m",
         verdict(short.max() < GPS_SIGMA)),
        ("filtering improves on the compensated height h^c",
         "yes (Fig. 3: final below h^c)",
         f"final {a.rms('final'):.3g} m vs h^c {a.rms('compensated'):.3g} m",
         verdict(a.rms("final") < a.rms("compensated"))),
        ("final height well below the raw baro error once the weather has drifted (cruise; "
         "holds if the 95 % intervals do not overlap)",
         "yes (Fig. 3: baro error grows with height)",
         f"final {a.windows['final', 'cruise'].text(3)} m vs baro "
         f"{a.windows['baro', 'cruise'].text(3)} m (ratio "
         f"{a.rms('final', 'cruise') / a.rms('baro', 'cruise'):.2f})",
         verdict(clearly_below(a.windows["final", "cruise"], a.windows["baro", "cruise"]))),
        ("(not in the paper) final height versus raw baro below 1800 m", "-",
         f"final {a.windows['final', 'low'].text(3)} m vs baro "
         f"{a.windows['baro', 'low'].text(3)} m", "-"),
        ("BaselineKF (not in the paper), whole flight / cruise",
         "-",
         f"{a.windows['BaselineKF final', 'flight'].text(3)} m / "
         f"{a.windows['BaselineKF final', 'cruise'].text(3)} m",
         "-"),
    ]
    return markdown_table(("claim", "paper", f"ours ({a.runs} runs, [95 % CI])", "holds"),
                          rows)


def format_tables(analysis: WhangAnalysis) -> str:
    rejected = ", ".join(f"{name} {count:.3g}" for name, count in analysis.rejected.items())
    return (f"whang2008 (Whang & Ra 2008) Section 3, {analysis.runs} Monte Carlo runs.\n\n"
            f"{claims_table(analysis)}\n\n{window_table(analysis)}\n\n"
            f"Samples rejected by the innovation gates, mean per run: {rejected}.\n")


# ------------------------------------------------------------------------------ figure


def plot_fig3(analysis: WhangAnalysis, path: Path) -> Path:
    """Fig. 2 (run 0's trajectory) above the Fig. 3 equivalent."""
    fig, (top, bottom) = figure(2, height_ratios=(1, 3))
    top.plot(analysis.time, analysis.altitude, color="black", linewidth=1)
    top.set_ylabel("altitude [m]")
    top.set_title("Fig. 2 equivalent: trajectory (profile 'whang2008')", fontsize=9)
    styles = {"BaselineKF final": {"linestyle": "--"}}
    for name in CURVES:
        curve = analysis.curves[name]
        line, = bottom.plot(curve.time, curve.rms, linewidth=1.1, label=curve.label,
                            **styles.get(name, {}))
        bottom.fill_between(curve.time, curve.low, curve.high, color=line.get_color(),
                            alpha=0.18, linewidth=0)
    bottom.axhline(GPS_SIGMA, color="grey", linewidth=0.8, linestyle=":",
                   label="GPS error level (70 m)")
    bottom.set_ylabel("RMS error [m]")
    bottom.set_xlabel("time [s]")
    bottom.set_ylim(bottom=0)
    bottom.legend(loc="upper left", fontsize=8)
    bottom.set_title(f"Fig. 3 equivalent: RMS errors over {analysis.runs} runs "
                     f"(95 % chi-square bands)", fontsize=9)
    return save_figure(fig, path)


# ------------------------------------------------------------------------------ command


def reproduce(options: ReproduceOptions) -> int:
    """Run (or complete) the campaigns, write the figure and the tables, print them."""
    return run_reproduction(options, "whang2008", CAMPAIGNS, DEFAULT_RUNS, analyse,
                            format_tables,
                            lambda a, out: [plot_fig3(a, out / "whang2008_fig3.png")])
