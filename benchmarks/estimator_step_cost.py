"""Cost of one estimator ``do_step``, µs, for two versions of the code in the same run.

    python benchmarks/estimator_step_cost.py [--base /tmp/base] [--stop 60] [--repeat 5]

The inputs an estimator sees in a system (default: YangFusionKF in ``yang2020``, AltitudeEKF
in ``yang2020_altitude_ekf``: 100 Hz steps, baro and accelerometer at every step, GNSS at
10 Hz, radio altimeter at 5 Hz) are recorded once, running the system's FMUs (``models/``
must be built; any version will do: both versions step the same recorded inputs). Each
version then steps a fresh estimator core over them, in a process of its own that imports
that version's ``altfusion`` (``--base``: the root of another checkout, e.g.
``git worktree add --detach /tmp/base 6300b44``), and reports the best of ``--repeat`` runs:
the CPU time (``time.process_time``: the time the process waits for a core is left out) of a
loop writing the inputs and stepping (``do_step`` and ``take_notes``, as the FMU adapter
calls them), less that of the same loop writing the inputs only, over the steps. Timings on
a shared machine still move by ±10 %: compare versions within one run.
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
CASES = (("yang2020", "YangFusionKF"), ("yang2020_altitude_ekf", "AltitudeEKF"))

WORKER = """
import json, sys, time
sys.meta_path = [f for f in sys.meta_path if "__editable__" not in getattr(f, "__name__",
                 type(f).__module__)]
sys.path.insert(0, sys.argv[1])
import numpy as np
import altfusion
assert altfusion.__file__.startswith(sys.argv[1]), altfusion.__file__
from altfusion.estimators.registry import ESTIMATOR_CLASSES
data = np.load(sys.argv[2])
names = json.loads(sys.argv[3])
core_class = ESTIMATOR_CLASSES[sys.argv[4]]
params = core_class.Params(**json.loads(sys.argv[5]))
rows = data["inputs"].tolist()
kinds = [int if n.endswith("_count") else bool if n.endswith(("_fix", "_valid")) else float
         for n in names]
rows = [[kind(v) for kind, v in zip(kinds, row)] for row in rows]
def run(step):
    core = core_class(params, step_size=float(sys.argv[7]))
    dt, clock = core.dt, core.clock
    start = time.process_time()
    for n, row in enumerate(rows):
        for name, value in zip(names, row):
            setattr(core, name, value)
        if step:
            core.do_step(clock.time(n), dt)
            core.take_notes()
    return time.process_time() - start, core
best = float("inf")
for _ in range(int(sys.argv[6])):
    stepped, core = run(True)
    best = min(best, (stepped - run(False)[0]) / len(rows))
print(json.dumps({"us": best * 1e6, "h_est": core.h_est}))
"""


def record_inputs(system: str, stop: float, folder: Path) -> tuple[Path, list[str], dict,
                                                                     float]:
    """The estimator's inputs after each base step of ``system`` (its component
    ``estimator``), its parameters and step."""
    from altfusion.cosim import Simulation
    from altfusion.systems import build_system

    spec = build_system(system)
    estimator = spec.component("estimator")
    links = {c.end.partition(".")[2]: c.start for c in spec.connections
             if c.end.startswith("estimator.")}
    names = sorted(links)
    from dataclasses import replace
    spec = replace(spec, record=tuple(sorted(set(links.values()))), metrics=(),
                   output_interval=estimator.step_size)
    fmus = {p.stem: p for p in MODELS.glob("*.fmu")}
    with Simulation(spec, fmus, "fmu") as simulation:
        results = simulation.run(stop_time=stop)
    inputs = np.column_stack([results[links[name]][1:] for name in names])
    path = folder / f"{system}.npz"
    np.savez(path, inputs=inputs)
    return path, names, dict(estimator.parameters), estimator.step_size


def cost(root: Path, data: Path, names: list[str], fmu: str, parameters: dict, repeat: int,
         step: float) -> dict:
    output = subprocess.run(
        [sys.executable, "-c", WORKER, str(root), str(data), json.dumps(names), fmu,
         json.dumps(parameters), str(repeat), str(step)],
        check=True, capture_output=True, text=True).stdout
    return json.loads(output)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", type=Path, help="root of the other version's checkout")
    parser.add_argument("--stop", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    roots = {"this": ROOT, **({"base": args.base.resolve()} if args.base else {})}
    with tempfile.TemporaryDirectory() as folder:
        for system, fmu in CASES:
            data, names, parameters, step = record_inputs(system, args.stop, Path(folder))
            for label, root in roots.items():
                result = cost(root, data, names, fmu, parameters, args.repeat, step)
                print(f"{fmu:14s} {system:22s} {label:5s} {result['us']:7.2f} µs per do_step "
                      f"(h_est at the end {result['h_est']!r})", flush=True)


if __name__ == "__main__":
    main()
