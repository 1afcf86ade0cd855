"""AltitudeEKF through the fault suite (docs/faults.md) on the suite's flight.

    python benchmarks/altitude_ekf_faults.py [FAULT ...]

Each scenario of ``altfusion.systems.faults.FAULTS`` is applied to ``fault_flight`` with
AltitudeEKF alone (given the flight's true noises and its flat terrain, ``TRUE_NOISE``), and
scored with ``altfusion.scores`` against the same flight without a fault (the SensorFaults
component set to ``none``, same seeds): coverage |e| <= 2 h_std outside the fault's
transient, seconds to isolate each source the scenario expects isolated (<= 10 s), the RMS
after the transient against 3x the nominal RMS, ``h_valid`` false within ``aiding_timeout``
when every sensor stops (``silent``), and finite outputs throughout. Printed one line per
scenario.
"""

import math
import sys
from pathlib import Path

import numpy as np

from altfusion.cosim import Simulation
from altfusion.scores import HONEST_COVERAGE, coverage, isolation_time, recovered
from altfusion.systems.faults import FAULTS, fault_flight, with_fault

MODELS = Path(__file__).resolve().parents[1] / "models"
NAME = "AltitudeEKF"
AIDING_TIMEOUT = 5.0
ISOLATE_WITHIN = 10.0


def main() -> None:
    names = sys.argv[1:] or list(FAULTS)
    print(f"{'fault':24s} {'coverage':>9s} {'isolated after':>15s} {'RMS after / 3x nominal':>24s}"
          f"  verdict")
    for name in names:
        fault = FAULTS[name]
        system = with_fault(fault_flight((NAME,)), name)
        fmus = {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components}
        with Simulation(system, fmus, "core") as simulation:
            nominal = simulation.run(parameters={"fault.scenario": "none"})
            run = simulation.run()
        t = run.time
        error, std = run[f"{NAME}.h_est"] - run["plant.h"], run[f"{NAME}.h_std"]
        valid, status = run[f"{NAME}.h_valid"], run[f"{NAME}.status"]
        end = fault.start + fault.transient
        cover = coverage(t, error, std, valid, ((fault.start, end),) if fault.transient else ())
        ok = bool(np.all(np.isfinite(run[f"{NAME}.h_est"])))
        ok &= math.isnan(cover) or HONEST_COVERAGE[0] <= cover <= HONEST_COVERAGE[1]
        isolated = {s: isolation_time(t, status, s, fault.start) for s in fault.faulty}
        ok &= all(v is not None and v <= ISOLATE_WITHIN for v in isolated.values())
        back, after, nominal_rms = recovered(
            t, error, valid, nominal[f"{NAME}.h_est"] - nominal["plant.h"],
            nominal[f"{NAME}.h_valid"], end)
        ok &= back
        if name == "silent":
            invalid = t[(t >= fault.start) & (valid < 0.5)]
            ok &= bool(len(invalid)) and invalid[0] - fault.start <= AIDING_TIMEOUT + 0.1
        iso = ", ".join(f"{s} {'never' if v is None else f'{v:.1f} s'}"
                        for s, v in isolated.items()) or "-"
        print(f"{name:24s} {100 * cover:8.1f}% {iso:>15s} {after:10.3g} / {3 * nominal_rms:<10.3g}"
              f"   {'pass' if ok else 'FAIL'}", flush=True)


if __name__ == "__main__":
    main()
