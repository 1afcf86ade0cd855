"""Instructions executed per base step of a co-simulation, counted by valgrind (callgrind).

    python benchmarks/instructions_per_step.py [SYSTEM] [--seconds 10] [--backend fmu|core]

Wall-clock speed on a shared VM moves by ±10 % from one minute to the next; the number of
instructions does not (it depends on the code and the inputs only, not on the machine's load),
so it is the figure that compares two versions of the code, one optimisation at a time. It
needs Debian's ``valgrind`` and runs ~50x slower than native.

Two runs of SYSTEM are counted, each after a 2 s warm-up run: one of ``--seconds`` simulated
seconds and one of 2 s; their difference divided by the base steps between them is the cost
of a base step with start-up, imports and instantiation removed. ``PYTHONHASHSEED`` is fixed
so that dictionary layouts repeat, OpenBLAS runs one thread (its idle worker threads' spinning
was counted too: ±1 % from run to run) and address-space randomization is off where
``setarch`` can turn it off (hashes of objects follow their addresses): three counts of the
same process then agreed to 3,000 of 782 million instructions (without: ±5 million).
"""

import argparse
import os
import platform
import re
import subprocess
import sys
from pathlib import Path

from altfusion.systems import DEFAULT_SYSTEM, build_system

MODELS = Path(__file__).resolve().parents[1] / "models"
WARM_UP = 2.0

RUN = """
import sys
from pathlib import Path
from altfusion.cosim import Simulation
from altfusion.systems import build_system
fmus = {{p.stem: p for p in Path({models!r}).glob("*.fmu")}}
with Simulation(build_system({system!r}), fmus, {backend!r}) as simulation:
    simulation.run(stop_time={warm_up!r})
    simulation.run(stop_time=float(sys.argv[1]))
"""


def _setarch_works() -> bool:
    """Whether ``setarch -R`` (no address-space randomization) runs here."""
    try:
        return subprocess.run(["setarch", platform.machine(), "-R", "true"],
                              capture_output=True).returncode == 0
    except OSError:
        return False


def callgrind_count(code: str, argument: str, env: dict[str, str] | None = None,
                    cwd: Path | None = None, python: str = sys.executable) -> int:
    """Instructions of a whole ``python -c code argument`` process, counted by callgrind with
    ``PYTHONHASHSEED`` fixed, OpenBLAS on one thread and address-space randomization off
    where ``setarch`` runs (``env`` added to the environment, run in ``cwd``; ``python``:
    the interpreter, this one by default)."""
    no_aslr = ["setarch", platform.machine(), "-R"] if _setarch_works() else []
    completed = subprocess.run(
        [*no_aslr, "valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
         python, "-c", code, argument],
        capture_output=True, text=True, check=True, cwd=cwd,
        env={**os.environ, "PYTHONHASHSEED": "0", "OPENBLAS_NUM_THREADS": "1",
             "OMP_NUM_THREADS": "1", **(env or {})})
    found = re.search(r"Collected : (\d+)", completed.stderr)
    if found is None:
        raise RuntimeError(f"no instruction count in valgrind's output:\n{completed.stderr}")
    return int(found.group(1))


def instructions(system: str, backend: str, seconds: float) -> int:
    """Instructions of a whole process that warms up and then simulates ``seconds``."""
    code = RUN.format(models=str(MODELS), system=system, backend=backend, warm_up=WARM_UP)
    return callgrind_count(code, repr(seconds))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("system", nargs="?", default=DEFAULT_SYSTEM)
    parser.add_argument("--seconds", type=float, default=10.0 + WARM_UP,
                        help="simulated seconds of the long run (default 12)")
    parser.add_argument("--backend", choices=("fmu", "core"), default="fmu")
    args = parser.parse_args()
    base_step = build_system(args.system).base_step
    long_run = instructions(args.system, args.backend, args.seconds)
    short_run = instructions(args.system, args.backend, WARM_UP)
    steps = round((args.seconds - WARM_UP) / base_step)
    print(f"{args.system} ({args.backend}): {(long_run - short_run) / steps:,.0f} instructions "
          f"per base step ({steps} base steps of {base_step} s counted)")


if __name__ == "__main__":
    main()
