"""Cost per step of AltitudeEKF against YangFusionKF (issue 16's target: at most twice).

    python benchmarks/altitude_ekf_cost.py [--stop T] [--repeat N]

Both estimators fly yang2020's closed loop (``yang2020`` and ``yang2020_altitude_ekf``:
baro and accelerometer every 10 ms, GPS every 100 ms, radio altimeter every 200 ms, the
estimator stepped every 10 ms), so each sees the same streams. Printed: the CPU time per
do_step of the estimator component,

* core: the core object stepped in-process (``Component.do_step``, timed around the call);
* FMU: the FMU's doStep through fmpy (pythonfmu's bridge included; the runner's get/set
  calls are not part of it);

the best of ``--repeat`` runs of ``--stop`` simulated seconds, and the ratio.
"""

import argparse
import time
from pathlib import Path

from altfusion.cosim import Simulation
from altfusion.systems import build_system

MODELS = Path(__file__).resolve().parents[1] / "models"
SYSTEMS = {"YangFusionKF": "yang2020", "AltitudeEKF": "yang2020_altitude_ekf"}


def estimator_cost(system_name: str, backend: str, stop: float) -> float:
    """CPU seconds per do_step of the component ``estimator``."""
    system = build_system(system_name)
    fmus = {c.fmu: MODELS / f"{c.fmu}.fmu" for c in system.components}
    spent = []
    with Simulation(system, fmus, backend) as simulation:
        simulation.run(stop_time=1.0)                      # warm-up: imports, instantiation
        component = next(c for c in simulation._components if c.name == "estimator")
        original = component.step

        def timed(t, h):
            start = time.thread_time()
            original(t, h)
            spent.append(time.thread_time() - start)

        component.step = timed
        simulation.run(stop_time=stop)
    return sum(spent) / len(spent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--stop", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"{'backend':8s} {'YangFusionKF µs':>16s} {'AltitudeEKF µs':>15s} {'ratio':>6s}")
    for backend in ("core", "fmu"):
        cost = {name: min(estimator_cost(system, backend, args.stop)
                          for _ in range(args.repeat)) for name, system in SYSTEMS.items()}
        yang, ekf = cost["YangFusionKF"] * 1e6, cost["AltitudeEKF"] * 1e6
        print(f"{backend:8s} {yang:16.1f} {ekf:15.1f} {ekf / yang:6.2f}", flush=True)


if __name__ == "__main__":
    main()
