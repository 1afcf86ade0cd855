"""Honesty of h_std: the coverage of |e| <= 2 h_std of every estimator in every paper system
(one run, the catalog's seeds, through the FMUs). Run by hand (never as a test):

    python benchmarks/coverage.py [SYSTEM ...]

For each estimator component (an FMU of the catalog's estimators) of each system it prints
the RMS error, the coverage over the samples ``h_valid`` declares valid, and the fraction of
time valid. An honest h_std covers 85-99.5 % (docs/faults.md; 95.4 % for a Gaussian error).
The fault suite's coverage is printed by ``system_tests/test_fault_suite.py``'s scores
(``altfusion.scores.coverage``).
"""

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from altfusion import scores
from altfusion.cosim import Simulation
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.systems import SYSTEMS, build_system

MODELS = Path(__file__).resolve().parents[1] / "models"
PAPER_SYSTEMS = ("whang2008", "whang2008_baseline", "hajiyev", "hajiyev_drift", "yang2020",
                 "yang2020_baseline", "bao2017", "xu2016_hover15", "xu2016_hover35",
                 "xu2016_multipoint", "xu2016_multipoint_wind", "fault_flight")


def estimator_components(system) -> list[str]:
    return [c.name for c in system.components if c.fmu in ESTIMATOR_CLASSES]


def measure(name: str, fmus: dict[str, Path]) -> list[tuple[str, str, float, float, float]]:
    """(component, FMU, RMS, coverage, valid fraction) of every estimator of system ``name``."""
    system = build_system(name)
    components = estimator_components(system)
    signals = [f"{c}.{s}" for c in components for s in ("h_est", "h_std", "h_valid")]
    system = replace(system, record=tuple(dict.fromkeys(("plant.h", *signals))))
    with Simulation(system, fmus) as simulation:
        results = simulation.run()
    rows = []
    for component in components:
        error = results[f"{component}.h_est"] - results["plant.h"]
        valid = results[f"{component}.h_valid"]
        covered = scores.coverage(results.time, error, results[f"{component}.h_std"], valid)
        rms = scores.window_rms(results.time, error, valid, results.time[0])
        rows.append((component, system.component(component).fmu, rms, covered,
                     float(np.mean(valid > 0.5))))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("systems", nargs="*", metavar="SYSTEM",
                        help="catalog systems (default: every paper system and fault_flight)")
    args = parser.parse_args()
    unknown = [name for name in args.systems if name not in SYSTEMS]
    if unknown:
        parser.error(f"unknown system(s) {unknown}; known: {list(SYSTEMS)}")
    args.systems = args.systems or PAPER_SYSTEMS
    fmus = {path.stem: path for path in MODELS.glob("*.fmu")}
    print(f"{'system':24}{'component':26}{'FMU':26}{'RMS m':>9}{'coverage':>10}{'valid':>7}")
    for name in args.systems:
        for component, fmu, rms, covered, valid in measure(name, fmus):
            print(f"{name:24}{component:26}{fmu:26}{rms:9.3g}{covered:10.3f}{valid:7.3f}",
                  flush=True)


if __name__ == "__main__":
    main()
