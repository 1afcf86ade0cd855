"""The fault suite's results table of docs/faults.md ("Results"), measured. Run by hand:

    python benchmarks/fault_suite_table.py

Every estimator flies ``fault_flight`` side by side, once without a fault (``none``) and once
per scenario of ``altfusion.systems.faults.FAULTS`` (same seeds; the core objects stepped
in-process, the FMUs' own numbers), as ``system_tests/test_fault_suite.py`` does. Each cell:
the RMS height error after the scenario's transient (over [start + transient, 300 s), the
samples ``h_valid`` declares valid; ``none``: the whole flight), its coverage of
|e| <= 2 h_std outside the transient, and the seconds to isolate each faulty source the
estimator reads; **bold** beyond 3x the nominal RMS over the same window; "invalid": no valid
sample in the window. Printed as the Markdown table the page holds.
"""

from pathlib import Path

import numpy as np

from altfusion.cosim import Simulation
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.scores import coverage, isolation_time, recovered, window_rms
from altfusion.systems.faults import FAULTS, fault_flight, run_parameters, with_fault

MODELS = Path(__file__).resolve().parents[1] / "models"
ESTIMATORS = tuple(ESTIMATOR_CLASSES)


def cell(results, nominal, estimator: str, fault: str) -> str:
    """One estimator's entry for one scenario (module docstring)."""
    t = results.time
    error = results[f"{estimator}.h_est"] - results["plant.h"]
    std, valid = results[f"{estimator}.h_std"], results[f"{estimator}.h_valid"]
    if fault == "none":
        return (f"{window_rms(t, error, valid, 0.0):.3g} m, "
                f"cov {coverage(t, error, std, valid):.2f}")
    scenario = FAULTS[fault]
    end = scenario.start + scenario.transient
    passed, rms, _ = recovered(t, error, valid, nominal[f"{estimator}.h_est"] - nominal["plant.h"],
                               nominal[f"{estimator}.h_valid"], end)
    if np.isnan(rms):
        return "invalid"
    excluded = ((scenario.start, end),) if scenario.transient else ()
    text = f"{rms:.3g} m" if passed else f"**{rms:.3g}** m"
    text += f", cov {coverage(t, error, std, valid, excluded):.2f}"
    for source in scenario.faulty:
        if source in ESTIMATOR_CLASSES[estimator].sources():
            seconds = isolation_time(t, results[f"{estimator}.status"], source, scenario.start)
            text += (", isolated: no" if seconds is None
                     else f", isolated in {seconds:.0f} s")
    return text


def main() -> None:
    system = with_fault(fault_flight(ESTIMATORS), next(iter(FAULTS)))
    fmus = {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components}
    with Simulation(system, fmus, "core") as simulation:
        runs = {fault: simulation.run(parameters=run_parameters(fault))
                for fault in ("none", *FAULTS)}
    print(f"| scenario | {' | '.join(ESTIMATORS)} |")
    print(f"|---|{'---|' * len(ESTIMATORS)}")
    for fault, results in runs.items():
        cells = [cell(results, runs["none"], estimator, fault) for estimator in ESTIMATORS]
        print(f"| `{fault}` | {' | '.join(cells)} |")


if __name__ == "__main__":
    main()
