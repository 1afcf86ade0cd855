"""The replay comparison plot: estimators vs PX4 EKF2 vs raw baro and GPS, and vs the
rangefinder over flat ground where the log has one."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from altfusion.atomic import save_figure  # noqa: E402
from altfusion.cosim.results import Results  # noqa: E402
from altfusion.replay.compare import REPLAY, new_sample_rows, range_prefix  # noqa: E402


def _samples(results: Results, prefix: str, value: str, valid: str | None = None):
    rows = new_sample_rows(results, prefix, valid)
    return results.time[rows], results[f"{REPLAY}.{value}"][rows]


def plot_replay(results: Results, estimators: list[str], path: Path, title: str,
                start: float) -> Path:
    """Heights (top), differences to EKF2 (middle) and, with a rangefinder, the ground height
    each estimate implies (bottom); the shaded span before ``start`` is offset learning."""
    ranged = range_prefix(results)
    panels = 3 if ranged else 2
    fig, axes = plt.subplots(panels, 1, sharex=True, figsize=(12, 2.9 * panels + 0.6))
    ekf_t, ekf_h = _samples(results, "ekf", "ekf_h", "ekf_valid")
    gps_t, gps_h = _samples(results, "gps", "gps_h", "gps_fix")
    baro_t, baro_h = _samples(results, "baro", "baro_h")
    offset = (float(np.median(np.interp(gps_t, baro_t, baro_h) - gps_h))
              if len(gps_t) and len(baro_t) else 0.0)
    heights = axes[0]
    heights.plot(gps_t, gps_h, ".", color="0.45", markersize=3, label="GPS (raw)")
    heights.plot(baro_t, baro_h - offset, "x", color="0.7", markersize=3,
                 label=f"baro (raw) {-offset:+.1f} m (median offset to GPS)")
    heights.plot(ekf_t, ekf_h, color="black", linewidth=2, label="PX4 EKF2")
    after = results.time >= start
    for name in estimators:
        heights.plot(results.time[after], results[f"{name}.h_est"][after], linewidth=1,
                     label=name)
    if len(gps_h):
        heights.set_ylim(gps_h.min() - 3, gps_h.max() + 3)
    heights.set_ylabel("altitude MSL [m]")
    differences = axes[1]
    for name in estimators:
        rows = new_sample_rows(results, "ekf", "ekf_valid")
        rows = rows[after[rows]]
        differences.plot(results.time[rows],
                         results[f"{name}.h_est"][rows] - results[f"{REPLAY}.ekf_h"][rows],
                         linewidth=1, label=f"{name} - EKF2")
    if len(gps_t):
        ekf_at_gps = np.interp(gps_t, ekf_t, ekf_h) if len(ekf_t) else np.nan * gps_t
        differences.plot(gps_t, gps_h - ekf_at_gps, ".", color="0.45", markersize=3,
                         label="GPS - EKF2")
    differences.set_ylabel("difference to EKF2 [m]")
    if ranged:
        ground = axes[2]
        rows = new_sample_rows(results, ranged, f"{ranged}_valid")
        measured = results[f"{REPLAY}.{ranged}_h"][rows]
        times = results.time[rows]
        valid = results[f"{REPLAY}.ekf_valid"][rows] > 0.5
        ground.plot(times[valid], results[f"{REPLAY}.ekf_h"][rows][valid] - measured[valid],
                    color="black", linewidth=2, label=f"EKF2 - {ranged}")
        for name in estimators:
            keep = times >= start
            ground.plot(times[keep], results[f"{name}.h_est"][rows][keep] - measured[keep],
                        linewidth=1, label=f"{name} - {ranged}")
        ground.set_ylabel("implied ground MSL [m]")
    for ax in axes:
        ax.axvspan(results.time[0], start, color="0.92", zorder=0)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    axes[-1].set_xlabel("log time [s] (shaded: before the offsets are learnt)")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=100)
    plt.close(fig)
    return path
