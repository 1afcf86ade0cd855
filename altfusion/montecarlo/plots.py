"""Plots of campaign statistics (matplotlib, no display needed); each returns the PNG path."""

from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from altfusion.atomic import save_figure  # noqa: E402
from altfusion.montecarlo.aggregation import (  # noqa: E402
    CampaignStatistics,
    MetricStatistics,
    SignalEnvelope,
)

MAX_PANELS = 6
DPI = 110


def _by_unit(items: list, unit: Callable) -> dict[str, list]:
    groups: dict[str, list] = {}
    for item in items:
        groups.setdefault(unit(item), []).append(item)
    return dict(list(groups.items())[:MAX_PANELS])


def _save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI)
    plt.close(fig)
    return path


def _panels(count: int, height: float = 2.4):
    fig, axes = plt.subplots(count, 1, sharex=True, figsize=(9, height * count + 0.8),
                             squeeze=False)
    return fig, axes[:, 0]


def _subtitle(statistics: CampaignStatistics, bands: bool = True) -> str:
    text = f"{statistics.manifest['system']['name']}: {len(statistics.runs)} runs"
    return text + (f", {100 * statistics.confidence:g} % confidence bands" if bands else "")


def plot_rms_versus_time(statistics: CampaignStatistics, path: Path,
                         series: list[tuple[str, MetricStatistics]] | None = None) -> Path:
    """RMS error over runs versus time, one panel per unit, chi-square band (whang2008 Fig. 3),
    on a log axis: estimators whose errors differ a thousandfold stay readable side by side.

    ``series`` (label, metric statistics) overrides the campaign's own metrics, e.g. to
    overlay several estimators.
    """
    series = series or [(m.metric.name, m) for m in statistics.metrics]
    groups = _by_unit(series, lambda item: item[1].unit)
    fig, axes = _panels(len(groups))
    for ax, (unit, items) in zip(axes, groups.items(), strict=True):
        for label, metric in items:
            line, = ax.plot(statistics.time, metric.profile.rms, linewidth=1.2, label=label)
            ax.fill_between(statistics.time, metric.profile.rms_low, metric.profile.rms_high,
                            color=line.get_color(), alpha=0.2, linewidth=0)
        ax.set_ylabel(f"RMS error [{unit}] (log)" if unit else "RMS error (log)")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"RMS error versus time - {_subtitle(statistics)}", fontsize=9)
    return _save(fig, path)


MEAN_PANELS = 12
"""At most this many metrics get a mean-error panel (two a row)."""


def plot_mean_error_versus_time(statistics: CampaignStatistics, path: Path) -> Path:
    """Mean error over runs versus time with its t band, one panel per metric, each on its
    own axis (an estimator's 0.4 m beside another's 500 m), the axis fitted to the mean and
    the band clipped to it (two runs give a band of 9 standard deviations)."""
    metrics = statistics.metrics[:MEAN_PANELS]
    columns = min(2, len(metrics))
    rows = -(-len(metrics) // columns)
    fig, axes = plt.subplots(rows, columns, sharex=True, squeeze=False,
                             figsize=(4.6 * columns + 0.4, 2.0 * rows + 0.8))
    for ax in axes.flat[len(metrics):]:
        ax.set_visible(False)
    for ax, metric in zip(axes.flat, metrics, strict=False):
        profile = metric.profile
        line, = ax.plot(statistics.time, profile.mean, linewidth=1.0, label="mean")
        if profile.mean_low is not None:
            ax.fill_between(statistics.time, profile.mean_low, profile.mean_high,
                            color=line.get_color(), alpha=0.2, linewidth=0,
                            label=f"{100 * statistics.confidence:g} % band")
        ax.axhline(0.0, color="black", linewidth=0.6)
        finite = np.abs(profile.mean[np.isfinite(profile.mean)])
        if finite.size and np.percentile(finite, 99.5) > 0:
            limit = 1.5 * float(np.percentile(finite, 99.5))
            ax.set_ylim(-limit, limit)
        ax.set_title(metric.metric.name, fontsize=9)
        ax.set_ylabel(f"mean error [{metric.unit}]" if metric.unit else "mean error",
                      fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]", fontsize=8)
    fig.suptitle(f"Mean error versus time - {_subtitle(statistics)}", fontsize=9)
    return _save(fig, path)


HISTOGRAM_COLUMNS = 3
"""Histogram panels per row: three 3.1 in panels at 110 dpi fill about 1000 px, the report's
width, so the plot is shown at its own size."""


def plot_run_rms_histograms(statistics: CampaignStatistics, path: Path) -> Path:
    """Histogram of the per-run RMS error of each metric, three panels a row."""
    metrics = statistics.metrics[:MAX_PANELS]
    columns = min(len(metrics), HISTOGRAM_COLUMNS)
    rows = -(-len(metrics) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.1 * columns + 0.4, 2.6 * rows + 0.5),
                             squeeze=False)
    for ax in axes.flat[len(metrics):]:
        ax.set_visible(False)
    for ax, metric in zip(axes.flat, metrics, strict=False):
        bins = max(5, min(40, int(round(2 * len(metric.run_rms) ** (1 / 3)))))
        ax.hist(metric.run_rms, bins=bins, color="tab:blue", alpha=0.8)
        ax.axvline(metric.rms, color="black", linewidth=1, label=f"overall {metric.rms:.3g}")
        ax.set_xlabel(f"run RMS error [{metric.unit}]" if metric.unit else "run RMS error")
        ax.set_ylabel("runs")
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.xaxis.set_major_locator(MaxNLocator(4))
        ax.tick_params(labelsize=8)
        ax.set_title(metric.metric.name, fontsize=9)
        ax.legend(fontsize=7)
    fig.suptitle(f"Per-run RMS error - {_subtitle(statistics, bands=False)}", fontsize=9)
    return _save(fig, path)


def plot_signal_envelopes(statistics: CampaignStatistics, path: Path) -> Path:
    """Each recorded signal over runs: mean, ±σ band and min-max range, one panel per unit."""
    groups = _by_unit(statistics.signals, lambda s: s.unit)
    fig, axes = _panels(len(groups), height=2.2)
    for ax, (unit, signals) in zip(axes, groups.items(), strict=True):
        for signal in signals:
            _envelope(ax, statistics, signal)
        ax.set_ylabel(f"[{unit}]" if unit else "")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=7)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"Recorded signals: mean, ±σ, min-max - {_subtitle(statistics, bands=False)}",
                 fontsize=9)
    return _save(fig, path)


def _envelope(ax, statistics: CampaignStatistics, signal: SignalEnvelope) -> None:
    line, = ax.plot(statistics.time, signal.mean, linewidth=1, label=signal.name)
    color = line.get_color()
    ax.fill_between(statistics.time, signal.mean - signal.std, signal.mean + signal.std,
                    color=color, alpha=0.25, linewidth=0)
    ax.fill_between(statistics.time, signal.minimum, signal.maximum, color=color, alpha=0.1,
                    linewidth=0)
