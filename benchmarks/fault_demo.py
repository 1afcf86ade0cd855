"""The fault demonstration (``altfusion.systems.fault_demo``): yang2020's loop flown through an
accelerometer bias, a GNSS outage and a failed barometer, on AltitudeEKF and on YangFusionKF.

    python benchmarks/fault_demo.py [--out docs/fault_demo.png] [--backend fmu|core]

Prints each estimator's RMS height error and coverage (|e| <= 2 h_std) per phase of the
flight and its largest error,
whether ``h_valid`` held, and draws both errors (with each filter's ±2 h_std) over the
flight into ``--out`` (the README's figure). Needs the built models/.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from altfusion.cosim import Simulation  # noqa: E402
from altfusion.systems import build_system  # noqa: E402
from altfusion.systems.fault_demo import ACC_BIAS, BARO_FAILURE, GPS_OUTAGE  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SYSTEMS = {"AltitudeEKF": "fault_demo_altitude_ekf", "YangFusionKF": "fault_demo_yang"}
PHASES = {"before the faults (5 s-100 s, acc bias only)": (5.0, GPS_OUTAGE[0]),
          "GNSS outage": GPS_OUTAGE,
          "GNSS back, baro healthy": (GPS_OUTAGE[1], BARO_FAILURE),
          "baro failed (+200 m)": (BARO_FAILURE, 420.0)}


def fly(name: str, backend: str):
    system = build_system(name)
    fmus = {c.fmu: ROOT / "models" / f"{c.fmu}.fmu" for c in system.components}
    with Simulation(system, fmus, backend) as simulation:
        return simulation.run()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "fault_demo.png")
    parser.add_argument("--backend", choices=("fmu", "core"), default="fmu")
    args = parser.parse_args()
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for (label, system), ax in zip(SYSTEMS.items(), axes, strict=True):
        r = fly(system, args.backend)
        t, e = r.time, r["estimator.h_est"] - r["plant.h"]
        std = r["estimator.h_std"]
        valid = r["estimator.h_valid"] > 0.5
        flight = t >= 5.0
        print(f"{label}: largest |error| {np.max(np.abs(e[flight])):.3g} m, RMS "
              f"{np.sqrt(np.mean(e[flight] ** 2)):.3g} m, |e| <= 2 h_std "
              f"{100 * np.mean(np.abs(e[flight]) <= 2 * std[flight]):.1f} % from 5 s; h_valid "
              f"{100 * np.mean(valid[t >= 1.0]):.1f} % of the flight")
        for phase, (start, end) in PHASES.items():
            k = (t >= start) & (t < end)
            print(f"  {phase:45s} RMS {np.sqrt(np.mean(e[k] ** 2)):8.3g} m, |e| <= 2 h_std "
                  f"{100 * np.mean(np.abs(e[k]) <= 2 * std[k]):5.1f} %")
        ax.fill_between(t, -2 * std, 2 * std, color="C0", alpha=0.2, label="±2 h_std")
        ax.plot(t, e, color="C0", lw=0.8, label="h_est - h")
        ax.axvspan(*GPS_OUTAGE, color="0.85", zorder=0, label="GNSS outage")   # behind the band
        ax.axvline(BARO_FAILURE, color="C3", ls="--", label="baro +200 m")
        ax.set_yscale("symlog", linthresh=2.0)
        ax.set_ylim(-300, 300)
        ax.set_ylabel("height error, m (symlog)")
        ax.set_title(f"{label} (flies on its own estimate)", fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8, ncol=4)
    axes[-1].set_xlabel("time, s")
    fig.suptitle(f"yang2020's climb/cruise/descent through faults: accelerometer bias "
                 f"{ACC_BIAS:g} m/s², GNSS outage, failed barometer", fontsize=11)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
