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

With ``--priors`` AltitudeEKF is told the noises only, then the noises and one group of the
stated error models at a time (:data:`PRIOR_GROUPS`), then all of them: which stated model
carries the paper estimator's advantage over AltitudeEKF told only the noises.

Run by hand (models/ built):
``python benchmarks/altitude_ekf_scenarios.py [--runs N] [--priors] [SCENARIO ...]``;
the core backend steps the components in-process (same numbers as the FMUs, faster).
"""

import argparse
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


PRIOR_GROUPS = {"baro offset": ("P0_offset",), "baro scale": ("P0_scale", "baro_scale_psd"),
                "baro walk": ("baro_bias_psd",),
                "terrain": ("terrain_h", "P0_terrain", "terrain_psd"),
                "accelerometer bias": ("P0_acc_bias", "acc_bias_psd")}
"""The stated error models in groups, each told on its own with ``--priors``."""


def noises(name: str) -> dict:
    """AltitudeEKF's noise parameters in system ``name``: its sensors' true noises."""
    system = build_system(name)
    return sensor_noise(system, {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components})


def parameters(name: str) -> dict:
    """AltitudeEKF's parameters in system ``name``: its sensors' noises and error models."""
    return {**noises(name), **SENSOR_ERRORS[name]}


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


def run(name: str, runs: int, told: dict) -> tuple[float, float, float]:
    """The paper estimator's and AltitudeEKF's RMS error and AltitudeEKF's coverage over
    ``runs`` seeded runs of system ``name``, AltitudeEKF told the parameters ``told``."""
    truth = TRUTH.get(name, "plant.h")
    system = with_observer(name, told)
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


def told_variants(name: str, priors: bool) -> dict[str, dict]:
    """What AltitudeEKF is told in system ``name``: the noises and every stated error model,
    or (``priors``) the noises alone, with each group of error models, with all."""
    stated = SENSOR_ERRORS[name]
    if not priors:
        return {"models": parameters(name)}
    noise = noises(name)
    groups = {group: {key: stated[key] for key in keys if key in stated}
              for group, keys in PRIOR_GROUPS.items()}
    return {"noise": noise,
            **{f"noise + {group}": {**noise, **told} for group, told in groups.items() if told},
            "models": parameters(name)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="*", default=list(SENSOR_ERRORS))
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--priors", action="store_true",
                        help="told the noises, then each group of stated error models")
    args = parser.parse_args()
    print(f"{'scenario':16s} {'told':30s} {'paper RMS m':>12s} {'AltitudeEKF RMS m':>18s} "
          f"{'coverage':>9s}")
    for name in args.scenarios:
        for label, told in told_variants(name, args.priors).items():
            paper, ekf, coverage = run(name, args.runs, told)
            print(f"{name:16s} {label:30s} {paper:12.4g} {ekf:18.4g} {100 * coverage:8.1f}%",
                  flush=True)


if __name__ == "__main__":
    main()
