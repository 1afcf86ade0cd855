"""Plots of co-simulation results (matplotlib, no display needed)."""

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from altfusion.atomic import save_figure  # noqa: E402
from altfusion.cosim.results import Results  # noqa: E402

MAX_PANELS = 6


def plot_results(results: Results, path: Path, title: str, subtitle: str = "") -> Path:
    """One panel per unit (the first ``MAX_PANELS`` units), every column of that unit in it."""
    by_unit: dict[str, list[str]] = {}
    for name in results.columns:
        by_unit.setdefault(results.units.get(name, ""), []).append(name)
    units = list(by_unit)[:MAX_PANELS]
    fig, axes = plt.subplots(len(units), 1, sharex=True, figsize=(9, 2.2 * len(units) + 0.8),
                             squeeze=False)
    for ax, unit in zip(axes[:, 0], units, strict=True):
        for name in by_unit[unit]:
            ax.plot(results.time, results[name], label=name, linewidth=1)
        ax.set_ylabel(f"[{unit}]" if unit else "")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=7)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title + ("\n" + textwrap.fill(subtitle, 110) if subtitle else ""), fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return path
