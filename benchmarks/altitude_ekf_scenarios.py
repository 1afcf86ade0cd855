"""AltitudeEKF beside each paper's estimator in the paper's own scenario (issue 16's targets).

Each paper system of the catalog gets AltitudeEKF as an observer component ``ekf`` (wired to
the same sensor outputs with ``systems.wiring.estimator_connections``, stepped with the
paper's estimator; in the closed loops the aircraft still flies on the paper's estimate),
configured as ``altfusion evaluate`` configures it: the sensors' true noises by their contract
names (``evaluation.scenarios.sensor_noise``) and the system's sensor error models
(``systems.error_models.SENSOR_ERRORS``, the one table both use). Both estimators see the same
seeded sensor samples. Printed per scenario: the height RMS error of the paper's estimator
and of AltitudeEKF over all runs, and AltitudeEKF's coverage, the share of samples with
|e| <= 2 h_std after the first ``SETTLE`` seconds (target 85-99.5 %).

Run by hand (models/ built): ``python benchmarks/altitude_ekf_scenarios.py [RUNS]``;
the core backend steps the components in-process (same numbers as the FMUs, faster).
"""

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from altfusion.cosim import Simulation
from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.evaluation.scenarios import sensor_noise
from altfusion.systems import build_system
from altfusion.systems.error_models import SENSOR_ERRORS
from altfusion.systems.spec import ComponentSpec
from altfusion.systems.wiring import estimator_connections

MODELS = Path(__file__).resolve().parent.parent / "models"
SETTLE = 10.0
"""Seconds after the start left out of the coverage (the filter's start transient)."""

TRUTH = {"hajiyev": "truth.gps_h", "hajiyev_drift": "truth.gps_h"}
"""Truth column of the systems whose aircraft starts away from the sensors' placeholder
(default: ``plant.h``)."""

SEEDED = ("air_data", "gnss", "accelerometer", "radar", "laser", "atmosphere")


def parameters(name: str) -> dict:
    """AltitudeEKF's parameters in system ``name``: its sensors' noises and error models."""
    system = build_system(name)
    fmus = {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components}
    return {**sensor_noise(system, fmus), **SENSOR_ERRORS[name]}


def with_observer(name: str, parameters: dict):
    """The catalog system ``name`` with AltitudeEKF as observer component ``ekf``."""
    system = build_system(name)
    step = next(c.step_size for c in system.components if c.name == "estimator")
    present = {c.name for c in system.components}
    wiring = estimator_connections(AltitudeEKF, "ekf", sensors=tuple(present))
    return replace(system, components=system.components + (
        ComponentSpec("ekf", "AltitudeEKF", step, parameters),),
        connections=system.connections + wiring,
        record=tuple(dict.fromkeys(system.record + ("estimator.h_est", "ekf.h_est",
                                                    "ekf.h_std"))))


def run(name: str, runs: int) -> tuple[float, float, float]:
    truth = TRUTH.get(name, "plant.h")
    system = with_observer(name, parameters(name))
    fmus = {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components}
    present = {c.name for c in system.components}
    paper, ekf, covered = [], [], []
    with Simulation(system, fmus, backend="core") as sim:
        for i in range(runs):
            seeds = {f"{c}.seed": 1000 * (i + 1) + k for k, c in enumerate(SEEDED)
                     if c in present}
            r = sim.run(parameters=seeds)
            keep = r.time >= SETTLE
            t_true = r[truth]
            paper.append((r["estimator.h_est"] - t_true)[keep])
            e = (r["ekf.h_est"] - t_true)[keep]
            ekf.append(e)
            covered.append(np.abs(e) <= 2.0 * r["ekf.h_std"][keep])
    rms = [float(np.sqrt(np.mean(np.concatenate(x) ** 2))) for x in (paper, ekf)]
    return rms[0], rms[1], float(np.mean(np.concatenate(covered)))


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    names = sys.argv[2:] or list(SENSOR_ERRORS)
    print(f"{'scenario':26s} {'paper RMS m':>12s} {'AltitudeEKF RMS m':>18s} {'coverage':>9s}")
    for name in names:
        paper, ekf, coverage = run(name, runs)
        print(f"{name:26s} {paper:12.4g} {ekf:18.4g} {100 * coverage:8.1f}%", flush=True)


if __name__ == "__main__":
    main()
