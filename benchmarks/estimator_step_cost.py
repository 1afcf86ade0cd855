"""Cost of one estimator ``do_step``, µs or instructions, for two versions of the code in the
same run.

    python benchmarks/estimator_step_cost.py [--base /tmp/base] [--stop 60] [--repeat 5]
                                             [--estimators all|NAME,...] [--instructions]
                                             [--python INTERPRETER ...] [--sources]

The inputs an estimator sees in its system (:data:`CASES`; by default YangFusionKF in
``yang2020`` and AltitudeEKF in ``yang2020_altitude_ekf``, issue 28's two: 100 Hz steps, baro
and accelerometer at every step, GNSS at 10 Hz, radio altimeter at 5 Hz; ``--estimators
all``: every estimator) are recorded once, running the system's FMUs (``models/`` must be
built; any version will do: both versions step the same recorded inputs). Each version then
steps a fresh estimator core over them, in a process of its own that imports that version's
``altfusion`` (``--base``: the root of another checkout, e.g. ``git worktree add --detach
/tmp/base 6300b44``), and reports the best of ``--repeat`` runs: the CPU time
(``time.process_time``: the time the process waits for a core is left out) of a loop writing
the inputs and stepping (``do_step`` and ``take_notes``, as the FMU adapter calls them), less
that of the same loop writing the inputs only, over the steps. Timings on a shared machine
still move by ±10 %: compare versions within one run.

``--instructions``: instructions per step instead, counted by valgrind (callgrind, as
``instructions_per_step.py`` counts them: the same on a busy machine as on an idle one):
two processes step a fresh core over all the recorded steps and over the first fifth of
them, and the difference of their counts over the steps between is the cost of a step, the
inputs' writes included, start-up removed (~50x slower than native).

``--python``: step in these interpreters instead of this one (each needs numpy, scipy, fmpy,
pythonfmu and python-control importable; ``altfusion`` comes from the version's root): FMUs
run in their host's Python, 3.10 or later, and its version sets the estimators' speed.

Each version steps on its compiled modules where its build compiled them for the interpreter
(:mod:`altfusion.compiled`; a checkout without them, or another interpreter, runs its Python
sources). ``--sources``: also a row of this version on its Python sources
(``ALTFUSION_PURE_PYTHON`` set), labelled ``py``.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from itertools import product
from pathlib import Path

import numpy as np
from instructions_per_step import callgrind_count

from altfusion.compiled import PURE_PYTHON

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
CASES = {"YangFusionKF": "yang2020", "AltitudeEKF": "yang2020_altitude_ekf",
         "XuSHAEKF": "xu2016_hover15", "BaselineKF": "yang2020_baseline",
         "WhangGAEstimator": "whang2008", "BaoDriftEstimator": "bao2017",
         "HajiyevAdaptiveEstimator": "hajiyev"}
"""Each estimator and the system whose inputs it steps on (its component ``estimator``)."""
DEFAULT = ("YangFusionKF", "AltitudeEKF")

WORKER = """
import json, sys, time
job = json.loads(sys.argv[1])
sys.meta_path = [f for f in sys.meta_path if "__editable__" not in getattr(f, "__name__",
                 type(f).__module__)]
sys.path.insert(0, job["root"])
import numpy as np
import altfusion
assert altfusion.__file__.startswith(job["root"]), altfusion.__file__
from altfusion.estimators.registry import ESTIMATOR_CLASSES
names = job["names"]
core_class = ESTIMATOR_CLASSES[job["fmu"]]
params = core_class.Params(**job["parameters"])
rows = np.load(job["data"])["inputs"].tolist()[:job["limit"]]
kinds = [int if n.endswith("_count") else bool if n.endswith(("_fix", "_valid")) else float
         for n in names]
rows = [[kind(v) for kind, v in zip(kinds, row)] for row in rows]
def run(step):
    core = core_class(params, step_size=job["step"])
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
for _ in range(job["repeat"]):                 # repeat 0: stepped once, untimed (counted)
    stepped, core = run(True)
    best = min(best, (stepped - run(False)[0]) / len(rows))
if not job["repeat"]:
    core = run(True)[1]
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


def environment(label: str) -> dict[str, str]:
    """The environment of a worker for the row ``label`` (``py``: on the Python sources)."""
    return {PURE_PYTHON: "1" if label == "py" else ""}


def cost(job: dict, python: str, label: str) -> dict:
    """The worker's result for ``job`` in the interpreter ``python`` (its CPU time per step,
    its last height)."""
    output = subprocess.run([python, "-c", WORKER, json.dumps(job)], check=True,
                            capture_output=True, text=True,
                            env={**os.environ, **environment(label)}).stdout
    return json.loads(output)


def instructions(job: dict, steps: int, python: str, label: str) -> float:
    """Instructions per step of ``job``'s estimator in the interpreter ``python``: stepping
    all ``steps`` less stepping the first fifth of them, over the steps between."""
    few = steps // 5
    counts = [callgrind_count(WORKER, json.dumps({**job, "repeat": 0, "limit": limit}),
                              env=environment(label), python=python)
              for limit in (steps, few)]
    return (counts[0] - counts[1]) / (steps - few)


def python_version(python: str) -> str:
    """The version of the interpreter ``python`` (3.11.7...)."""
    return subprocess.run([python, "-c", "import platform; print(platform.python_version())"],
                          check=True, capture_output=True, text=True).stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", type=Path, help="root of the other version's checkout")
    parser.add_argument("--stop", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--estimators", default=",".join(DEFAULT),
                        help="'all' or estimator names, comma-separated (default: "
                             f"{','.join(DEFAULT)})")
    parser.add_argument("--instructions", action="store_true",
                        help="count instructions per step (valgrind) instead of timing")
    parser.add_argument("--python", action="append", default=None,
                        help="interpreter to step in (repeatable; default: this one)")
    parser.add_argument("--sources", action="store_true",
                        help="also step this version on its Python sources (row 'py')")
    args = parser.parse_args()
    pythons = {python_version(python): python for python in args.python or [sys.executable]}
    chosen = tuple(CASES) if args.estimators == "all" else tuple(args.estimators.split(","))
    unknown = [name for name in chosen if name not in CASES]
    if unknown:
        parser.error(f"unknown estimator(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    roots = {"this": ROOT, **({"py": ROOT} if args.sources else {}),
             **({"base": args.base.resolve()} if args.base else {})}
    with tempfile.TemporaryDirectory() as folder:
        for fmu in chosen:
            system = CASES[fmu]
            data, names, parameters, step = record_inputs(system, args.stop, Path(folder))
            steps = len(np.load(data)["inputs"])
            for (label, root), (version, python) in product(roots.items(), pythons.items()):
                job = {"root": str(root), "data": str(data), "names": names, "fmu": fmu,
                       "parameters": parameters, "repeat": args.repeat, "step": step,
                       "limit": steps}
                if args.instructions:
                    figure = (f"{instructions(job, steps, python, label):9,.0f} "
                              "instructions per do_step")
                else:
                    result = cost(job, python, label)
                    figure = (f"{result['us']:7.2f} µs per do_step (h_est at the end "
                              f"{result['h_est']!r})")
                print(f"{fmu:24s} {system:22s} {label:5s} Python {version:7s} {figure}",
                      flush=True)


if __name__ == "__main__":
    main()
